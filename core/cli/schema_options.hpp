// Command-line options for keys of the parameter file, described by the schema (dqjulia/schema.hpp):
// a flag that sets a key takes its help, limits, choices and default from the key's field, and its
// values are checked by the parameter file's own checks (param_check.hpp) while the arguments are
// parsed; a choice's name becomes its enum value through schema::choiceIndex, as in the file's
// reader. The one place the command describes a key: nothing here lists choices or ranges itself.
// Costs one reading of the schema document (for the defaults) the first time an option is added.
#pragma once

#include <string>
#include <string_view>

#include <CLI/CLI.hpp>

#include "dqjulia/schema.hpp"

namespace dqj::cli {

/// The help of a flag that sets `field`'s key, one line: the field's help, its limits and default,
/// and the key, e.g. "N, the iteration count (the paper uses 6 to 15); 1 to 100000, default 15
/// [fractal.iterations]"; `note` (what the flag adds to the key) follows on a line of its own.
/// tests/cli/schema_flags_test.cpp reads this form back against `dqjulia schema`.
std::string schemaHelp(const schema::Field& field, std::string_view note = {});

/// The limits of a field as its help states them: "1 to 100000", "above 0, at most 1", "each -100 to
/// 100", "one of paper, paper-coupled, dual", "comma-separated, of surface, ..."; "" for none.
std::string limitsText(const schema::Field& field);

/// Describes, checks and sizes an option added for the schema key `key` (schemaOption does it).
CLI::Option* describeSchemaOption(CLI::Option* option, std::string_view key, std::string_view note);

/// Adds option `names` (e.g. "-n,--iterations") that sets the schema key `key` into `value`: its
/// help from schemaHelp, each value checked against the field (numbers, components of vectors,
/// choice names, comma-separated choice sets), vectors taking their 3 or 8 numbers.
template <typename T>
CLI::Option* schemaOption(CLI::App& command, const std::string& names, std::string_view key, T& value,
                          std::string_view note = {}) {
    return describeSchemaOption(command.add_option(names, value), key, note);
}

/// Adds flag `names` that turns the boolean key `key` off (--no-colors for bake.mesh_colors).
CLI::Option* schemaOffFlag(CLI::App& command, const std::string& names, std::string_view key, bool& value);

/// The enum value of a choice name that the option's check accepted:
/// schemaChoice<Coloring>("material.coloring", "trap") = Coloring::Trap. Throws ParamError for a
/// name the field does not have.
int schemaChoiceIndex(std::string_view key, std::string_view name);
template <typename Enum>
Enum schemaChoice(std::string_view key, std::string_view name) {
    return static_cast<Enum>(schemaChoiceIndex(key, name));
}

}  // namespace dqj::cli
