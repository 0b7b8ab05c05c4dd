// The dqjulia command run as a user runs it: results on stdout and in files, clear errors
// with a non-zero exit for bad input, and nothing written when it fails.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "dqjulia/dqjulia.h"
#include "dqjulia/empty_result.hpp"
#include "dqjulia/image.hpp"
#include "dqjulia/inspect.hpp"
#include "dqjulia/param_file.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

using dqj::test::readFile;

namespace {

using Outcome = dqj::test::CommandResult;

class Cli : public dqj::test::ScratchFolder {
protected:
    /// Runs `dqjulia <arguments>` with `input` on stdin.
    Outcome run(const std::string& arguments, const std::string& input = "") {
        return dqj::test::runCommand(DQJ_CLI, arguments, dir_, input);
    }
};

std::vector<std::vector<std::string>> csvRows(const std::string& text) {
    std::vector<std::vector<std::string>> rows;
    std::istringstream lines(text);
    std::string line;
    while (std::getline(lines, line)) {
        std::vector<std::string> cells;
        std::istringstream fields(line);
        std::string cell;
        while (std::getline(fields, cell, ',')) cells.push_back(cell);
        rows.push_back(cells);
    }
    return rows;
}

TEST_F(Cli, HelpListsSubcommands) {
    const Outcome result = run("--help");
    EXPECT_EQ(result.exitCode, 0);
    for (const char* name : {"render", "eval", "inspect"}) EXPECT_NE(result.out.find(name), std::string::npos) << name;
    for (const char* sub : {"render --help", "eval --help", "inspect --help"}) EXPECT_EQ(run(sub).exitCode, 0) << sub;
}

TEST_F(Cli, EvalMatchesReferenceValues) {
    // c1, rows "c1,1" and "c1,3" of the reference vectors, paper and dual variants.
    const std::string c1 = "--c -0.10 0.8 -0.26 0.15 -0.23 -0.38 -0.86 0.64 -n 15 --bailout 4";
    const std::string points = "0.3 0.2 0.1 0 0 0 0 0\n# a comment\n\n1,0,0,0, 0,0.05,0,0\n";
    Outcome paper = run("eval --variant paper " + c1, points);
    ASSERT_EQ(paper.exitCode, 0) << paper.err;
    auto rows = csvRows(paper.out);
    ASSERT_EQ(rows.size(), 3u) << paper.out;
    EXPECT_EQ(rows[0], (std::vector<std::string>{"n", "r", "ra", "rb", "de"}));
    EXPECT_EQ(rows[1][0], "6");
    EXPECT_EQ(rows[1][4], "inf");
    EXPECT_EQ(rows[2][0], "3");
    EXPECT_NEAR(std::stod(rows[2][4]), 0.21884361698100624, 1e-12);

    Outcome dual = run("eval --variant dual " + c1, points);
    ASSERT_EQ(dual.exitCode, 0) << dual.err;
    rows = csvRows(dual.out);
    EXPECT_EQ(rows[1][0], "14");
    EXPECT_NEAR(std::stod(rows[1][4]), 0.004513454803138481, 1e-14);
    EXPECT_NEAR(std::stod(rows[1][3]), 250.4132804916606, 1e-9);
}

TEST_F(Cli, EvalSliceCoordsGoThroughTheSlice) {
    // The slice a.i,a.j,a.s maps (x, y, z) to (z, x, y, 0 | 0).
    const Outcome mapped = run("eval --slice a.i,a.j,a.s --slice-coords", "0.2 0.1 0.3\n");
    const Outcome direct = run("eval", "0.3 0.2 0.1 0 0 0 0 0\n");
    ASSERT_EQ(mapped.exitCode, 0) << mapped.err;
    EXPECT_EQ(mapped.out, direct.out);
}

TEST_F(Cli, EvalRejectsBadLines) {
    const Outcome result = run("eval", "0.1 0.2 0.3\n");
    EXPECT_EQ(result.exitCode, 2);
    EXPECT_NE(result.err.find("line 1: expected 8 numbers"), std::string::npos) << result.err;
    EXPECT_NE(run("eval", "0 0 0 0 0 0 0 x\n").err.find("expected 8 numbers"), std::string::npos);
}

TEST_F(Cli, InspectExplainsThePapersFirstConstant) {
    const Outcome result = run("inspect --c -0.10 0.8 -0.26 0.15 -0.23 -0.38 -0.86 0.64 --variant paper -n 15");
    ASSERT_EQ(result.exitCode, 0) << result.err;
    EXPECT_NE(result.out.find("OUTSIDE the Mandelbrot set"), std::string::npos) << result.out;
    EXPECT_NE(result.out.find("empty for N >= 6"), std::string::npos) << result.out;
    // At N = 5 the orbit of b = 0 has not escaped yet: the slice is not empty.
    const Outcome five = run("inspect --c -0.10 0.8 -0.26 0.15 -0.23 -0.38 -0.86 0.64 --variant paper -n 5 --json");
    ASSERT_EQ(five.exitCode, 0) << five.err;
    EXPECT_NE(five.out.find("\"empty\": false"), std::string::npos) << five.out;
}

TEST_F(Cli, RenderWritesAPictureOfTheDefaultFractal) {
    const std::string out = path("default.png");
    const Outcome result = run("render -q -W 160 -H 120 -o '" + out + "'");
    ASSERT_EQ(result.exitCode, 0) << result.err;
    const dqj::Image image = dqj::readPng(out);
    ASSERT_EQ(image.width, 160);
    ASSERT_EQ(image.height, 120);
    // The fractal covers the middle of the frame and differs from the background there.
    const float* centre = &image.rgba[(60 * 160 + 80) * 4];
    const float* corner = &image.rgba[0];
    EXPECT_GT(std::abs(centre[0] - corner[0]) + std::abs(centre[1] - corner[1]) + std::abs(centre[2] - corner[2]),
              0.05f);
}

TEST_F(Cli, RenderOfAnEmptySliceSaysWhy) {
    const std::string out = path("empty.png");
    const Outcome result =
        run("render -q -W 32 -H 24 --c -0.10 0.8 -0.26 0.15 -0.23 -0.38 -0.86 0.64 --variant paper -o '" + out + "'");
    EXPECT_EQ(result.exitCode, 0) << result.err;
    EXPECT_NE(result.err.find("no surface"), std::string::npos) << result.err;
    EXPECT_NE(result.err.find("outside the Mandelbrot set"), std::string::npos) << result.err;
}

// One wording of an empty result (issue 37): the four commands and the C ABI say that their result
// is empty and why in emptyResultMessage's sentence, each of its kind, with the one reason
// inspect() proves for the parameters (the paper's first "test2" constant, whose slice holds the
// escaping dual part fixed; a box of it that the bake finds empty too).
TEST_F(Cli, EveryCommandAndTheCAbiWordAnEmptyResultAlike) {
    const std::string file = write("empty.json", R"({
      "fractal": {"c": [-0.10, 0.8, -0.26, 0.15, -0.23, -0.38, -0.86, 0.64], "variant": "paper", "iterations": 8},
      "bake": {"resolution": 40, "bounds": {"min": [-1, -1, -1], "max": [0.5, 0.5, 0.5]}}})");
    const std::string reason = dqj::provenEmptyReason(dqj::loadParams(file));
    ASSERT_NE(reason.find("the slice is empty for N >= 6"), std::string::npos) << reason;
    EXPECT_EQ(dqj::inspect(dqj::loadParams(file)).emptyReason, reason);

    struct Case {
        std::string command, output;
        dqj::EmptyResult kind;
        bool named;  // the message names the file (bakes and meshes write one a frame)
    };
    for (const Case& item : {Case{"render -W 32 -H 24", "empty.png", dqj::EmptyResult::Render, false},
                             Case{"bake", "empty.vdb", dqj::EmptyResult::Bake, true},
                             Case{"mesh", "empty.ply", dqj::EmptyResult::Mesh, true},
                             Case{"povray", "empty.pov", dqj::EmptyResult::Povray, false}}) {
        const Outcome result = run(item.command + " -q -p '" + file + "' -o '" + path(item.output) + "'");
        EXPECT_EQ(result.exitCode, 0) << item.command << ": " << result.err;
        const std::string name = item.command.substr(0, item.command.find(' '));
        const std::string expected =
            "dqjulia " + name +
            ": warning: " + dqj::emptyResultMessage(item.kind, reason, item.named ? path(item.output) : "") + "\n";
        EXPECT_EQ(result.err, expected) << item.command;  // said once, in the one wording
    }

    dqj_context context = nullptr;
    ASSERT_EQ(dqj_context_create(&context), DQJ_OK);
    ASSERT_EQ(dqj_context_load_params_file(context, file.c_str()), DQJ_OK) << dqj_context_error(context);
    std::vector<uint8_t> pixels(32 * 24 * 4);
    ASSERT_EQ(dqj_render_rgba8(context, pixels.data(), 32, 24, 32 * 4, nullptr, nullptr), DQJ_OK);
    EXPECT_EQ(std::string(dqj_context_warning(context)), dqj::emptyResultMessage(dqj::EmptyResult::Render, reason));
    ASSERT_EQ(dqj_bake_vdb(context, path("abi.vdb").c_str(), nullptr, nullptr), DQJ_OK) << dqj_context_error(context);
    EXPECT_EQ(std::string(dqj_context_warning(context)), dqj::emptyResultMessage(dqj::EmptyResult::Bake, reason));
    ASSERT_EQ(dqj_mesh_compute(context, nullptr, nullptr), DQJ_OK) << dqj_context_error(context);
    EXPECT_EQ(std::string(dqj_context_warning(context)), dqj::emptyResultMessage(dqj::EmptyResult::Mesh, reason));
    dqj_context_destroy(context);

    // Without a known reason, each kind says what to try.
    EXPECT_NE(dqj::emptyResultMessage(dqj::EmptyResult::Render, "").find("larger detail"), std::string::npos);
    EXPECT_NE(dqj::emptyResultMessage(dqj::EmptyResult::Bake, "").find("higher resolution"), std::string::npos);
}

TEST_F(Cli, ParameterFileAndFlagOverrides) {
    const std::string file =
        write("p.json", R"({"fractal": {"iterations": 7, "variant": "dual"}, "render": {"width": 40, "height": 30}})");
    const std::string saved = path("saved.json");
    const Outcome result =
        run("render -q -p '" + file + "' -n 9 -o '" + path("o.png") + "' --save-params '" + saved + "'");
    ASSERT_EQ(result.exitCode, 0) << result.err;
    const std::string text = readFile(saved);
    EXPECT_NE(text.find("\"iterations\": 9"), std::string::npos) << text;      // flag wins
    EXPECT_NE(text.find("\"variant\": \"dual\""), std::string::npos) << text;  // file kept
    EXPECT_EQ(dqj::readPng(path("o.png")).width, 40);
}

struct BadInput {
    std::string arguments;
    std::string file;     // parameter file contents, if any (passed with -p)
    std::string message;  // expected in stderr
};

TEST_F(Cli, BadInputGetsOneClearMessageAndWritesNothing) {
    const std::vector<BadInput> cases = {
        {"render -n 0", "", "fractal.iterations"},
        {"render --bailout 1.1", "", "containment radius"},
        {"render --variant quaternion", "", "--variant"},
        {"render --slice a.s,a.s,a.j", "", "named twice"},
        {"render --slice a.s,a.x,a.j", "", "unknown axis \"a.x\""},
        {"render --rotate a.j,b.s", "", "PLANE:DEGREES"},
        {"render --c 1 2 3", "", "--c"},
        {"render --normals analytic --variant paper", "", "need variant \"dual\""},
        {"render", R"({"fractal": {"iteratons": 5}})", "did you mean \"iterations\""},
        {"render", "{\"fractal\": {\n  \"iterations\": 5,\n}", "line 3"},
        {"render", R"({"fractal": {"c": [1, 2, 3]}})", "fractal.c: must be an array of 8 numbers"},
        {"render", R"({"render": {"width": -4}})", "render.width"},
        {"render", R"({"render": {"step_factor": 2}})", "render.step_factor"},
        {"render", R"({"camera": {"direction": [0, 1, 0]}})", "camera.up"},
        {"render", R"({"slice": {"axes": [[1,0,0,0,0,0,0,0],[2,0,0,0,0,0,0,0],[0,0,1,0,0,0,0,0]]}})", "parallel"},
        {"render -o " + std::string("out.jpg"), "", "must end in .png or .exr"},
        {"render -p /no/such/file.json", "", "/no/such/file.json"},
    };
    for (const BadInput& bad : cases) {
        std::string arguments = bad.arguments;
        if (!bad.file.empty()) arguments += " -p '" + write("bad.json", bad.file) + "'";
        const std::string out = path("never.png");
        if (arguments.find(" -o ") == std::string::npos) arguments += " -o '" + out + "'";
        const Outcome result = run(arguments);
        EXPECT_EQ(result.exitCode, 2) << arguments << "\n" << result.err;
        EXPECT_NE(result.err.find(bad.message), std::string::npos) << arguments << "\nstderr: " << result.err;
        EXPECT_FALSE(fs::exists(out)) << arguments;
    }
}

TEST_F(Cli, UnwritableOutputFailsBeforeWorkWithoutPartialFiles) {
    const Outcome result = run("render -q -W 16 -H 12 -o '" + path("missing/dir/x.png") + "'");
    EXPECT_EQ(result.exitCode, 2);
    EXPECT_NE(result.err.find("the folder '" + path("missing/dir") + "' does not exist"), std::string::npos)
        << result.err;
    EXPECT_FALSE(fs::exists(path("missing")));
    // An existing image is left intact when a render into it fails validation.
    const std::string existing = write("keep.png", "precious");
    EXPECT_EQ(run("render -n 0 -o '" + existing + "'").exitCode, 2);
    EXPECT_EQ(readFile(existing), "precious");
}

TEST_F(Cli, ExistingOutputIsRefusedUnlessForced) {
    const std::string existing = write("keep.png", "precious");
    const Outcome refused = run("render -q -W 16 -H 12 -o '" + existing + "'");
    EXPECT_EQ(refused.exitCode, 2);
    EXPECT_NE(refused.err.find("exists; pass --force to overwrite it"), std::string::npos) << refused.err;
    EXPECT_EQ(readFile(existing), "precious");
    const Outcome forced = run("render -q -W 16 -H 12 --force -o '" + existing + "'");
    EXPECT_EQ(forced.exitCode, 0) << forced.err;
    EXPECT_EQ(dqj::readPng(existing).width, 16);
}

TEST_F(Cli, ExamplesAreValidParameterFiles) {
    int count = 0;
    for (const auto& entry : fs::directory_iterator(DQJ_EXAMPLES)) {
        if (entry.path().extension() != ".json") continue;
        ++count;
        const Outcome result = run("inspect --samples 8 -p '" + entry.path().string() + "'");
        EXPECT_EQ(result.exitCode, 0) << entry.path() << "\n" << result.err;
    }
    EXPECT_GE(count, 10);
}

}  // namespace
