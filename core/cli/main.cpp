// dqjulia: render, evaluate and inspect dual-quaternion Julia fractals from the command line.
#include <iostream>
#include <map>
#include <string>
#include <vector>

#ifdef _WIN32
#include <windows.h>
#endif

#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/dqjulia.h"

namespace {

int run(int argc, char** argv) {
    using namespace dqj::cli;
    // Every message escaped from here on, the argument parser's (a missing --params file) included.
    const MessageEscaping escaping;
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

}  // namespace

#ifdef _WIN32
// Windows hands narrow arguments in the ANSI code page, which cannot hold every file name: the
// command takes its UTF-16 arguments (wmain, linked with -municode) as UTF-8, the toolkit's file
// names, and writes UTF-8 to the console.
int wmain(int argc, wchar_t** wideArgv) {
    std::vector<std::string> arguments;
    for (int index = 0; index < argc; ++index) {
        const int bytes = ::WideCharToMultiByte(CP_UTF8, 0, wideArgv[index], -1, nullptr, 0, nullptr, nullptr);
        std::string argument(bytes > 0 ? std::size_t(bytes) : 1, '\0');
        ::WideCharToMultiByte(CP_UTF8, 0, wideArgv[index], -1, argument.data(), bytes, nullptr, nullptr);
        argument.resize(argument.size() - 1);  // the terminating NUL
        arguments.push_back(std::move(argument));
    }
    std::vector<char*> argv;
    for (std::string& argument : arguments) argv.push_back(argument.data());
    argv.push_back(nullptr);
    ::SetConsoleOutputCP(CP_UTF8);
    return run(argc, argv.data());
}
#else
int main(int argc, char** argv) { return run(argc, argv); }
#endif
