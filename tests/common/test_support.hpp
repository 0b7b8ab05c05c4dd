// test_support.hpp - helpers the GoogleTest suites share: a scratch folder per test and the
// names of the files in it, a small tmpfs (a disk that fills up), reading a file whole, running
// a command and capturing its output, starting a program in the background (for the interrupt
// tests), and random numbers that are the same on every platform.
#pragma once
#include <fcntl.h>
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/mount.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

extern char** environ;

namespace dqj::test {

/// "<temp>/<prefix>_<pid>_<test name>", emptied and created. The pid keeps parallel ctest
/// processes apart; a parameterised test's "Name/Param" becomes "Name_Param", one folder, so
/// removing it leaves nothing behind.
inline std::filesystem::path freshTestFolder(const std::string& prefix) {
    std::string name = ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::replace(name.begin(), name.end(), '/', '_');
    const std::filesystem::path folder =
        std::filesystem::temp_directory_path() / (prefix + "_" + std::to_string(::getpid()) + "_" + name);
    std::filesystem::remove_all(folder);
    std::filesystem::create_directories(folder);
    return folder;
}

/// A small tmpfs of `size` (e.g. "64k") mounted at `path` (created) while the object lives: a
/// disk that fills up. mounted() is false where mounting is not allowed (not root): skip then.
class Tmpfs {
public:
    Tmpfs(const std::filesystem::path& path, const std::string& size) : path_(path) {
        std::filesystem::create_directories(path_);
        mounted_ = ::mount("tmpfs", path_.c_str(), "tmpfs", 0, ("size=" + size).c_str()) == 0;
    }
    ~Tmpfs() {
        if (mounted_) ::umount(path_.c_str());
    }
    Tmpfs(const Tmpfs&) = delete;
    Tmpfs& operator=(const Tmpfs&) = delete;
    bool mounted() const { return mounted_; }
    const std::filesystem::path& path() const { return path_; }

private:
    std::filesystem::path path_;
    bool mounted_ = false;
};

/// The whole file as bytes; "" if it cannot be read.
inline std::string readFile(const std::filesystem::path& path) {
    std::ifstream file(path, std::ios::binary);
    std::ostringstream text;
    text << file.rdbuf();
    return text.str();
}

/// What a command did: its exit code (-1 if it did not exit normally) and its output.
struct CommandResult {
    int exitCode = -1;
    std::string out;
    std::string err;
};

/// Runs `program arguments` through the shell (so arguments are quoted as on a command line),
/// `input` on stdin. Its stdin, stdout and stderr go through hidden files in `scratch`, removed
/// afterwards, so tests that list the folder see only what the command wrote.
inline CommandResult runCommand(const std::string& program, const std::string& arguments,
                                const std::filesystem::path& scratch, const std::string& input = "") {
    const std::filesystem::path in = scratch / ".stdin", out = scratch / ".stdout", err = scratch / ".stderr";
    std::ofstream(in) << input;
    const std::string command = "'" + program + "' " + arguments + " < '" + in.string() + "' > '" + out.string() +
                                "' 2> '" + err.string() + "'";
    const int status = std::system(command.c_str());
    CommandResult result;
    result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    result.out = readFile(out);
    result.err = readFile(err);
    for (const std::filesystem::path& file : {in, out, err}) std::filesystem::remove(file);
    return result;
}

/// Starts `program` with `arguments`, its stderr into `errPath`; returns its pid, or -1.
inline pid_t spawnProgram(const std::string& program, const std::vector<std::string>& arguments,
                          const std::filesystem::path& errPath) {
    std::vector<std::string> all{program};
    all.insert(all.end(), arguments.begin(), arguments.end());
    std::vector<char*> argv;
    for (std::string& argument : all) argv.push_back(argument.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 2, errPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    pid_t pid = -1;
    const int status = posix_spawn(&pid, program.c_str(), &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    return status == 0 ? pid : -1;
}

/// The value of "key N" in a command's --stats output (the first number after the key).
inline double statValue(const std::string& text, const std::string& key) {
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line))
        if (line.rfind(key + " ", 0) == 0) return std::stod(line.substr(key.size() + 1));
    ADD_FAILURE() << "no " << key << " in:\n" << text;
    return -1.0;
}

/// The names a command's --help lists in a section (e.g. "Subcommands:"), one per entry line ("  name  text").
inline std::vector<std::string> helpSection(const std::string& help, const std::string& section) {
    std::vector<std::string> names;
    std::istringstream lines(help);
    bool inside = false;
    for (std::string line; std::getline(lines, line);) {
        if (line.rfind(section, 0) == 0) {
            inside = true;
            continue;
        }
        if (inside && (line.empty() || line[0] != ' ')) inside = false;
        if (inside && line.size() > 2 && line[2] != ' ') names.push_back(line.substr(2, line.find(' ', 2) - 2));
    }
    return names;
}

/// The names of the files in a folder, sorted.
inline std::vector<std::string> fileNames(const std::filesystem::path& folder) {
    std::vector<std::string> names;
    for (const auto& entry : std::filesystem::directory_iterator(folder))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

/// The fixture of a test that works in a folder of its own: "<temp>/dqjulia_<suite>_<pid>_<test>"
/// (freshTestFolder), made before the test and removed after it (kept after a failed test when
/// keepWhenFailed_ is set, to look at what it made). Suites use it by name
/// (`using Scratch = ScratchFolder;`) or derive from it (bake_fixture.hpp's BakeFolder, the
/// command's tests' fixtures); a suite's own SetUp and TearDown call these first and last.
class ScratchFolder : public ::testing::Test {
public:
    void SetUp() override {
        std::string suite = ::testing::UnitTest::GetInstance()->current_test_info()->test_suite_name();
        for (char& c : suite)
            if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
        dir_ = freshTestFolder("dqjulia_" + suite);
    }
    void TearDown() override {
        if (!(keepWhenFailed_ && HasFailure())) std::filesystem::remove_all(dir_);
    }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    std::vector<std::string> files() const { return fileNames(dir_); }
    /// Writes `text` (bytes as given) to the file `name` in the folder; its path.
    std::string write(const std::string& name, const std::string& text) const {
        std::ofstream(dir_ / name, std::ios::binary) << text;
        return path(name);
    }
    std::filesystem::path dir_;

protected:
    bool keepWhenFailed_ = false;
};

/// mt19937_64 is specified exactly by the standard, its distributions are not: the bits are
/// mapped here, so every platform tests the same points.
class Random {
public:
    explicit Random(std::uint64_t seed) : engine_(seed) {}
    double uniform(double low, double high) {
        return low + (high - low) * static_cast<double>(engine_() >> 11) * 0x1.0p-53;
    }
    template <typename Count>
    Count index(Count count) {
        return static_cast<Count>(engine_() % static_cast<std::uint64_t>(count));
    }
    glm::dvec3 inUnitBall() {
        while (true) {
            const glm::dvec3 v(uniform(-1, 1), uniform(-1, 1), uniform(-1, 1));
            if (glm::dot(v, v) <= 1.0) return v;
        }
    }
    /// A direction, uniform on the sphere (from the ball, away from its centre).
    glm::dvec3 unitVector() {
        while (true) {
            const glm::dvec3 v = inUnitBall();
            const double length = glm::length(v);
            if (length > 0.1) return v / length;
        }
    }

private:
    std::mt19937_64 engine_;
};

}  // namespace dqj::test
