// Outputs (issue 35): an input is never an output; a run that writes several files publishes all
// of them or none; every output is checked before the work. Each class is tested through the real
// command, every command of the class: the exit status, the message and the files left behind.
#include <gtest/gtest.h>

#include <sys/statvfs.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "files/atomic_file.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using dqj::test::readFile;

namespace {

#define EXPECT_CONTAINS(text, part) EXPECT_NE(std::string(text).find(part), std::string::npos) << "in: " << (text)

/// Every file below `folder` (recursively, links as themselves) with its content ("-> target" for a link).
std::map<std::string, std::string> snapshot(const fs::path& folder) {
    std::map<std::string, std::string> files;
    for (const auto& entry : fs::recursive_directory_iterator(folder)) {
        const std::string name = fs::relative(entry.path(), folder).string();
        if (entry.is_symlink())
            files[name] = "-> " + fs::read_symlink(entry.path()).string();
        else if (entry.is_regular_file())
            files[name] = readFile(entry.path());
        else
            files[name] = "(folder)";
    }
    return files;
}

class Outputs : public dqj::test::ScratchFolder {
protected:
    void TearDown() override {
        disk_.reset();
        ScratchFolder::TearDown();
    }
    /// `arguments` with DIR replaced by the scratch folder, run in it.
    dqj::test::CommandResult run(std::string arguments, const std::string& input = "") {
        for (std::size_t at; (at = arguments.find("DIR")) != std::string::npos;)
            arguments.replace(at, 3, dir_.string());
        return dqj::test::runCommand(DQJ_CLI, arguments, dir_, input);
    }
    void write(const fs::path& path, const std::string& text) const { std::ofstream(path, std::ios::binary) << text; }

    std::optional<dqj::test::Tmpfs> disk_;  // unmounted before the folder is removed
};

// --- An input is never an output ----------------------------------------------------------

/// A run that would write over one of its own inputs. OUT is created as the input itself (when
/// `output` names the input), or as a symbolic or a hard link to it.
struct InputCase {
    const char* name;
    const char* input;      // the input, in the scratch folder
    const char* output;     // the output's name there
    const char* arguments;  // DIR is the scratch folder
};

const InputCase kInputCases[] = {
    {"merge_named_tiles", "a.tile_1.vdb", "a.tile_1.vdb",
     "merge -q DIR/a.tile_1.vdb DIR/a.tile_2.vdb -o DIR/a.tile_1.vdb"},
    {"merge_named_link", "a.tile_2.vdb", "m.vdb", "merge -q DIR/a.tile_1.vdb DIR/a.tile_2.vdb -o DIR/m.vdb"},
    {"merge_tiling", "a.tile_1.vdb", "a.vdb", "merge -q --tiles 2x1x1 -o DIR/a.vdb"},
    {"render_params", "p.json", "out.png", "render -q -W 8 -H 8 -p DIR/p.json -o DIR/out.png"},
    {"render_save_params", "p.json", "p.json",
     "render -q -W 8 -H 8 -p DIR/p.json -o DIR/o.png --save-params DIR/p.json"},
    {"render_voxels", "a.tile_1.vdb", "out.png", "render -q -W 8 -H 8 --voxels DIR/a.tile_1.vdb -o DIR/out.png"},
    {"povray_scene", "p.json", "scene.pov", "povray -q -p DIR/p.json -o DIR/scene.pov"},
    {"povray_df3", "p.json", "scene.df3", "povray -q --df3 --df3-resolution 8 -p DIR/p.json -o DIR/scene.pov"},
    {"povray_include", "p.json", "dqjulia.inc", "povray -q -p DIR/p.json -o DIR/scene.pov"},
    {"explore_tile", "explore/tile_01.json", "explore/tile_01.json",
     "explore -q --count 2 --tile-width 16 --tile-height 16 -p DIR/explore/tile_01.json -o DIR/explore"},
    {"explore_around", "explore/tile_01.json", "explore/tile_01.json",
     "explore -q --count 2 --tile-width 16 --tile-height 16 --around DIR/explore/tile_01.json -o DIR/explore"},
    {"sheet", "pic.png", "pic.png", "sheet -t DIR/pic.png -o DIR/pic.png"},
    {"bake", "p.json", "out.vdb", "bake -q -r 8 -p DIR/p.json -o DIR/out.vdb"},
    {"bake_frame", "p.json", "seq_0002.vdb", "bake -q -r 8 -p DIR/p.json --frames 1-3 -o DIR/seq.vdb"},
    {"bake_tile", "p.json", "t.tile_2.vdb", "bake -q -r 16 -p DIR/p.json --tiles 2x1x1 -o DIR/t.vdb"},
    {"mesh", "p.json", "out.ply", "mesh -q -r 8 -p DIR/p.json -o DIR/out.ply"},
    {"farm_slurm_params", "job.params.json", "job.params.json", "farm slurm -p DIR/job.params.json -o DIR/job.vdb"},
    {"farm_slurm_script", "p.json", "job.slurm", "farm slurm -p DIR/p.json -o DIR/job.vdb"},
    {"farm_slurm_merge_script", "p.json", "job.merge.slurm", "farm slurm -p DIR/p.json --tiles 2x1x1 -o DIR/job.vdb"},
    {"farm_openjd_template", "p.json", "job.openjd.json", "farm openjd -p DIR/p.json -o DIR/job.vdb"},
};

class InputsAreNeverOutputs : public Outputs, public ::testing::WithParamInterface<InputCase> {};

TEST_P(InputsAreNeverOutputs, RefusedWithAndWithoutForceThroughEveryKindOfName) {
    const InputCase& test = GetParam();
    // The inputs: a parameter file, two tiles of a bake, a picture, an explored tile.
    fs::create_directories(dir_ / "explore");
    const std::string params = R"({"fractal": {"iterations": 8}})";
    for (const char* name : {"p.json", "job.params.json", "explore/tile_01.json"}) write(dir_ / name, params);
    ASSERT_EQ(run("bake -q -r 16 --tiles 2x1x1 -o DIR/a.vdb").exitCode, 0);
    ASSERT_EQ(run("render -q -W 8 -H 8 -o DIR/pic.png").exitCode, 0);

    const bool same = std::strcmp(test.input, test.output) == 0;
    for (const char* how : {"the name", "a symbolic link", "a hard link"}) {
        if (same != (std::strcmp(how, "the name") == 0)) continue;
        SCOPED_TRACE(how);
        const fs::path input = dir_ / test.input, output = dir_ / test.output;
        if (!same) {
            fs::remove(output);
            if (std::strcmp(how, "a symbolic link") == 0)
                fs::create_symlink(input, output);
            else
                fs::create_hard_link(input, output);
        }
        const auto before = snapshot(dir_);
        for (const char* force : {"", " --force"}) {
            const auto result = run(std::string(test.arguments) + force);
            EXPECT_EQ(result.exitCode, 2) << force << ": " << result.err;
            EXPECT_CONTAINS(result.err,
                            "which this run reads: a run never writes over its own input, not even with "
                            "--force; write to another name");
            EXPECT_CONTAINS(result.err, "'" + input.string() + "'");
            EXPECT_EQ(snapshot(dir_), before) << "files changed";
        }
        if (!same) fs::remove(output);
    }
}

INSTANTIATE_TEST_SUITE_P(Commands, InputsAreNeverOutputs, ::testing::ValuesIn(kInputCases),
                         [](const auto& info) { return std::string(info.param.name); });

// --- All or nothing --------------------------------------------------------------------------

/// A command that writes several files into OUT (a folder), and those files. kSetCases holds every
/// command, in every configuration, whose one output is several files (a frame sequence and the
/// tiles of a bake are separate outputs instead, each published when done: README).
struct SetCase {
    const char* name;
    const char* arguments;  // OUT is the output folder
    std::vector<const char*> outputs;
};

const SetCase kSetCases[] = {
    {"povray_scene", "povray -q -o OUT/scene.pov", {"scene.pov", "dqjulia.inc"}},
    {"povray_df3",
     "povray -q --df3 --df3-resolution 24 -o OUT/scene.pov",
     {"scene.pov", "scene.df3", "scene_df3.pov", "dqjulia.inc"}},
    {"render_save_params",
     "render -q -W 64 -H 48 -o OUT/picture.png --save-params OUT/picture.json",
     {"picture.png", "picture.json"}},
    {"explore",
     "explore -q --count 2 --tile-width 32 --tile-height 24 -o OUT",
     {"sheet.png", "tile_01.png", "tile_01.json", "tile_02.png", "tile_02.json"}},
    {"farm_slurm", "farm slurm --frames 1-4 -o OUT/job.vdb", {"job.params.json", "job.slurm"}},
    {"farm_slurm_tiles",
     "farm slurm --frames 1-4 --tiles 2x1x1 -o OUT/job.vdb",
     {"job.params.json", "job.slurm", "job.merge.slurm"}},
    {"farm_openjd", "farm openjd --frames 1-4 -o OUT/job.vdb", {"job.params.json", "job.openjd.json"}},
};

class AllOrNothing : public Outputs, public ::testing::WithParamInterface<SetCase> {
protected:
    dqj::test::CommandResult runInto(const fs::path& folder, const std::string& extra = "",
                                     const std::string& environment = "") {
        std::string arguments = GetParam().arguments;
        for (std::size_t at; (at = arguments.find("OUT")) != std::string::npos;)
            arguments.replace(at, 3, folder.string());
        if (environment.empty()) return run(arguments + extra);
        return dqj::test::runCommand("/usr/bin/env",
                                     environment + " '" + std::string(DQJ_CLI) + "' " + arguments + extra, dir_);
    }
    std::set<std::string> names(const fs::path& folder) const {
        const std::vector<std::string> all = dqj::test::fileNames(folder);
        return {all.begin(), all.end()};
    }
    std::set<std::string> expected() const { return {GetParam().outputs.begin(), GetParam().outputs.end()}; }
    void writeOld(const fs::path& folder) const {
        for (const char* name : GetParam().outputs) write(folder / name, std::string("old ") + name);
    }
    void expectOld(const fs::path& folder) const {
        for (const char* name : GetParam().outputs)
            EXPECT_EQ(readFile(folder / name), std::string("old ") + name) << name;
    }
};

std::uintmax_t pagesOf(std::uintmax_t bytes) { return (bytes + 4095) / 4096; }

// A disk with room for all files but one page: the run fails, publishes nothing and leaves no
// temporary file; with the space back, the retry succeeds (once, a failed povray --df3 left its
// scene behind, and the retry was refused for it). With --force over old files, the old files stay.
TEST_P(AllOrNothing, AFullDiskPublishesNothingAndTheRetrySucceeds) {
    // How much the files take, from a run on the ordinary disk.
    const fs::path roomy = dir_ / "roomy";
    fs::create_directories(roomy);
    const auto clean = runInto(roomy);
    ASSERT_EQ(clean.exitCode, 0) << clean.err;
    ASSERT_EQ(names(roomy), expected());
    std::uintmax_t pages = 0;
    for (const char* name : GetParam().outputs) pages += pagesOf(fs::file_size(roomy / name));

    const fs::path mount = dir_ / "disk";
    if (!disk_.emplace(mount, "4m").mounted()) GTEST_SKIP() << "cannot mount a tmpfs here: " << std::strerror(errno);
    auto fill = [&](std::uintmax_t freePages) {
        struct statvfs info {};
        ASSERT_EQ(::statvfs(mount.c_str(), &info), 0);
        const std::uintmax_t available = std::uintmax_t(info.f_bavail) * info.f_frsize;
        ASSERT_GT(available, freePages * 4096);
        write(mount / ".filler", std::string(available - freePages * 4096, 'x'));
    };
    for (const bool force : {false, true}) {
        SCOPED_TRACE(force ? "--force over old files" : "new files");
        for (const auto& entry : fs::directory_iterator(mount)) fs::remove(entry.path());
        if (force) writeOld(mount);
        fill(pages - 1);
        const auto failed = runInto(mount, force ? " --force" : "");
        EXPECT_EQ(failed.exitCode, 1) << failed.err;
        EXPECT_CONTAINS(failed.err, "No space left on device");
        EXPECT_CONTAINS(failed.err, "(none of the " + std::to_string(GetParam().outputs.size()) +
                                        " files of this run was written)");
        std::set<std::string> left = force ? expected() : std::set<std::string>{};
        left.insert(".filler");
        EXPECT_EQ(names(mount), left);
        if (force) expectOld(mount);

        fs::remove(mount / ".filler");  // the space is back: the retry succeeds
        const auto retry = runInto(mount, force ? " --force" : "");
        EXPECT_EQ(retry.exitCode, 0) << retry.err;
        EXPECT_EQ(names(mount), expected());
        for (const char* name : GetParam().outputs)  // the new files (scripts name their folder: sizes vary)
            EXPECT_EQ(readFile(mount / name).rfind("old ", 0), std::string::npos) << name;
    }
}

// Publishing itself fails for one file (the fault shim refuses its name): the files published
// before it are withdrawn and the files they replaced are put back, whichever file it is.
TEST_P(AllOrNothing, AFailureWhilePublishingWithdrawsWhatWasPublished) {
    const fs::path folder = dir_ / "out";
    fs::create_directories(folder);
    for (std::size_t failing = 0; failing < GetParam().outputs.size(); ++failing)
        for (const bool force : {false, true}) {
            SCOPED_TRACE("publishing file " + std::to_string(failing + 1) + (force ? ", --force" : ""));
            for (const auto& entry : fs::directory_iterator(folder)) fs::remove(entry.path());
            if (force) writeOld(folder);
            const auto result =
                runInto(folder, force ? " --force" : "",
                        "LD_PRELOAD='" + std::string(DQJ_FAULT_SHIM) + "' DQJ_FAULT_DIR='" + folder.string() +
                            "' DQJ_FAULT_MODE=publish DQJ_FAULT_AFTER=" + std::to_string(failing));
            EXPECT_EQ(result.exitCode, 1) << result.err;
            EXPECT_CONTAINS(result.err, "Input/output error");
            EXPECT_CONTAINS(result.err, "files of this run was written)");
            EXPECT_EQ(names(folder), force ? expected() : std::set<std::string>{});  // nothing hidden left either
            if (force) expectOld(folder);
        }
}

INSTANTIATE_TEST_SUITE_P(Commands, AllOrNothing, ::testing::ValuesIn(kSetCases),
                         [](const auto& info) { return std::string(info.param.name); });

// The set itself: a file that appears meanwhile (without --force) withdraws what was published.
TEST_F(Outputs, AFileThatAppearsWhileASetIsPublishedWithdrawsTheOthers) {
    dqj::AtomicFileSet set(dqj::Existing::Keep);
    set.add((dir_ / "first.txt").string()).stream() << "first";
    set.add((dir_ / "second.txt").string()).stream() << "second";
    write(dir_ / "second.txt", "someone else's");
    try {
        set.commit();
        ADD_FAILURE() << "published over a file that appeared";
    } catch (const std::runtime_error& error) {
        EXPECT_CONTAINS(error.what(), "the file appeared while dqjulia worked and is kept");
        EXPECT_CONTAINS(error.what(), "(none of the 2 files of this run was written)");
    }
    EXPECT_EQ(snapshot(dir_), (std::map<std::string, std::string>{{"second.txt", "someone else's"}}));
}

// --- Every output checked before the work ----------------------------------------------------

/// Every command that writes files, with NAME in one of its outputs' names (`output`, in DIR), and
/// work enough that a refusal after it would take many seconds.
struct Writer {
    const char* arguments;
    const char* output;
};
const Writer kWriters[] = {
    {"render -q -W 1600 -H 1200 -s 3 -o DIR/NAME.png", "NAME.png"},
    {"render -q -W 1600 -H 1200 -s 3 -o DIR/ok.png --save-params DIR/NAME.json", "NAME.json"},
    {"bake -q -r 1024 -o DIR/NAME.vdb", "NAME.vdb"},
    {"bake -q -r 1024 --frames 1-2 -o DIR/NAME.vdb", "NAME_0002.vdb"},
    {"bake -q -r 1024 --tiles 2x1x1 -o DIR/NAME-tiled.vdb", "NAME-tiled.tile_2.vdb"},
    {"mesh -q -r 1024 -o DIR/NAME.ply", "NAME.ply"},
    {"povray -q --df3 --df3-resolution 512 -o DIR/NAME.pov", "NAME.df3"},
    {"explore -q --count 100 -o DIR/NAME", "NAME/tile_07.json"},
    {"merge -q --tiles 2x1x1 -o DIR/NAME.vdb", "NAME.vdb"},
    {"sheet -t DIR/pic.png -o DIR/NAME.png", "NAME.png"},
    {"farm slurm -o DIR/job.vdb --script DIR/NAME.slurm", "NAME.slurm"},
    {"farm openjd -o DIR/job.vdb --template DIR/NAME.json", "NAME.json"},
};

std::string withName(std::string text, const std::string& name) {
    text.replace(text.find("NAME"), 4, name);
    return text;
}

TEST_F(Outputs, ADanglingLinkIsRefusedBeforeTheWork) {
    ASSERT_EQ(run("render -q -W 8 -H 8 -o DIR/pic.png").exitCode, 0);
    ASSERT_EQ(run("bake -q -r 16 --tiles 2x1x1 -o DIR/dangling.vdb").exitCode, 0);  // merge's tiles
    fs::create_directories(dir_ / "dangling");                                      // explore's folder
    for (const Writer& writer : kWriters) {
        for (const char* force : {"", " --force"}) {
            SCOPED_TRACE(std::string(writer.arguments) + force);
            const fs::path output = dir_ / withName(writer.output, "dangling");
            const fs::path target = dir_ / "missing" / "target";
            fs::remove(output);
            fs::create_symlink(target, output);
            const auto before = snapshot(dir_);
            const auto started = std::chrono::steady_clock::now();
            const auto result = run(withName(writer.arguments, "dangling") + force);
            const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
            EXPECT_EQ(result.exitCode, 2) << result.err;
            EXPECT_CONTAINS(result.err, "cannot write '" + output.string() + "': it is a symbolic link to '" +
                                            target.string() + "', which does not exist");
            EXPECT_EQ(result.err.find("appeared"), std::string::npos) << result.err;
            EXPECT_LT(seconds, 5.0) << "refused only after the work";
            EXPECT_EQ(snapshot(dir_), before);
            fs::remove(output);
        }
    }
}

// explore writes a folder: a dangling link or a file in its place is refused before the work,
// and a folder it made is removed again when the run fails (here: publishing its files fails).
TEST_F(Outputs, ExploresFolderIsCheckedBeforeItIsMadeAndRemovedAfterAFailure) {
    fs::create_symlink(dir_ / "missing", dir_ / "dangling");
    write(dir_ / "file", "a file");
    const auto before = snapshot(dir_);
    for (const char* force : {"", " --force"}) {
        SCOPED_TRACE(force);
        auto result = run(std::string("explore -q --count 100 -o DIR/dangling") + force);
        EXPECT_EQ(result.exitCode, 2) << result.err;
        EXPECT_CONTAINS(result.err, "--output '" + (dir_ / "dangling").string() + "' is a symbolic link to '" +
                                        (dir_ / "missing").string() + "', which does not exist; give a folder");
        result = run(std::string("explore -q --count 100 -o DIR/file") + force);
        EXPECT_EQ(result.exitCode, 2) << result.err;
        EXPECT_CONTAINS(result.err, "is a file, not a folder; explore writes a folder of files");
        EXPECT_EQ(snapshot(dir_), before);
    }
    const fs::path fresh = dir_ / "fresh" / "sub";
    const auto failed =
        dqj::test::runCommand("/usr/bin/env",
                              "LD_PRELOAD='" + std::string(DQJ_FAULT_SHIM) + "' DQJ_FAULT_DIR='" + fresh.string() +
                                  "' DQJ_FAULT_MODE=publish DQJ_FAULT_AFTER=0 '" + DQJ_CLI +
                                  "' explore -q --count 2 --tile-width 16 --tile-height 16 -o '" + fresh.string() + "'",
                              dir_);
    EXPECT_EQ(failed.exitCode, 1) << failed.err;
    EXPECT_CONTAINS(failed.err, "(none of the 5 files of this run was written)");
    EXPECT_EQ(snapshot(dir_), before) << "the folders this run made are left";
    const auto retry = run("explore -q --count 2 --tile-width 16 --tile-height 16 -o DIR/fresh/sub");
    EXPECT_EQ(retry.exitCode, 0) << retry.err;
    EXPECT_EQ(dqj::test::fileNames(fresh).size(), 5u);
}

TEST_F(Outputs, DevicesAreRefusedBeforeTheWork) {
    ASSERT_EQ(run("render -q -W 8 -H 8 -o DIR/pic.png").exitCode, 0);
    ASSERT_EQ(run("bake -q -r 16 --tiles 2x1x1 -o DIR/device.vdb").exitCode, 0);
    fs::create_directories(dir_ / "device");
    for (const Writer& writer : kWriters) {
        SCOPED_TRACE(writer.arguments);
        const fs::path output = dir_ / withName(writer.output, "device");
        fs::remove(output);
        fs::create_symlink("/dev/null", output);  // a device under the output's own name
        const auto before = snapshot(dir_);
        const auto started = std::chrono::steady_clock::now();
        const auto result = run(withName(writer.arguments, "device") + " --force");
        EXPECT_EQ(result.exitCode, 2) << result.err;
        EXPECT_CONTAINS(result.err, "is not a regular file (a device, FIFO or socket)");
        EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), 5.0);
        EXPECT_EQ(snapshot(dir_), before);
        fs::remove(output);
    }
}

TEST_F(Outputs, ANameTooLongForTheFileSystemIsRefusedBeforeTheWorkAndTheLongestIsWritten) {
    // 255 bytes is the longest name: written, also over an old file (its hidden temporary name is
    // shortened to fit); 256 bytes is refused before the work, saying why.
    const std::string longest(255 - 4, 'n');
    write(dir_ / (longest + ".png"), "old");
    auto result = run("render -q -W 8 -H 8 --force -o DIR/" + longest + ".png");
    EXPECT_EQ(result.exitCode, 0) << result.err;
    EXPECT_NE(readFile(dir_ / (longest + ".png")), "old");
    const std::string tooLong(256 - 4, 'n');
    const auto started = std::chrono::steady_clock::now();
    result = run("bake -q -r 1024 -o DIR/" + tooLong + ".vdb");
    EXPECT_EQ(result.exitCode, 2) << result.err;
    EXPECT_CONTAINS(result.err, "the file name is 256 bytes long; this file system allows at most 255");
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), 5.0);
    EXPECT_EQ(dqj::test::fileNames(dir_), std::vector<std::string>{longest + ".png"});
}

// The Windows name rule, tested here as pure logic (the Windows build applies it; tests/windows
// runs it under Wine).
TEST(WindowsNames, ReservedDeviceNamesInAnyComponentAnyCaseAnyExtension) {
    for (const std::string name :
         {"CON", "con", "Prn.png", "AUX.tar.gz", "nul", "NUL.vdb", "COM1", "com9.txt", "LPT1", "lpt5.x.y",
          "COM\xc2\xb9", "lpt\xc2\xb3.png", "CONIN$", "conout$.txt", "NUL .png", "CON  "}) {
        SCOPED_TRACE(name);
        for (const std::string& path : {name, "C:\\renders\\" + name, "Z:/renders/" + name + "/out.png",
                                        "\\\\server\\share\\" + name, "dir/" + name + "/x/out.vdb"})
            EXPECT_NE(dqj::windowsNameProblem(path), "") << path;
    }
    EXPECT_NE(dqj::windowsNameProblem("C:\\dir\\AUX.png").find("reserves for a device"), std::string::npos);
}

TEST(WindowsNames, OtherNamesWindowsCannotHold) {
    for (const std::string path :
         {"out.png.", "out.png ", "dir./out.png", "dir\\a:b.png", "C:\\x\\a:stream", "what?.png", "star*.png",
          "pipe|.png", "less<.png", "quote\".png", "tab\t.png", "\\\\.\\COM1", "//./PhysicalDrive0"})
        EXPECT_NE(dqj::windowsNameProblem(path), "") << path;
    EXPECT_NE(dqj::windowsNameProblem("out.png.").find("would be 'out.png'"), std::string::npos);
}

TEST(WindowsNames, OrdinaryNamesPass) {
    for (const std::string path :
         {"out.png", "C:\\renders\\fractal.vdb", "C:fractal.vdb", "Z:/tmp/console.png", "CONSOLE", "COM10.png",
          "COM0.png", "LPT.png", "nul_0001.vdb", "my.con.png", "caf\xc3\xa9.png", "./out.png", "../x/out.png",
          "\\\\server\\share\\out.png", "\\\\?\\C:\\out.png", "\\\\?\\UNC\\server\\share\\out.png", "dir/.hidden"})
        EXPECT_EQ(dqj::windowsNameProblem(path), "") << path;
}

}  // namespace
