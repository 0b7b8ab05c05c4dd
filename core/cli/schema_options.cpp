// Options for schema keys: see schema_options.hpp.
#include "schema_options.hpp"

#include <cstdint>
#include <cstdlib>

#include "dqjulia/param_file.hpp"
#include "params/json_text.hpp"
#include "params/param_check.hpp"

namespace dqj::cli {
namespace {

using json::formatNumber;
using json::Json;
using schema::Field;
using schema::Type;

/// The default of a scalar key as the schema document publishes it ("15", "paper", "surface,density"), or "".
std::string defaultText(std::string_view key) {
    static const Json document = Json::parse(schema::schemaJson());
    for (const Json& entry : document["fields"]) {
        if (entry["key"].get<std::string>() != key || !entry.contains("default")) continue;
        const Json& value = entry["default"];
        if (value.is_string()) return value.get<std::string>();
        if (value.is_number_integer()) return value.dump();
        if (value.is_number()) return formatNumber(value.get<double>());
        if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
        if (value.is_array() && !value.empty() && value[0].is_string()) {
            std::string names;
            for (const Json& name : value) names += (names.empty() ? "" : ",") + name.get<std::string>();
            return names;
        }
        return "";
    }
    return "";
}

std::string choiceNames(const Field& field) {
    std::string names;
    for (const schema::Choice& choice : field.choices) names += (names.empty() ? "" : ", ") + std::string(choice.name);
    return names;
}

/// A number's range: "1 to 100000", "above 0, at most 1", "above 0, below 170".
std::string rangeText(const Field& field) {
    if (!field.minExclusive && !field.maxExclusive) {
        if (field.type == Type::Integer)
            return std::to_string(std::int64_t(field.min)) + " to " + std::to_string(std::int64_t(field.max));
        return formatNumber(field.min) + " to " + formatNumber(field.max);
    }
    return (field.minExclusive ? "above " : "at least ") + formatNumber(field.min) +
           (field.maxExclusive ? ", below " : ", at most ") + formatNumber(field.max);
}

/// Runs one of param_check.hpp's checks; its ParamError becomes the validator's message.
template <typename Check>
std::string failureOf(const Check& check) {
    try {
        check();
    } catch (const ParamError& error) {
        return error.what();
    }
    return "";
}

/// A number, or a vector's component (`key` "camera.position[0]"), within the field's range.
CLI::Validator numberCheck(const Field& field, const std::string& key) {
    return CLI::Validator(
        [&field, key](std::string& text) -> std::string {
            char* end = nullptr;
            const double value = std::strtod(text.c_str(), &end);
            if (text.empty() || end != text.c_str() + text.size()) return "";  // the option's conversion says so
            return failureOf([&] { detail::checkNumber(field, Json(value), key, ""); });
        },
        "");
}

/// Each of a vector's `size` components, checked under its own key as the file's reader does.
void checkComponents(CLI::Option* option, const Field& field, int size) {
    option->expected(size);
    for (int index = 0; index < size; ++index)
        option->check(
            numberCheck(field, std::string(field.key) + "[" + std::to_string(index) + "]").application_index(index));
}

/// A choice's name; for a choice set, comma-separated names.
CLI::Validator choiceCheck(const Field& field) {
    return CLI::Validator(
        [&field](std::string& text) -> std::string {
            if (field.type != Type::ChoiceSet)
                return failureOf([&] { detail::checkChoice(field, Json(text), std::string(field.key), ""); });
            for (std::size_t start = 0; start <= text.size();) {
                const std::size_t comma = std::min(text.find(',', start), text.size());
                const std::string name = text.substr(start, comma - start);
                std::string failure =
                    failureOf([&] { detail::checkChoice(field, Json(name), std::string(field.key), ""); });
                if (!failure.empty()) return failure;
                start = comma + 1;
            }
            return "";
        },
        "");
}

}  // namespace

std::string limitsText(const Field& field) {
    switch (field.type) {
        case Type::Integer:
        case Type::Number: return rangeText(field);
        case Type::Vec3:
        case Type::Color:
        case Type::Vec8:
        case Type::DualQuat: return "each " + rangeText(field);
        case Type::Choice: return "one of " + choiceNames(field);
        case Type::ChoiceSet: return "comma-separated, of " + choiceNames(field);
        default: return "";
    }
}

std::string schemaHelp(const Field& field, std::string_view note) {
    std::string help(field.help);
    std::string limits = limitsText(field);
    if (const std::string byDefault = defaultText(field.key); !byDefault.empty())
        limits += (limits.empty() ? "default " : ", default ") + byDefault;
    if (!limits.empty()) help += "; " + limits;
    help += " [" + std::string(field.key) + "]";
    if (!note.empty()) help += "\n" + std::string(note);
    return help;
}

CLI::Option* describeSchemaOption(CLI::Option* option, std::string_view key, std::string_view note) {
    const Field& field = schema::field(key);
    option->description(schemaHelp(field, note));
    switch (field.type) {
        case Type::Integer:
        case Type::Number: option->check(numberCheck(field, std::string(field.key))); break;
        case Type::Vec3:
        case Type::Color: checkComponents(option, field, 3); break;
        case Type::Vec8:
        case Type::DualQuat: checkComponents(option, field, 8); break;
        case Type::Choice:
        case Type::ChoiceSet: option->check(choiceCheck(field)); break;
        default: break;  // strings, slice axes and rotations: read by the command's own parsers
    }
    return option;
}

CLI::Option* schemaOffFlag(CLI::App& command, const std::string& names, std::string_view key, bool& value) {
    return command.add_flag(names, value, schemaHelp(schema::field(key), "This flag turns it off"));
}

int schemaChoiceIndex(std::string_view key, std::string_view name) {
    const Field& field = schema::field(key);
    detail::checkChoice(field, Json(std::string(name)), std::string(key), "");
    return *schema::choiceIndex(field, name);
}

}  // namespace dqj::cli
