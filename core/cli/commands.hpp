// The subcommands of the dqjulia command. Each registers its options on the app and returns
// the function that runs it (called after parsing).
#pragma once

#include <functional>

#include <CLI/CLI.hpp>

namespace dqj::cli {

using Runner = std::function<int()>;

Runner addRenderCommand(CLI::App& app);
Runner addEvalCommand(CLI::App& app);
Runner addInspectCommand(CLI::App& app);
Runner addBakeCommand(CLI::App& app);
Runner addMeshCommand(CLI::App& app);
Runner addPovrayCommand(CLI::App& app);
Runner addExploreCommand(CLI::App& app);
Runner addSheetCommand(CLI::App& app);
Runner addSchemaCommand(CLI::App& app);
Runner addMergeCommand(CLI::App& app);
Runner addFarmCommand(CLI::App& app);

}  // namespace dqj::cli
