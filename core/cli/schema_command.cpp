// dqjulia schema: the parameter file's schema (every key's type, label, help, default and
// range), the document the Blender add-on builds its controls from.
#include <iostream>

#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/schema.hpp"

namespace dqj::cli {

Runner addSchemaCommand(CLI::App& app) {
    app.add_subcommand("schema",
                       "Print the parameter file's schema as JSON: every key with its type, label, help,\n"
                       "default, range and choices (docs: Parameter file)");
    return [] {
        return reportErrors("schema", [] {
            std::cout << schema::schemaJson() << std::flush;
            return std::cout ? kSuccess : kFailure;
        });
    };
}

}  // namespace dqj::cli
