// dqjulia: render, evaluate and inspect dual-quaternion Julia fractals from the command line.
#include <cstdio>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "commands.hpp"
#include "common.hpp"
#include "dqjulia/dqjulia.h"
#include "files/message_text.hpp"
#include "platform/platform.hpp"

namespace {

/// The argument parser's message `message` as dqjulia shows it: printable (newlines kept), and each argument
/// longer than an excerpt that it quotes (whole, or its value after "--flag=") shown as
/// inputExcerpt() shows it, with its length; the parser quotes what it was given whole.
std::string parserMessage(const std::string& message, int argc, char** argv) {
    std::vector<std::string> quoted;
    for (int index = 1; index < argc; ++index) {
        const std::string argument = argv[index];
        const std::size_t equals = argument.find('=');
        for (const std::string& part :
             {argument, equals == std::string::npos ? std::string() : argument.substr(equals + 1)})
            if (dqj::inputExcerpt(part) != dqj::printableText(part)) quoted.push_back(part);
    }
    std::string shown;
    for (std::size_t at = 0; at < message.size();) {
        std::size_t next = message.size();
        const std::string* found = nullptr;
        for (const std::string& part : quoted) {  // the earliest, and of those the longest
            const std::size_t position = message.find(part, at);
            if (position < next || (position == next && found && part.size() > found->size())) {
                next = position;
                found = &part;
            }
        }
        shown += dqj::printableText(std::string_view(message).substr(at, next - at));
        if (!found) break;
        shown += dqj::inputExcerpt(*found);
        at = next + found->size();
    }
    return shown;
}

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
        // CLI11's message and hint to use --help, as app.exit(error) prints them, bounded.
        std::cerr << parserMessage(CLI::FailureMessage::simple(&app, error), argc, argv);
        return kBadInput;
    }
    installInterruptHandlers();
    for (const auto& [command, runner] : runners)
        if (command->parsed()) return runner();
    return kBadInput;
}

/// run(), with what escapes it (the argument parser running out of memory, say) reported as a
/// failure: an exception leaving main would end the process in std::terminate (exit 134).
int runReported(int argc, char** argv) {
    try {
        return run(argc, argv);
    } catch (const std::bad_alloc&) {
        std::fputs(
            "dqjulia: out of memory: this process may not use enough memory to start the work (see ulimit -v "
            "and the container's memory limit)\n",
            stderr);
    } catch (const std::exception& error) {
        try {
            std::fprintf(stderr, "dqjulia: %s\n", dqj::printableText(error.what()).c_str());
        } catch (const std::bad_alloc&) {
            std::fputs("dqjulia: out of memory\n", stderr);
        }
    }
    return dqj::cli::kFailure;
}

}  // namespace

// why: the program's entry point is the system's choice. Windows hands narrow arguments in the ANSI
// code page, which cannot hold every file name, so there the command starts at wmain (linked with
// -municode) and takes its UTF-16 arguments as UTF-8, the toolkit's file names
// (platform::utf8Arguments, which also has the console show UTF-8).
#ifdef _WIN32
int wmain(int argc, wchar_t** wideArgv) {
    std::vector<std::string> arguments = dqj::platform::utf8Arguments(argc, wideArgv);
    std::vector<char*> argv;
    for (std::string& argument : arguments) argv.push_back(argument.data());
    argv.push_back(nullptr);
    return runReported(argc, argv.data());
}
#else
int main(int argc, char** argv) { return runReported(argc, argv); }
#endif
