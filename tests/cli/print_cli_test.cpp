// `dqjulia mesh`'s print check as a user meets it: an STL or 3MF checked closed and
// edge-manifold as its slabs are written; the ball's full report (one closed island, its
// size and volume, its diameter as its thinnest wall) in the file's units; an STL refused with
// the reason named and nothing written unless --allow-unprintable; a PLY written with a warning;
// islands dropped by --min-island and --largest-only; a mesh too large for one piece refused.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <sstream>
#include <string>

#include "test_support.hpp"

namespace fs = std::filesystem;

namespace {

using Outcome = dqj::test::CommandResult;

class PrintCli : public dqj::test::ScratchFolder {
protected:
    Outcome run(const std::string& arguments) { return dqj::test::runCommand(DQJ_CLI, arguments, dir_); }
};

using dqj::test::statValue;

/// c = 0: the unit ball, 40 voxels across a 3-wide box (voxel 0.075).
const std::string kBall =
    "mesh --c 0 0 0 0 0 0 0 0 --bailout 4 -r 40 --bounds-min -1.5 -1.5 -1.5 --bounds-max 1.5 1.5 1.5 --no-colors ";
constexpr double kVoxel = 0.075;
constexpr double kPi = std::numbers::pi;

TEST_F(PrintCli, AnStlIsCheckedClosedAndManifoldAsItIsStreamed) {
    const Outcome ok = run(kBall + "--stats -o '" + path("ball.stl") + "'");
    ASSERT_EQ(ok.exitCode, 0) << ok.err;
    EXPECT_EQ(statValue(ok.out, "print_closed"), 1.0);
    EXPECT_EQ(statValue(ok.out, "print_edge_manifold"), 1.0);
    EXPECT_EQ(statValue(ok.out, "print_ok"), 1.0);
    EXPECT_EQ(ok.out.find("print_islands"), std::string::npos) << ok.out;  // asked for with --min-island
    EXPECT_NE(ok.err.find("print check: closed, edge-manifold; "), std::string::npos) << ok.err;
    // In slabs (the limit too small for one piece), checked all the same.
    const Outcome slabs = run("mesh -r 256 --no-colors --max-memory 120M --stats -o '" + path("big.3mf") + "'");
    ASSERT_EQ(slabs.exitCode, 0) << slabs.err;
    EXPECT_GT(statValue(slabs.out, "slabs"), 1.0);
    EXPECT_EQ(statValue(slabs.out, "print_closed"), 1.0);
    EXPECT_EQ(statValue(slabs.out, "print_edge_manifold"), 1.0);
    EXPECT_EQ(statValue(slabs.out, "print_ok"), 1.0);
}

TEST_F(PrintCli, TheBallIsPrintableAndReported) {
    const Outcome ok = run(kBall + "--min-island 1 --stats -o '" + path("ball.stl") + "'");
    ASSERT_EQ(ok.exitCode, 0) << ok.err;
    EXPECT_EQ(statValue(ok.out, "print_closed"), 1.0);
    EXPECT_EQ(statValue(ok.out, "print_edge_manifold"), 1.0);
    EXPECT_EQ(statValue(ok.out, "print_islands"), 1.0);
    EXPECT_EQ(statValue(ok.out, "print_ok"), 1.0);
    EXPECT_NEAR(statValue(ok.out, "print_island_1_size"), 2.0, kVoxel);
    EXPECT_NEAR(statValue(ok.out, "print_island_1_volume"), 4.0 / 3.0 * kPi, 4.0 * kPi * kVoxel);
    EXPECT_EQ(statValue(ok.out, "print_wall_found"), 0.0);  // none under the default 12 voxels
    EXPECT_NE(ok.err.find("print check: closed, edge-manifold; 1 island"), std::string::npos) << ok.err;
    // Binary STL: 84 bytes, then 50 a triangle (each quad two).
    const double triangles = statValue(ok.out, "triangulated");
    EXPECT_EQ(double(fs::file_size(path("ball.stl"))), 84.0 + 50.0 * triangles);
}

TEST_F(PrintCli, AnStlWithAWallTooThinIsRefusedUnlessAllowed) {
    const Outcome refused = run(kBall + "--min-wall 2.5 -o '" + path("ball.stl") + "'");
    EXPECT_EQ(refused.exitCode, 2) << refused.err;
    EXPECT_NE(refused.err.find("was not written: its thinnest wall, "), std::string::npos) << refused.err;
    EXPECT_NE(refused.err.find("is under --min-wall 2.5 (--allow-unprintable writes it anyway)"), std::string::npos)
        << refused.err;
    EXPECT_TRUE(files().empty());

    const Outcome allowed = run(kBall + "--min-wall 2.5 --allow-unprintable --stats -o '" + path("ball.stl") + "'");
    EXPECT_EQ(allowed.exitCode, 0) << allowed.err;
    EXPECT_NEAR(statValue(allowed.out, "print_thinnest_wall"), 2.0, kVoxel);  // the diameter
    EXPECT_EQ(statValue(allowed.out, "print_ok"), 0.0);
    EXPECT_NE(allowed.err.find("warning: " + path("ball.stl") + " is not printable"), std::string::npos) << allowed.err;
    EXPECT_TRUE(fs::exists(path("ball.stl")));

    // A PLY is not for printing: written, with the warning.
    const Outcome ply = run(kBall + "--min-wall 2.5 -o '" + path("ball.ply") + "'");
    EXPECT_EQ(ply.exitCode, 0) << ply.err;
    EXPECT_NE(ply.err.find("is not printable"), std::string::npos) << ply.err;
    EXPECT_TRUE(fs::exists(path("ball.ply")));
}

TEST_F(PrintCli, TheCheckIsInTheFilesUnits) {
    // 100 mm across: the wall, the island and --min-wall in millimetres.
    const Outcome refused = run(kBall + "--units mm --size 100 --min-wall 120 --stats -o '" + path("ball.3mf") + "'");
    EXPECT_EQ(refused.exitCode, 2) << refused.err;
    EXPECT_NE(refused.err.find("is under --min-wall 120"), std::string::npos) << refused.err;
    EXPECT_TRUE(files().empty());
    const Outcome ok = run(kBall + "--units mm --size 100 --min-wall 90 --stats -o '" + path("ball.3mf") + "'");
    ASSERT_EQ(ok.exitCode, 0) << ok.err;
    EXPECT_NEAR(statValue(ok.out, "print_island_1_size"), 100.0, 1e-3);
    EXPECT_NEAR(statValue(ok.out, "print_thinnest_wall"), 100.0, 100.0 * kVoxel / 2.0);
    EXPECT_TRUE(fs::exists(path("ball.3mf")));
}

TEST_F(PrintCli, IslandsAreDroppedOnRequest) {
    const std::string fractal = "mesh -r 128 --no-colors --stats ";  // 5 islands
    const Outcome all = run(fractal + "--min-island 1 --allow-unprintable -o '" + path("all.stl") + "'");
    ASSERT_EQ(all.exitCode, 0) << all.err;
    const double islands = statValue(all.out, "print_islands"), faces = statValue(all.out, "faces");
    ASSERT_GT(islands, 2.0) << all.err;  // the default Julia set breaks into islands
    const double largest = statValue(all.out, "print_island_1_faces"),
                 second = statValue(all.out, "print_island_2_faces");

    const Outcome one = run(fractal + "--largest-only --allow-unprintable -o '" + path("one.stl") + "'");
    ASSERT_EQ(one.exitCode, 0) << one.err;
    EXPECT_EQ(statValue(one.out, "print_islands"), 1.0);
    EXPECT_EQ(statValue(one.out, "print_dropped_islands"), islands - 1.0);
    EXPECT_EQ(statValue(one.out, "print_dropped_faces"), faces - largest);
    EXPECT_EQ(statValue(one.out, "faces"), largest);

    const Outcome some = run(fractal + "--min-island " + std::to_string(long(second)) + " --allow-unprintable -o '" +
                             path("some.ply") + "'");
    ASSERT_EQ(some.exitCode, 0) << some.err;
    EXPECT_GE(statValue(some.out, "print_islands"), 2.0);
    EXPECT_EQ(statValue(some.out, "print_island_2_faces"), second);
    EXPECT_EQ(statValue(some.out, "print_islands") + statValue(some.out, "print_dropped_islands"), islands);

    const Outcome none =
        run(fractal + "--min-island " + std::to_string(long(largest) + 1) + " -o '" + path("none.ply") + "'");
    EXPECT_EQ(none.exitCode, 2);
    EXPECT_NE(none.err.find("drops every island: the largest has " + std::to_string(long(largest)) + " faces"),
              std::string::npos)
        << none.err;
    EXPECT_FALSE(fs::exists(path("none.ply")));
}

TEST_F(PrintCli, AMeshForSlabsIsRefusedForTheCheckBeforeWork) {
    const Outcome refused = run("mesh -r 256 --max-memory 120M --largest-only -o '" + path("big.stl") + "'");
    EXPECT_EQ(refused.exitCode, 2) << refused.err;
    EXPECT_NE(refused.err.find("needs the mesh in one piece"), std::string::npos) << refused.err;
    EXPECT_TRUE(files().empty());
    const Outcome bad = run(kBall + "--min-wall -1 -o '" + path("ball.stl") + "'");
    EXPECT_EQ(bad.exitCode, 2) << bad.err;
    EXPECT_NE(bad.err.find("--min-wall"), std::string::npos) << bad.err;
    EXPECT_TRUE(files().empty());
}

}  // namespace
