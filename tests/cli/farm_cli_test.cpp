// The farm side of the command, run as a farm's task runs it: tiles baked apart and merged
// into the one-piece bake's file (the same bytes but OpenVDB's random file id), frames of
// tiles, --skip-existing (temporary files never count), --threads, the exit codes, bad input
// to merge, and the job files of `dqjulia farm slurm` and `dqjulia farm openjd` (the engines
// themselves run them in tests/farm).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "test_support.hpp"

namespace fs = std::filesystem;

using dqj::test::readFile;

namespace {

class FarmCli : public dqj::test::ScratchFolder {
protected:
    dqj::test::CommandResult run(const std::string& arguments) {
        return dqj::test::runCommand(DQJ_CLI, arguments, dir_);
    }
    std::string quoted(const std::string& name) const { return "'" + path(name) + "'"; }
};

/// A VDB file without the 36-byte random id OpenVDB writes into every file's header (from
/// byte 21): what two bakes of the same grids share.
std::string withoutFileId(const std::string& path) {
    std::string bytes = readFile(path);
    EXPECT_GT(bytes.size(), 64u) << path;
    if (bytes.size() > 64) bytes.replace(21, 36, 36, '-');
    return bytes;
}

const char* const kAnimation = R"({
  "slice": {"rotations": [{"plane": "a.j,b.s", "degrees": 0}]},
  "animation": {"slice.rotations[0].degrees": [{"frame": 1, "value": 0}, {"frame": 3, "value": 30}]}})";

TEST_F(FarmCli, TilesMergeIntoTheOnePieceBakesFile) {
    // The surface and density merge exactly, so the file is the one-piece bake's byte for byte;
    // the attribute grids (fast-swept extension fields) to float rounding (tests/core/tiles_test).
    const std::string flags = "-q -r 40 --grids surface,density ";
    ASSERT_EQ(run("bake " + flags + "-o " + quoted("whole.vdb")).exitCode, 0);
    const auto tiles = run("bake " + flags + "--tiles 3x2x1 -o " + quoted("tiled.vdb"));
    ASSERT_EQ(tiles.exitCode, 0) << tiles.err;
    for (int index = 1; index <= 6; ++index)
        EXPECT_TRUE(fs::is_regular_file(path("tiled.tile_" + std::to_string(index) + ".vdb"))) << index;
    // By name (any order), or by the tiling beside --output.
    const auto named = run("merge --stats " + quoted("tiled.tile_6.vdb") + " " + path("tiled.tile_[1-5].vdb") + " -o " +
                           quoted("named.vdb"));  // the shell expands the pattern, as a user's does
    ASSERT_EQ(named.exitCode, 0) << named.err;
    EXPECT_NE(named.out.find("tiles 6\n"), std::string::npos) << named.out;
    const auto byTiling = run("merge -q --tiles 3x2x1 -o " + quoted("tiled.vdb"));
    ASSERT_EQ(byTiling.exitCode, 0) << byTiling.err;
    EXPECT_EQ(withoutFileId(path("named.vdb")), withoutFileId(path("whole.vdb")));
    EXPECT_EQ(withoutFileId(path("tiled.vdb")), withoutFileId(path("whole.vdb")));
    // One tile at a time, as a farm's tasks bake them.
    ASSERT_EQ(run("bake " + flags + "--tiles 3x2x1 --tile 4 -o " + quoted("one.vdb")).exitCode, 0);
    EXPECT_EQ(dqj::test::fileNames(dir_).size(), 1u + 6 + 2 + 1);  // whole, 6 tiles, named, tiled, one's tile
    EXPECT_EQ(withoutFileId(path("one.tile_4.vdb")), withoutFileId(path("tiled.tile_4.vdb")));
}

TEST_F(FarmCli, FramesOfTilesMergeFrameByFrame) {
    const std::string params = write("anim.json", kAnimation);
    const std::string flags = "-q -r 32 --grids surface,density -p '" + params + "' --frames 2-3 ";
    ASSERT_EQ(run("bake " + flags + "-o " + quoted("whole.vdb")).exitCode, 0);
    ASSERT_EQ(run("bake " + flags + "--tiles 1x2x2 -o " + quoted("seq.vdb")).exitCode, 0);
    EXPECT_TRUE(fs::is_regular_file(path("seq_0003.tile_4.vdb")));
    const auto merged =
        run("merge -q --tiles 1x2x2 " + flags.substr(flags.find("--frames")) + "-o " + quoted("seq.vdb"));
    ASSERT_EQ(merged.exitCode, 0) << merged.err;
    for (const char* frame : {"_0002.vdb", "_0003.vdb"})
        EXPECT_EQ(withoutFileId(path(std::string("seq") + frame)), withoutFileId(path(std::string("whole") + frame)));
    EXPECT_NE(withoutFileId(path("seq_0002.vdb")), withoutFileId(path("seq_0003.vdb")));
}

TEST_F(FarmCli, SkipExistingRedoesOnlyWhatIsMissing) {
    const std::string params = write("anim.json", kAnimation);
    const std::string flags = "-r 24 -p '" + params + "' --frames 1-3 -o " + quoted("seq.vdb");
    ASSERT_EQ(run("bake -q --frames 2 -r 24 -p '" + params + "' -o " + quoted("seq.vdb")).exitCode, 0);
    const std::string frame2 = readFile(path("seq_0002.vdb"));
    // A dead writer's temporary file is not a finished frame: frame 3 is baked all the same.
    write(".seq_0003.vdb.tmp-dead01", "partial");
    const auto first = run("bake --skip-existing " + flags);
    ASSERT_EQ(first.exitCode, 0) << first.err;
    EXPECT_NE(first.err.find("skipped " + path("seq_0002.vdb") + ": it exists"), std::string::npos) << first.err;
    EXPECT_EQ(readFile(path("seq_0002.vdb")), frame2);
    EXPECT_TRUE(fs::is_regular_file(path("seq_0001.vdb")) && fs::is_regular_file(path("seq_0003.vdb")));
    // Everything done: nothing to do, and success.
    const auto again = run("bake --skip-existing " + flags);
    EXPECT_EQ(again.exitCode, 0) << again.err;
    EXPECT_EQ(again.err.find("wrote"), std::string::npos) << again.err;
    // Without it an existing output is bad input (a retry cannot help); both flags contradict.
    EXPECT_EQ(run("bake " + flags).exitCode, 2);
    const auto both = run("bake --force --skip-existing " + flags);
    EXPECT_EQ(both.exitCode, 2);
    EXPECT_NE(both.err.find("give one of the two"), std::string::npos) << both.err;
    // Meshes too.
    ASSERT_EQ(run("mesh -q -r 24 -o " + quoted("m.ply")).exitCode, 0);
    const auto mesh = run("mesh --skip-existing -r 24 -o " + quoted("m.ply"));
    EXPECT_EQ(mesh.exitCode, 0);
    EXPECT_NE(mesh.err.find("skipped"), std::string::npos) << mesh.err;
}

TEST_F(FarmCli, ThreadsAndExitCodesAreTheSchedulersToRead) {
    const auto one = run("bake -q -r 24 --threads 1 -o " + quoted("t1.vdb"));
    ASSERT_EQ(one.exitCode, 0) << one.err;
    const auto slurm = dqj::test::runCommand("/usr/bin/env",
                                             std::string("SLURM_CPUS_PER_TASK=2 '") + DQJ_CLI + "' bake -q -r 24 -o " +
                                                 quoted("t2.vdb"),
                                             dir_);
    ASSERT_EQ(slurm.exitCode, 0) << slurm.err;
    EXPECT_EQ(withoutFileId(path("t1.vdb")), withoutFileId(path("t2.vdb")));  // threads change no result
    EXPECT_EQ(run("bake --threads 0 -o " + quoted("x.vdb")).exitCode, 2);
    for (const char* command : {"bake", "mesh", "merge", "farm slurm", "farm openjd"}) {
        const auto help = run(std::string(command) + " --help");
        EXPECT_EQ(help.exitCode, 0) << command;
        EXPECT_NE(help.out.find("a retry cannot help"), std::string::npos) << command << "\n" << help.out;
    }
}

TEST_F(FarmCli, MergeRefusesWhatDoesNotFitAndWritesNothing) {
    ASSERT_EQ(run("bake -q -r 32 --tiles 2x1x1 -o " + quoted("a.vdb")).exitCode, 0);
    ASSERT_EQ(run("bake -q -r 32 -n 9 --tiles 2x1x1 --tile 2 -o " + quoted("b.vdb")).exitCode, 0);
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"merge " + quoted("a.tile_1.vdb") + " -o " + quoted("m.vdb"), "1 of the 2 tiles of 2x1x1 are missing: 2"},
        {"merge --tiles 2x2x1 -o " + quoted("a.vdb"), "no tile '" + path("a.tile_3.vdb")},
        {"merge " + quoted("a.tile_1.vdb") + " " + quoted("b.tile_2.vdb") + " -o " + quoted("m.vdb"),
         "is not a tile of the same bake"},
        {"merge -o " + quoted("m.vdb"), "give the tiles to merge"},
        {"merge --tiles 2x1 -o " + quoted("a.vdb"), "--tiles \"2x1\": expected AxBxC"},
        {"merge " + quoted("a.tile_1.vdb") + " --frames 1-2 -o " + quoted("m.vdb"), "--frames goes with --tiles"},
        {"bake -r 32 --tiles 5x1x1 -o " + quoted("m.vdb"), "at most 4 tiles of at least 8 voxels"},
        {"bake -r 32 --tiles 2x1x1 --tile 3 -o " + quoted("m.vdb"), "has tiles 1 to 2"},
        {"bake -r 32 --tile 1 -o " + quoted("m.vdb"), "--tile goes with --tiles"},
    };
    for (const auto& [arguments, message] : cases) {
        const auto result = run(arguments);
        EXPECT_EQ(result.exitCode, 2) << arguments << "\n" << result.err;
        EXPECT_NE(result.err.find(message), std::string::npos) << arguments << "\n" << result.err;
        EXPECT_FALSE(fs::exists(path("m.vdb"))) << arguments;
    }
    // A damaged tile is reported as such (exit 1), and nothing is written.
    const std::string bytes = readFile(path("a.tile_2.vdb"));
    std::ofstream(path("cut.tile_2.vdb"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
    const auto cut = run("merge " + quoted("a.tile_1.vdb") + " " + quoted("cut.tile_2.vdb") + " -o " + quoted("m.vdb"));
    EXPECT_EQ(cut.exitCode, 1) << cut.err;
    EXPECT_NE(cut.err.find("truncated"), std::string::npos) << cut.err;
    EXPECT_FALSE(fs::exists(path("m.vdb")));
}

TEST_F(FarmCli, FarmCommandsWriteTheirJobFiles) {
    const std::string params = write("anim.json", kAnimation);
    const std::string flags = "-p '" + params + "' -r 24 --frames 1-10 --chunk 4 --tiles 2x1x1 -o " + quoted("out.vdb");
    const auto slurm = run("farm slurm " + flags);
    ASSERT_EQ(slurm.exitCode, 0) << slurm.err;
    const std::string script = readFile(path("out.slurm")), merge = readFile(path("out.merge.slurm"));
    EXPECT_NE(script.find("#SBATCH --array=0-5\n"), std::string::npos) << script;  // 3 chunks x 2 tiles
    EXPECT_NE(script.find(" bake -p '" + path("out.params.json") + "' --frames \"$first-$last\" --tiles 2x1x1"),
              std::string::npos)
        << script;
    EXPECT_NE(merge.find("#SBATCH --array=0-2\n"), std::string::npos) << merge;
    EXPECT_NE(merge.find(" merge --tiles 2x1x1 --frames \"$first-$last\" -o '" + path("out.vdb") + "' --skip-existing"),
              std::string::npos)
        << merge;
    EXPECT_NE(slurm.out.find("--dependency=afterok:"), std::string::npos) << slurm.out;
    // The parameter file the tasks read is the bake's, flags applied.
    EXPECT_NE(readFile(path("out.params.json")).find("\"resolution\": 24"), std::string::npos);
    // The files exist now: again only with --force.
    EXPECT_EQ(run("farm slurm " + flags).exitCode, 2);
    ASSERT_EQ(run("farm slurm --force " + flags).exitCode, 0);

    const auto openjd = run("farm openjd " + flags + " --force");
    ASSERT_EQ(openjd.exitCode, 0) << openjd.err;
    const auto job = nlohmann::json::parse(readFile(path("out.openjd.json")));
    EXPECT_EQ(job["specificationVersion"], "jobtemplate-2023-09");
    ASSERT_EQ(job["steps"].size(), 2u);
    const auto& bake = job["steps"][0];
    EXPECT_EQ(bake["parameterSpace"]["taskParameterDefinitions"][0]["range"],
              nlohmann::json::array({"1-4", "5-8", "9-10"}));
    EXPECT_EQ(bake["parameterSpace"]["taskParameterDefinitions"][1]["range"], "1-2");
    EXPECT_EQ(job["steps"][1]["dependencies"][0]["dependsOn"], "Bake");
    EXPECT_EQ(job["parameterDefinitions"][2]["default"], "out.vdb");  // relative to the template's folder
    // Bad input: a tiling that does not fit, and too many chunks for a task parameter.
    EXPECT_EQ(run("farm openjd -r 24 --tiles 9x1x1 -o " + quoted("x.vdb")).exitCode, 2);
    const auto many = run("farm openjd -p '" + params + "' --frames 1-2000 -o " + quoted("x.vdb"));
    EXPECT_EQ(many.exitCode, 2);
    EXPECT_NE(many.err.find("raise --chunk"), std::string::npos) << many.err;
    EXPECT_FALSE(fs::exists(path("x.openjd.json")));
}

}  // namespace
