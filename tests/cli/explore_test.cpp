// dqjulia explore and sheet: reproducible constants with non-empty slices, labelled sheets.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <bit>
#include <cstdint>
#include <sstream>

#include "contact_sheet.hpp"
#include "dqjulia/inspect.hpp"
#include "dqjulia/params.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

using dqj::test::readFile;

namespace {

int runCli(const std::string& arguments) {
    const int status = std::system((std::string("'") + DQJ_CLI + "' " + arguments + " 2>/dev/null").c_str());
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

fs::path scratch(const std::string& name) {
    const fs::path dir = fs::temp_directory_path() / ("dqjulia_explore_" + std::to_string(::getpid()) + "_" + name);
    fs::remove_all(dir);
    return dir;
}

TEST(Explore, SameSeedSameConstantsAndEveryTileIsNonEmpty) {
    const fs::path first = scratch("first"), second = scratch("second");
    ASSERT_EQ(runCli("explore -q --seed 11 --count 4 --columns 2 --tile-width 64 --tile-height 48 -o '" +
                     first.string() + "'"),
              0);
    ASSERT_EQ(runCli("explore -q --seed 11 --count 4 --columns 2 --tile-width 64 --tile-height 48 -o '" +
                     second.string() + "'"),
              0);
    for (int tile = 1; tile <= 4; ++tile) {
        const std::string name = "tile_0" + std::to_string(tile);
        const std::string json = readFile(first / (name + ".json"));
        // The tile's parameter file is complete, the same for the same seed but for the folder
        // its picture went to, and its slice is not empty.
        const dqj::Params params = dqj::parseParams(json, name);
        dqj::Params again = dqj::parseParams(readFile(second / (name + ".json")), name);
        again.output.path = params.output.path;
        EXPECT_EQ(dqj::toJson(params), dqj::toJson(again)) << name;
        const dqj::InspectReport report = dqj::inspect(params, 16);
        EXPECT_TRUE(report.emptyReason.empty()) << name << ": " << report.emptyReason;
        EXPECT_GT(report.insideFraction, 0.0) << name;
        EXPECT_EQ(dqj::readPng(first / (name + ".png")).width, 64);
    }
    EXPECT_FALSE(fs::exists(first / "tile_05.json"));
    // A different seed gives different constants.
    const fs::path other = scratch("other");
    ASSERT_EQ(runCli("explore -q --seed 12 --count 1 --tile-width 32 --tile-height 24 -o '" + other.string() + "'"), 0);
    EXPECT_NE(dqj::parseParams(readFile(other / "tile_01.json")).fractal.c.a,
              dqj::parseParams(readFile(first / "tile_01.json")).fractal.c.a);
    // Two columns of 64 px plus padding; the sheet exists once and is refused the second time.
    const dqj::Image sheet = dqj::readPng((first / "sheet.png").string());
    EXPECT_EQ(sheet.width, 8 + 2 * (64 + 8));
    EXPECT_EQ(runCli("explore -q --seed 11 --count 1 -o '" + first.string() + "'"), 2);
    for (const fs::path& dir : {first, second, other}) fs::remove_all(dir);
}

/// A parameter file in `dir` (made) with `json`.
fs::path writeParams(const fs::path& dir, const std::string& json) {
    fs::create_directories(dir);
    fs::path path = dir / "start.json";
    std::ofstream(path) << json;
    return path;
}

TEST(ExploreAround, WritesTheSheetAndEveryTilesCompleteDocumentTheSameForTheSameSeed) {
    const fs::path input = scratch("around_input");
    const fs::path start = writeParams(input, R"({"description": "start", "render": {"width": 320, "height": 200}})");
    const fs::path first = scratch("around_first"), second = scratch("around_second");
    const std::string arguments = "explore -q --around '" + start.string() +
                                  "' --seed 4 --strength small --lock a,variant --tile-width 40 --tile-height 32 -o '";
    ASSERT_EQ(runCli(arguments + first.string() + "'"), 0);
    ASSERT_EQ(runCli(arguments + second.string() + "'"), 0);
    const dqj::Params original = dqj::loadParams(start.string());
    for (int tile = 1; tile <= 9; ++tile) {  // a 3 x 3 grid by default
        const std::string name = "tile_0" + std::to_string(tile);
        const dqj::Params params = dqj::parseParams(readFile(first / (name + ".json")), name);
        dqj::Params again = dqj::parseParams(readFile(second / (name + ".json")), name);
        again.output.path = params.output.path;  // the folders differ
        EXPECT_EQ(dqj::toJson(params), dqj::toJson(again)) << name;
        // A complete, valid, non-empty document at the original's size, its own picture's name
        // beside the tile, the locked part as it was.
        EXPECT_TRUE(dqj::inspect(params, 16).emptyReason.empty()) << name;
        EXPECT_EQ(params.render.width, 320);
        EXPECT_EQ(params.output.path, (first / (name + "_render.png")).string());
        for (int k = 0; k < 4; ++k)  // bit for bit
            EXPECT_EQ(std::bit_cast<std::uint64_t>(dqj::component(params.fractal.c.a, k)),
                      std::bit_cast<std::uint64_t>(dqj::component(original.fractal.c.a, k)))
                << name;
        EXPECT_NE(params.description.find("Variation " + std::to_string(tile) + " (seed 4, strength small"),
                  std::string::npos)
            << params.description;
        EXPECT_EQ(dqj::readPng(first / (name + ".png")).width, 40);
    }
    EXPECT_FALSE(fs::exists(first / "tile_10.json"));
    EXPECT_EQ(dqj::readPng((first / "sheet.png").string()).width, 8 + 3 * (40 + 8));
    // A pick goes straight on: rendered as it is (here smaller), and varied again.
    EXPECT_EQ(runCli("render -q -p '" + (first / "tile_05.json").string() + "' -W 32 -H 24"), 0);
    EXPECT_EQ(dqj::readPng(first / "tile_05_render.png").width, 32);
    const fs::path third = scratch("around_third");
    EXPECT_EQ(runCli("explore -q --around '" + (first / "tile_05.json").string() +
                     "' --count 2 --tile-width 24 --tile-height 24 -o '" + third.string() + "'"),
              0);
    EXPECT_EQ(dqj::loadParams((third / "tile_01.json").string()).description.rfind("Variation 1 (seed 1", 0), 0u);
    for (const fs::path& dir : {input, first, second, third}) fs::remove_all(dir);
}

TEST(ExploreAround, BadSettingsAndAnEmptyStartExitTwoAndWriteNothing) {
    const fs::path input = scratch("around_bad");
    const fs::path start = writeParams(input, "{}");
    const fs::path empty = input / "empty.json";
    std::ofstream(empty) << R"({"fractal": {"c": [-0.10, 0.8, -0.26, 0.15, -0.23, -0.38, -0.86, 0.64]}})";
    const fs::path out = input / "out";
    const std::string around = "explore -q --around '" + start.string() + "' -o '" + out.string() + "' ";
    for (const std::string& bad : {around + "--strength 1.5", around + "--strength enormous", around + "--strength 0",
                                   around + "--lock a,b,slice,iterations,variant", around + "--lock colour",
                                   "explore -q --strength tiny -o '" + out.string() + "'",
                                   "explore -q --around '" + empty.string() + "' -o '" + out.string() + "'",
                                   around + "--params '" + start.string() + "'"}) {
        EXPECT_EQ(runCli(bad), 2) << bad;
        EXPECT_FALSE(fs::exists(out)) << bad;
    }
    // The messages say what to do.
    const std::string log = (input / "log.txt").string();
    std::system(("'" + std::string(DQJ_CLI) + "' explore -q --around '" + empty.string() + "' -o '" + out.string() +
                 "' 2> '" + log + "'")
                    .c_str());
    EXPECT_NE(readFile(log).find("starting document is itself empty"), std::string::npos) << readFile(log);
    std::system(("'" + std::string(DQJ_CLI) + "' " + around + "--strength 3 2> '" + log + "'").c_str());
    EXPECT_NE(readFile(log).find("out of range: give 0.01 to 1 or tiny"), std::string::npos) << readFile(log);
    // An existing sheet is refused before the work, without --force; nothing else is written.
    fs::create_directories(out);
    std::ofstream(out / "sheet.png") << "mine";
    EXPECT_EQ(runCli(around + "--count 2"), 2);
    EXPECT_EQ(readFile(out / "sheet.png"), "mine");
    EXPECT_FALSE(fs::exists(out / "tile_01.json"));
    EXPECT_EQ(runCli(around + "--count 2 --tile-width 16 --tile-height 16 --force"), 0);
    EXPECT_TRUE(fs::exists(out / "tile_02.json"));
    fs::remove_all(input);
}

TEST(ContactSheet, LaysOutTilesAndDrawsLabels) {
    if (dqj::labelFontPath().empty()) GTEST_SKIP() << "no label font installed";
    auto tile = [](float value) {
        dqj::Image image;
        image.width = 40;
        image.height = 30;
        image.rgba.assign(4 * 40 * 30, value);
        return image;
    };
    dqj::SheetLayout layout;
    layout.columns = 2;
    const dqj::Image sheet =
        dqj::composeSheet({{tile(1.0f), "first"}, {tile(0.5f), "second\nline"}, {tile(0.25f), ""}}, layout);
    const int labelHeight = layout.labelLines * (layout.fontPixels + layout.fontPixels / 3) + layout.padding / 2;
    EXPECT_EQ(sheet.width, 8 + 2 * (40 + 8));
    EXPECT_EQ(sheet.height, 8 + 2 * (30 + labelHeight + 8));
    // Tiles land in their cells.
    EXPECT_EQ(sheet.rgba[4 * (10 * sheet.width + 10)], 1.0f);
    EXPECT_EQ(sheet.rgba[4 * (10 * sheet.width + 8 + 48 + 10)], 0.5f);
    // The first label strip has text (bright pixels on the dark background); the third has none.
    auto brightIn = [&](int x0, int y0) {
        int bright = 0;
        for (int y = y0; y < y0 + labelHeight; ++y)
            for (int x = x0; x < x0 + 40; ++x) bright += sheet.rgba[4 * (std::size_t(y) * sheet.width + x)] > 0.3f;
        return bright;
    };
    EXPECT_GT(brightIn(8, 8 + 30), 10);
    EXPECT_EQ(brightIn(8, 8 + 30 + labelHeight + 8 + 30), 0);
    EXPECT_THROW(dqj::composeSheet({}, layout), std::runtime_error);
}

}  // namespace

namespace {

TEST(PaperFigures, ReproduceScriptWritesEveryFigureAndExplainsTheEmptyTile) {
    const fs::path out = scratch("paper");
    const std::string command = std::string("'") + DQJ_EXAMPLES + "/reproduce_paper.py' --small --dqjulia '" + DQJ_CLI +
                                "' --out '" + out.string() + "' > '" + (out.string() + ".log") + "' 2>&1";
    fs::create_directories(out);
    ASSERT_EQ(std::system(command.c_str()), 0) << readFile(out.string() + ".log");
    for (const char* name : {"detail.png", "test2.png", "highres.png", "highres2.png", "voxels.png", "sheet.png"})
        EXPECT_TRUE(fs::exists(out / name)) << name;
    // Tile 1 of test2 is empty under the paper's rule: background only, and its label says why
    // (the log shows the label passed to the sheet).
    auto surfacePixels = [](const dqj::Image& image) {
        int count = 0;
        for (int y = 0; y < image.height; ++y) {
            const float* left = &image.rgba[4 * std::size_t(y) * image.width];  // background gradient: rows are uniform
            for (int x = 0; x < image.width; ++x)
                count += std::abs(image.rgba[4 * (std::size_t(y) * image.width + x)] - left[0]) > 0.02f;
        }
        return count;
    };
    EXPECT_EQ(surfacePixels(dqj::readPng((out / "test2_1.png").string())), 0);
    EXPECT_GT(surfacePixels(dqj::readPng((out / "test2_2.png").string())), 500);
    EXPECT_NE(readFile(out.string() + ".log").find("EMPTY under the paper's rule: the dual part"), std::string::npos);
    // Both voxel bakes show the object.
    EXPECT_GT(surfacePixels(dqj::readPng((out / "voxels_50.png").string())), 500);
    EXPECT_GT(surfacePixels(dqj::readPng((out / "voxels_100.png").string())), 500);
    fs::remove_all(out);
    fs::remove(out.string() + ".log");
}

}  // namespace
