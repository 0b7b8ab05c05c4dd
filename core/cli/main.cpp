// dqjulia: render, evaluate and inspect dual-quaternion Julia fractals from the command line.
#include <iostream>
#include <map>

#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/dqjulia.h"

int main(int argc, char** argv) {
    using namespace dqj::cli;
    CLI::App app{
        "dqjulia: dual-quaternion Julia fractals (zeta <- zeta^2 + c in 8-D, sliced to 3-D).\n"
        "Parameters come from a JSON file (--params) and flags, which override the file.",
        "dqjulia"};
    app.set_version_flag("--version", std::string("dqjulia ") + dqj_version_string());
    app.require_subcommand(1);
    std::map<CLI::App*, Runner> runners;
    for (auto add :
         {addRenderCommand, addEvalCommand, addInspectCommand, addPovrayCommand, addExploreCommand, addSheetCommand,
          addBakeCommand, addMeshCommand, addMergeCommand, addFarmCommand, addSchemaCommand}) {
        const std::size_t before = app.get_subcommands({}).size();
        Runner runner = add(app);
        runners[app.get_subcommands({}).at(before)] = std::move(runner);
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& help) {
        return app.exit(help);
    } catch (const CLI::CallForAllHelp& help) {
        return app.exit(help);
    } catch (const CLI::CallForVersion& version) {
        return app.exit(version);
    } catch (const CLI::ParseError& error) {
        app.exit(error);  // prints the message and a hint to use --help
        return kBadInput;
    }
    installInterruptHandlers();
    for (const auto& [command, runner] : runners)
        if (command->parsed()) return runner();
    return kBadInput;
}
