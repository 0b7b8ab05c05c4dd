// The command's flags against the parameter schema (issue 37): every flag that sets a key of the
// parameter file says so in its help ("... [fractal.iterations]"), and its help, limits, choices
// and default there are the schema's as `dqjulia schema` publishes them; a value outside the
// schema's limits is refused while the arguments are parsed, naming the key. The commands and
// their flags are read from each command's own --help, so a new flag or command is covered without
// changing this test, and a flag named after a key that does not go through the schema fails.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// CLI11's column for option descriptions.
constexpr std::size_t kDescriptionColumn = 30;

/// One option line of a --help: its names ("-n,--iterations"), the first line of its description.
struct HelpOption {
    std::string names;
    std::string description;
    std::string longName() const { return names.substr(names.rfind(',') + 1); }
};

class SchemaFlags : public dqj::test::ScratchFolder {
protected:
    dqj::test::CommandResult run(const std::string& arguments) {
        return dqj::test::runCommand(DQJ_CLI, arguments, dir_);
    }

    /// The schema's fields by key.
    std::map<std::string, json> schema() {
        const auto result = run("schema");
        EXPECT_EQ(result.exitCode, 0) << result.err;
        std::map<std::string, json> fields;
        const json document = json::parse(result.out);
        for (const json& field : document["fields"]) fields[field["key"].get<std::string>()] = field;
        return fields;
    }

    /// Every command ("render", "farm slurm", ...), from the help.
    std::vector<std::string> commands() {
        std::vector<std::string> result;
        for (const std::string& command : dqj::test::helpSection(run("--help").out, "Subcommands:")) {
            const std::vector<std::string> sub = dqj::test::helpSection(run(command + " --help").out, "Subcommands:");
            if (sub.empty()) result.push_back(command);
            for (const std::string& name : sub) result.push_back(command + " " + name);
        }
        return result;
    }

    /// The options of a help text. A description starts in CLI11's column, or on the next line
    /// when the names and type fill that column.
    static std::vector<HelpOption> options(const std::string& help) {
        std::vector<std::string> lines;
        std::istringstream text(help);
        for (std::string line; std::getline(text, line);) lines.push_back(line);
        std::vector<HelpOption> result;
        const std::string indent(kDescriptionColumn, ' ');
        for (std::size_t index = 0; index < lines.size(); ++index) {
            const std::string& line = lines[index];
            if (line.rfind("  -", 0) != 0) continue;
            HelpOption option;
            option.names = line.substr(2, line.find(' ', 2) - 2);
            const bool sameLine = line.size() > kDescriptionColumn && line[kDescriptionColumn - 1] == ' ' &&
                                  line[kDescriptionColumn] != ' ';
            const bool nextLine = index + 1 < lines.size() && lines[index + 1].rfind(indent, 0) == 0;
            if (sameLine && (line.find('[') != std::string::npos || !nextLine))
                option.description = line.substr(kDescriptionColumn);
            else if (nextLine)
                option.description = lines[index + 1].substr(kDescriptionColumn);
            result.push_back(option);
        }
        return result;
    }
};

/// "above 0, at most 1" or "1 to 100000" against the field's min, max and exclusivity.
void expectRange(const std::string& text, const json& field, const std::string& where) {
    ASSERT_TRUE(field.contains("min") && field.contains("max")) << where << ": the schema gives no range";
    const bool minExclusive = field.value("min_exclusive", false), maxExclusive = field.value("max_exclusive", false);
    std::string low, high;
    if (!minExclusive && !maxExclusive) {
        const std::size_t to = text.find(" to ");
        ASSERT_NE(to, std::string::npos) << where << ": '" << text << "'";
        low = text.substr(0, to);
        high = text.substr(to + 4);
    } else {
        const std::string lowWord = minExclusive ? "above " : "at least ";
        const std::string highWord = maxExclusive ? ", below " : ", at most ";
        ASSERT_EQ(text.rfind(lowWord, 0), 0u) << where << ": '" << text << "'";
        const std::size_t comma = text.find(highWord);
        ASSERT_NE(comma, std::string::npos) << where << ": '" << text << "'";
        low = text.substr(lowWord.size(), comma - lowWord.size());
        high = text.substr(comma + highWord.size());
    }
    EXPECT_EQ(std::strtod(low.c_str(), nullptr), field["min"].get<double>()) << where << ": '" << text << "'";
    EXPECT_EQ(std::strtod(high.c_str(), nullptr), field["max"].get<double>()) << where << ": '" << text << "'";
}

std::string choiceNames(const json& field) {
    std::string names;
    for (const json& choice : field["choices"])
        names += (names.empty() ? "" : ", ") + choice["name"].get<std::string>();
    return names;
}

/// The scalar default as the help shows it, or "" for none.
std::string defaultText(const json& field) {
    if (!field.contains("default")) return "";
    const json& value = field["default"];
    if (value.is_string()) return value.get<std::string>();
    if (value.is_boolean()) return value.get<bool>() ? "true" : "false";
    if (value.is_number()) return "number";
    if (value.is_array() && !value.empty() && value[0].is_string()) {
        std::string names;
        for (const json& name : value) names += (names.empty() ? "" : ",") + name.get<std::string>();
        return names;
    }
    return "";
}

/// A value outside the field's limits, as a flag's argument(s), or "" where there is none to give.
std::string outsideValue(const json& field) {
    const std::string type = field["type"];
    if (type == "choice" || type == "choice_set") return "no-such-name";
    if (!field.contains("max")) return "";
    const double max = field["max"].get<double>();
    const std::string number = max >= 1e100 ? std::string("-1e300") : std::to_string(max * 2 + 1);
    const int count = type == "vec3" || type == "color" ? 3 : type == "vec8" || type == "dual_quaternion" ? 8 : 1;
    if (type != "integer" && type != "number" && count == 1) return "";
    std::string values = type == "integer" ? std::to_string(static_cast<long long>(max) + 1) : number;
    for (int index = 1; index < count; ++index) values += " 0";
    return values;
}

TEST_F(SchemaFlags, EveryFlagOfAKeyHasTheSchemasHelpLimitsAndDefault) {
    const std::map<std::string, json> fields = schema();
    ASSERT_GT(fields.size(), 50u);
    const std::vector<std::string> all = commands();
    ASSERT_GE(all.size(), 12u);
    // Flags named after a key that are the command's own settings, not the key's.
    const std::set<std::string> ownSettings{
        "inspect --samples",  // samples per axis of the inside fraction
        "explore --samples",  // the contact sheet's tiles: their own default (1) and limit (8)
    };
    // The last part of every key a flag could set ("render.max_steps" -> "--max-steps").
    std::map<std::string, std::string> keyByFlag;
    for (const auto& [key, field] : fields) {
        const std::string type = field["type"];
        if (type == "object" || type == "list" || type == "animation" || key.find("[]") != std::string::npos) continue;
        std::string last = key.substr(key.rfind('.') + 1);
        for (char& ch : last)
            if (ch == '_') ch = '-';
        keyByFlag["--" + last] = key;
    }

    int keyed = 0;
    for (const std::string& command : all) {
        for (const HelpOption& option : options(run(command + " --help").out)) {
            const std::string where = command + " " + option.names;
            const std::string& text = option.description;
            const std::size_t open = text.rfind(" [");
            const bool hasKey = open != std::string::npos && text.back() == ']';
            if (!hasKey) {
                const auto named = keyByFlag.find(option.longName());
                EXPECT_TRUE(named == keyByFlag.end() || ownSettings.count(command + " " + option.longName()))
                    << where << " is named after " << named->second
                    << " but its help does not come from the schema (core/cli/schema_options.hpp): " << text;
                continue;
            }
            const std::string key = text.substr(open + 2, text.size() - open - 3);
            const auto found = fields.find(key);
            ASSERT_NE(found, fields.end()) << where << " names a key the schema does not have: " << key;
            const json& field = found->second;
            ++keyed;

            // "<help>[; <limits>][, default <value>] [<key>]"
            const std::string help = field["help"];
            ASSERT_EQ(text.rfind(help, 0), 0u)
                << where << ": the help is not the schema's\n  help:   " << text << "\n  schema: " << help;
            std::string rest = text.substr(help.size(), open - help.size());
            const std::string byDefault = defaultText(field);
            std::string shownDefault;
            if (const std::size_t at = rest.rfind("default "); at != std::string::npos) {
                shownDefault = rest.substr(at + 8);
                rest = rest.substr(0, at);
                if (rest.size() >= 2 && rest.substr(rest.size() - 2) == ", ") rest.resize(rest.size() - 2);
            }
            if (byDefault == "number")
                EXPECT_EQ(std::strtod(shownDefault.c_str(), nullptr), field["default"].get<double>()) << where;
            else
                EXPECT_EQ(shownDefault, byDefault) << where;
            if (rest.rfind("; ", 0) == 0) rest = rest.substr(2);

            const std::string type = field["type"];
            if (type == "integer" || type == "number") {
                expectRange(rest, field, where);
            } else if (type == "vec3" || type == "color" || type == "vec8" || type == "dual_quaternion") {
                ASSERT_EQ(rest.rfind("each ", 0), 0u) << where << ": '" << rest << "'";
                expectRange(rest.substr(5), field, where);
            } else if (type == "choice") {
                EXPECT_EQ(rest, "one of " + choiceNames(field)) << where;
            } else if (type == "choice_set") {
                EXPECT_EQ(rest, "comma-separated, of " + choiceNames(field)) << where;
            } else {
                EXPECT_EQ(rest, "") << where << ": limits for a key that has none";
            }

            // A value outside the schema's limits is refused by the argument parser, naming the key.
            const std::string outside = outsideValue(field);
            if (outside.empty()) continue;
            const auto refused = run(command + " " + option.longName() + " " + outside);
            EXPECT_EQ(refused.exitCode, 2) << where << " " << outside << ": " << refused.err;
            // "--iterations: fractal.iterations: must be ...", "--c: fractal.c[0]: must be ..."
            const std::string named =
                option.longName() + ": " + key + (outside.find(' ') != std::string::npos ? "[0]" : "");
            EXPECT_NE(refused.err.find(named + ": must be"), std::string::npos)
                << where << " " << outside << ": " << refused.err;
        }
    }
    EXPECT_GE(keyed, 40) << "flags that set schema keys";
}

}  // namespace
