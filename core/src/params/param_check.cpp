// param_check.cpp - see param_check.hpp.
#include "params/param_check.hpp"

#include <cmath>
#include <cstdint>

#include "dqjulia/param_file.hpp"
#include "files/message_text.hpp"

namespace dqj::detail {

namespace {

using json::describe;
using json::formatNumber;
using json::Json;
using schema::Field;
using schema::Type;

[[noreturn]] void fail(const std::string& key, const std::string& prefix, const std::string& message) {
    throw ParamError(key, prefix + (key.empty() ? "" : key + ": ") + message);
}

}  // namespace

void checkNumber(const Field& field, const Json& value, const std::string& key, const std::string& prefix) {
    if (value.is_null()) fail(key, prefix, "must be a finite number");
    if (!value.is_number()) fail(key, prefix, "must be a number, got " + describe(value));
    const double x = value.get<double>();
    if (!std::isfinite(x)) fail(key, prefix, "must be a finite number");
    if (field.type == Type::Integer) {
        if (std::nearbyint(x) != x) fail(key, prefix, "must be a whole number, got " + describe(value));
        if (x < field.min || x > field.max)
            fail(key, prefix,
                 "must be a whole number from " + std::to_string(std::int64_t(field.min)) + " to " +
                     std::to_string(std::int64_t(field.max)) + ", got " + formatNumber(x));
        return;
    }
    if (x < field.min || x > field.max || (field.minExclusive && x == field.min) ||
        (field.maxExclusive && x == field.max))
        fail(key, prefix,
             "must be " + std::string(field.minExclusive ? "greater than " : "at least ") + formatNumber(field.min) +
                 (field.maxExclusive ? " and less than " : " and at most ") + formatNumber(field.max) + ", got " +
                 formatNumber(x));
}

namespace {

std::string choiceList(const Field& field) {
    std::string allowed;
    for (const schema::Choice& choice : field.choices)
        allowed += (allowed.empty() ? "" : ", ") + std::string(choice.name);
    return allowed;
}

}  // namespace

void checkVector(const Field& field, const Json& value, const std::string& key, const std::string& prefix,
                 std::size_t size) {
    if (!value.is_array() || value.size() != size)
        fail(key, prefix, "must be an array of " + std::to_string(size) + " numbers, got " + describe(value));
    for (std::size_t index = 0; index < size; ++index)
        checkNumber(field, value[index], key + "[" + std::to_string(index) + "]", prefix);
}

void checkChoice(const Field& field, const Json& value, const std::string& key, const std::string& prefix) {
    if (value.is_string())
        for (const schema::Choice& choice : field.choices)
            if (value.get<std::string>() == choice.name) return;
    std::string got = describe(value);
    if (value.is_string()) {  // appended, not "\"" + ...: GCC 12's -Wrestrict misreads that (a false warning)
        got = "\"";
        got += inputExcerpt(value.get_ref<const std::string&>());
        got += '"';
    }
    fail(key, prefix, "must be one of " + choiceList(field) + ", got " + got);
}

namespace {

void checkCount(const Field& field, const Json& value, const std::string& key, const std::string& prefix,
                const std::string& what) {
    if (!value.is_array() || double(value.size()) < field.min || double(value.size()) > field.max)
        fail(key, prefix,
             "must be an array of " +
                 (field.min > 0 ? formatNumber(field.min) + " to " + formatNumber(field.max) + " " : std::string()) +
                 what + ", got " + describe(value));
}



void walk(const Json& node, const std::string& key) {
    const Field* field = key.empty() ? nullptr : schema::find(key);
    if (field) checkValue(*field, node, key, "");
    if (node.is_object()) {
        if (field && field->type == Type::Animation) return;  // its keys are parameter keys, checked by the reader
        for (const auto& item : node.items()) walk(item.value(), key.empty() ? item.key() : key + "." + item.key());
    } else if (node.is_array() && field && (field->type == Type::List || field->type == Type::ColorList)) {
        for (std::size_t index = 0; index < node.size(); ++index)
            walk(node[index], key + "[" + std::to_string(index) + "]");
    }
}

}  // namespace

void checkValue(const Field& field, const Json& value, const std::string& key, const std::string& prefix) {
    switch (field.type) {
        case Type::Boolean:
            if (!value.is_boolean()) fail(key, prefix, "must be true or false, got " + describe(value));
            return;
        case Type::Integer:
        case Type::Number: checkNumber(field, value, key, prefix); return;
        case Type::String:
            if (!value.is_string()) fail(key, prefix, "must be a string, got " + describe(value));
            return;
        case Type::Choice: checkChoice(field, value, key, prefix); return;
        case Type::ChoiceSet:
            checkCount(field, value, key, prefix, "grid names (" + choiceList(field) + ")");
            for (std::size_t index = 0; index < value.size(); ++index) {
                checkChoice(field, value[index], key + "[" + std::to_string(index) + "]", prefix);
                for (std::size_t before = 0; before < index; ++before)
                    if (value[before] == value[index]) fail(key, prefix, "names " + value[index].dump() + " twice");
            }
            return;
        case Type::Vec3:
        case Type::Color: checkVector(field, value, key, prefix, 3); return;
        case Type::Vec8:
        case Type::DualQuat: checkVector(field, value, key, prefix, 8); return;
        case Type::List: checkCount(field, value, key, prefix, "objects {...}"); return;
        case Type::ColorList: checkCount(field, value, key, prefix, "colours [r, g, b]"); return;
        case Type::Axes:  // names (read by the slice's parser) or three 8-D vectors
            if (value.is_array() && value.size() == 3)
                for (std::size_t axis = 0; axis < 3; ++axis)
                    checkVector(field, value[axis], key + "[" + std::to_string(axis) + "]", prefix, 8);
            return;
        case Type::AxisPair:  // two axis names, parsed by the reader
            if (!value.is_string()) fail(key, prefix, "must be a string, got " + describe(value));
            return;
        case Type::Object:
        case Type::Animation: return;
    }
}

void checkDocument(const Json& document) { walk(document, ""); }

}  // namespace dqj::detail
