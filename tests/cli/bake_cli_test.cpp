// `dqjulia bake` and `dqjulia mesh` run as a user runs them: files and --stats, frame
// sequences, one clear message for bad input with nothing written, and Ctrl-C / SIGTERM in the
// middle of a bake leaving the previous file and no temporary.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>
#include "test_support.hpp"

namespace fs = std::filesystem;

using dqj::test::readFile;

namespace {

using Outcome = dqj::test::CommandResult;

class BakeCli : public dqj::test::ScratchFolder {
protected:
    Outcome run(const std::string& arguments) { return dqj::test::runCommand(DQJ_CLI, arguments, dir_); }
};

using dqj::test::statValue;

TEST_F(BakeCli, BakeAndMeshReportTheirWork) {
    const Outcome bake = run("bake -r 32 --stats -o '" + path("f.vdb") + "'");
    ASSERT_EQ(bake.exitCode, 0) << bake.err;
    EXPECT_EQ(statValue(bake.out, "voxels_dense"), 32.0 * 32 * 32);
    EXPECT_GT(statValue(bake.out, "voxels_evaluated"), 0.0);
    EXPECT_GT(statValue(bake.out, "active_voxels"), 0.0);
    EXPECT_GT(statValue(bake.out, "peak_memory_bytes"), 1e6);
    EXPECT_GE(statValue(bake.out, "seconds"), 0.0);
    EXPECT_NE(bake.err.find("wrote " + path("f.vdb")), std::string::npos) << bake.err;
    EXPECT_NE(bake.err.find("voxels ("), std::string::npos) << bake.err;  // "evaluated X of Y voxels (Z%)"

    const Outcome mesh = run("mesh -r 32 --stats -o '" + path("f.obj") + "'");
    ASSERT_EQ(mesh.exitCode, 0) << mesh.err;
    const std::string obj = readFile(path("f.obj"));
    std::size_t vertices = 0, pos = 0;
    while ((pos = obj.find("\nv ", pos)) != std::string::npos) ++vertices, ++pos;
    EXPECT_EQ(double(vertices), statValue(mesh.out, "vertices"));
    EXPECT_EQ(files(), (std::vector<std::string>{"f.obj", "f.vdb"}));
}

TEST_F(BakeCli, FramesBakeANumberedSequence) {
    const std::string params = write("anim.json", R"({
      "slice": {"rotations": [{"plane": "a.j,b.s", "degrees": 0}]},
      "animation": {"slice.rotations[0].degrees": [{"frame": 1, "value": 0}, {"frame": 3, "value": 40, "interpolation": "smooth"}],
                    "fractal.iterations": [{"frame": 1, "value": 8}, {"frame": 3, "value": 12}]}})");
    const Outcome result = run("bake -q -r 24 -p '" + params + "' --frames 2-4 --stats -o '" + path("seq.vdb") + "'");
    ASSERT_EQ(result.exitCode, 0) << result.err;
    EXPECT_EQ(files(), (std::vector<std::string>{"anim.json", "seq_0002.vdb", "seq_0003.vdb", "seq_0004.vdb"}));
    EXPECT_NE(result.out.find("frame 4\n"), std::string::npos) << result.out;
    const Outcome meshes = run("mesh -q -r 24 -p '" + params + "' --frames 1-2 -o '" + path("seq.ply") + "'");
    ASSERT_EQ(meshes.exitCode, 0) << meshes.err;
    EXPECT_TRUE(fs::exists(path("seq_0001.ply")) && fs::exists(path("seq_0002.ply")));
    EXPECT_NE(readFile(path("seq_0001.ply")), readFile(path("seq_0002.ply")));
    // An existing frame is not overwritten without --force, and nothing is baked.
    const Outcome again = run("bake -q -r 24 -p '" + params + "' --frames 3-5 -o '" + path("seq.vdb") + "'");
    EXPECT_EQ(again.exitCode, 2);
    EXPECT_NE(again.err.find("seq_0003.vdb' exists; pass --force"), std::string::npos) << again.err;
    EXPECT_FALSE(fs::exists(path("seq_0005.vdb")));
}

TEST_F(BakeCli, BadInputGetsOneClearMessageAndWritesNothing) {
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"bake -r 4", "--resolution"},
        {"bake -r 20000", "--resolution"},
        {"bake --frames 5-2", "the last frame comes before the first"},
        {"bake --frames 1-x", "expected FIRST-LAST"},
        {"bake --frames 3-", "expected FIRST-LAST"},
        {"bake --max-memory lots", "expected a size such as 512M"},
        {"bake -r 512 --max-memory 1M", "more than the limit of 1 MB"},
        {"bake --grids surface,fog",
         "bake.grids: must be one of surface, density, color, trap, iterations, got \"fog\""},
        {"bake --bounds-min 0 0 0", "--bounds-min and --bounds-max go together"},
        {"bake --bounds-min 1 1 1 --bounds-max 0 2 2", "min must be below max"},
        {"mesh --adaptivity 3", "--adaptivity"},
        {"bake -n 0", "fractal.iterations"},
    };
    for (const auto& [arguments, message] : cases) {
        const Outcome result = run(arguments + " -o '" + path("never.vdb") + "'");
        EXPECT_EQ(result.exitCode, 2) << arguments << "\n" << result.err;
        EXPECT_NE(result.err.find(message), std::string::npos) << arguments << "\nstderr: " << result.err;
        EXPECT_TRUE(files().empty()) << arguments;
    }
    const Outcome png = run("bake -o '" + path("x.png") + "'");
    EXPECT_EQ(png.exitCode, 2);
    EXPECT_NE(png.err.find("must end in .vdb"), std::string::npos) << png.err;
    const Outcome amf = run("mesh -o '" + path("x.amf") + "'");
    EXPECT_EQ(amf.exitCode, 2);
    EXPECT_NE(amf.err.find("must end in .ply, .obj, .stl or .3mf"), std::string::npos) << amf.err;
    const Outcome folder = run("bake -o '" + path("missing/x.vdb") + "'");
    EXPECT_EQ(folder.exitCode, 2);
    EXPECT_NE(folder.err.find("does not exist"), std::string::npos) << folder.err;
    EXPECT_TRUE(files().empty());
}

class BakeInterrupt : public BakeCli, public ::testing::WithParamInterface<int> {};

TEST_P(BakeInterrupt, StopsPromptlyAndKeepsThePreviousFile) {
    const std::string target = path("keep.vdb");
    std::ofstream(target) << "previous";
    const fs::path errPath = dir_.parent_path() / (dir_.filename().string() + ".stderr");
    // A bake of several seconds; the signal arrives while it samples.
    const pid_t pid = dqj::test::spawnProgram(DQJ_CLI, {"bake", "-r", "384", "-f", "-o", target}, errPath);
    ASSERT_GT(pid, 0);
    std::this_thread::sleep_for(std::chrono::milliseconds(1200));
    const auto signalled = std::chrono::steady_clock::now();
    ASSERT_EQ(::kill(pid, GetParam()), 0);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - signalled).count();
    const std::string err = readFile(errPath);
    fs::remove(errPath);
    ASSERT_TRUE(WIFEXITED(status)) << "killed by signal " << WTERMSIG(status);
    EXPECT_EQ(WEXITSTATUS(status), 130) << err;
    EXPECT_LT(seconds, 3.0);
    EXPECT_NE(err.find("interrupted; nothing was written"), std::string::npos) << err;
    EXPECT_EQ(readFile(target), "previous");
    EXPECT_EQ(files(), std::vector<std::string>{"keep.vdb"});
}

INSTANTIATE_TEST_SUITE_P(Signals, BakeInterrupt, ::testing::Values(SIGINT, SIGTERM),
                         [](const ::testing::TestParamInfo<int>& info) {
                             return info.param == SIGINT ? "SIGINT" : "SIGTERM";
                         });

}  // namespace
