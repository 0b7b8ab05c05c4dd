// Every message escaped (issue 35): a value with terminal escape sequences, given to each flag
// that takes text (names of files above all), never reaches the terminal raw, whoever writes the
// message: the command, its argument parser (CLI11's validators) or a library. The flags are
// read from each command's own --help, so a new flag or command is covered without changing
// this test.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "test_support.hpp"

namespace fs = std::filesystem;

namespace {

/// Escape sequences a terminal obeys: set the window title, red text, a carriage return that
/// overwrites the line, DEL, and CSI as a C1 control in UTF-8 (U+009B).
const std::string kHostile =
    "\x1b]0;owned\x07\x1b[31mred\rover\x7f\xc2\x9b"
    "2J";

/// The first control character in `text` that is not a newline or a tab, as "\\xNN at offset N", or "".
std::string rawControl(const std::string& text) {
    for (std::size_t index = 0; index < text.size(); ++index) {
        const auto byte = static_cast<unsigned char>(text[index]);
        const auto next = index + 1 < text.size() ? static_cast<unsigned char>(text[index + 1]) : 0;
        if ((byte < 0x20 && byte != '\n' && byte != '\t') || byte == 0x7f ||
            (byte == 0xc2 && next >= 0x80 && next <= 0x9f))
            return "byte " + std::to_string(byte) + " at offset " + std::to_string(index);
    }
    return "";
}

/// An option of a command's --help that takes text: its longest name (or a positional's name).
struct TextOption {
    std::string name;
    bool positional = false;
};

/// The options and positionals of a command's --help whose value is text (CLI11 writes TEXT, TEXT:FILE, ...).
std::vector<TextOption> textOptions(const std::string& help) {
    std::vector<TextOption> options;
    std::istringstream lines(help);
    std::string line;
    while (std::getline(lines, line)) {
        if (line.size() < 3 || line[0] != ' ' || line[1] != ' ' || line[2] == ' ') continue;
        std::istringstream words(line.substr(2));
        std::string names, type;
        words >> names >> type;
        if (type.rfind("TEXT", 0) != 0) continue;
        const std::string longest = names.substr(names.rfind(',') + 1);  // "-o,--output" -> "--output"
        options.push_back({longest, longest[0] != '-'});
    }
    return options;
}

class Messages : public dqj::test::ScratchFolder {
protected:
    dqj::test::CommandResult run(const std::vector<std::string>& arguments) {
        std::string line;
        for (const std::string& argument : arguments) {
            std::string quoted = "'";
            for (const char ch : argument) quoted += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
            line += quoted + "' ";
        }
        return dqj::test::runCommand(DQJ_CLI, line, dir_);
    }
};

TEST_F(Messages, EveryTextFlagOfEveryCommandIsEscapedInEveryMessage) {
    const std::string dir = dir_.string();
    ASSERT_EQ(run({"render", "-q", "-W", "8", "-H", "8", "-o", dir + "/pic.png"}).exitCode, 0);
    ASSERT_EQ(run({"bake", "-q", "-r", "16", "--tiles", "2x1x1", "-o", dir + "/a.vdb"}).exitCode, 0);
    // Arguments that make each command work but for the flag under test (long names): the flag's
    // value replaces the one given here, or is added. A command missing here runs with the flag alone.
    const std::map<std::string, std::vector<std::string>> working{
        {"render", {"--width", "8", "--height", "8", "--output", dir + "/render.png", "--force"}},
        {"eval", {}},
        {"inspect", {"--samples", "2"}},
        {"povray", {"--output", dir + "/scene.pov", "--force"}},
        {"explore",
         {"--count", "1", "--tile-width", "16", "--tile-height", "16", "--output", dir + "/explore", "--force"}},
        {"sheet", {"--tile", dir + "/pic.png", "--output", dir + "/sheet.png", "--force"}},
        {"bake", {"--resolution", "8", "--output", dir + "/bake.vdb", "--force"}},
        {"mesh", {"--resolution", "8", "--output", dir + "/mesh.ply", "--force"}},
        {"merge", {"--tiles", "2x1x1", "--output", dir + "/a.vdb", "--force"}},
        {"farm slurm", {"--output", dir + "/job.vdb", "--force"}},
        {"farm openjd", {"--output", dir + "/job.vdb", "--force"}},
        {"schema", {}},
    };
    // The commands, from the help (a command with subcommands of its own is its subcommands).
    std::vector<std::string> commands;
    const std::vector<std::string> top = dqj::test::helpSection(run({"--help"}).out, "Subcommands:");
    ASSERT_GE(top.size(), 10u);
    for (const std::string& command : top) {
        const std::vector<std::string> sub = dqj::test::helpSection(run({command, "--help"}).out, "Subcommands:");
        if (sub.empty()) commands.push_back(command);
        for (const std::string& name : sub) commands.push_back(command + " " + name);
    }

    int flags = 0;
    std::vector<std::string> notQuoted;
    for (const std::string& command : commands) {
        std::vector<std::string> words;
        std::istringstream split(command);
        for (std::string word; split >> word;) words.push_back(word);
        std::vector<std::string> help = words;
        help.emplace_back("--help");
        const auto options = textOptions(run(help).out);
        for (const TextOption& option : options) {
            ++flags;
            // A name with the escape sequences in a folder that exists, ending as each command's files do.
            // In a folder of its own, so that no file one run writes is read by another.
            const std::string folder = dir + "/" + std::to_string(flags);
            fs::create_directories(folder);
            for (const char* extension : {".png", ".vdb", ".json"}) {
                const std::string value = folder + "/" + kHostile + extension;
                std::vector<std::string> arguments = words;
                const auto base = working.count(command) ? working.at(command) : std::vector<std::string>{};
                for (std::size_t index = 0; index < base.size(); ++index) {
                    if (!option.positional && base[index] == option.name) {
                        ++index;  // the flag's own value, replaced below
                        continue;
                    }
                    arguments.push_back(base[index]);
                }
                if (!option.positional) arguments.push_back(option.name);
                arguments.push_back(value);
                const auto result = run(arguments);
                SCOPED_TRACE(command + " " + option.name + " (" + extension + "): exit " +
                             std::to_string(result.exitCode));
                EXPECT_LE(result.exitCode, 2) << result.err;  // no crash
                EXPECT_EQ(rawControl(result.err), "") << result.err;
                EXPECT_EQ(rawControl(result.out), "") << result.out;
                if (std::string(extension) == ".png" && result.exitCode != 0 &&
                    (result.err + result.out).find("\\x1b]0;owned\\x07\\x1b[31mred\\x0dover\\x7f\\xc2\\x9b2J") ==
                        std::string::npos)
                    notQuoted.push_back(command + " " + option.name);
            }
        }
    }
    EXPECT_GE(flags, 30) << "the flags were not found in the help";
    // Every flag whose value names a file is quoted back (escaped) by the message that refuses it.
    for (const std::string& name : notQuoted) {
        const bool pathFlag =
            name.find("--output") != std::string::npos || name.find("--params") != std::string::npos ||
            name.find("--save-params") != std::string::npos || name.find("--voxels") != std::string::npos ||
            name.find("--script") != std::string::npos || name.find("--template") != std::string::npos ||
            name.find("sheet --tile") == 0;
        EXPECT_FALSE(pathFlag) << name << ": its value appears in no message";
    }
}

}  // namespace
