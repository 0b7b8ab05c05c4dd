// Tiled bakes (tiles.hpp): tiles merged equal the one-piece bake voxel for voxel (every grid a
// bake can hold: surface, density, color, trap, iterations; values bit for bit, active states,
// the inside and outside beyond the band), on leaf-aligned and unaligned tilings, for band
// widths 1, 3 and 6, colour depths from the band to 12 voxels below it, and a crop of the
// 512^3 bake across its seam, where a too small halo showed first (tiles_long_test.cpp: whole
// bakes of 384^3 to 576^3, crops of 1024^3 and 2048^3); each tile keeps only its box; the
// merge refuses tiles that do not belong together or do not cover the box once.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <openvdb/openvdb.h>

#include "dqjulia/bake.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/tiles.hpp"
#include "dqjulia/version.h"
#include "tile_merge_check.hpp"

namespace fs = std::filesystem;
using namespace dqj;
using dqj::test::readVdb;
using dqj::test::Tiles;
using dqj::test::VdbFile;

namespace {

struct Case {
    const char* name;
    int resolution;
    double band;
    const char* tiling;
    bool dual;
    double colorDepth;  // 0: no attribute grids; else color, trap and iterations too, this deep
    int crop = 0;       // else a 128^3 crop of the default bake at crop^3 (voxel size, seam, depth)
};

class TilesMerge : public Tiles, public ::testing::WithParamInterface<Case> {};

TEST_P(TilesMerge, EqualTheOnePieceBakeVoxelForVoxel) {
    const Case& c = GetParam();
    Params params;
    params.bake.resolution = c.resolution;
    params.bake.bandWidth = c.band;
    params.bake.grids = {BakeGrid::Surface, BakeGrid::Density};
    if (c.colorDepth > 0.0) {
        params.bake.grids.insert(params.bake.grids.end(), {BakeGrid::Color, BakeGrid::Trap, BakeGrid::Iterations});
        params.bake.colorDepth = c.colorDepth;
    }
    if (c.crop) dqj::test::cropOf(params, c.crop, openvdb::Coord(128));
    if (c.dual) {
        params.fractal.variant = Variant::Dual;
        params.fractal.c = toDualQuat({-0.2, 0.6, 0.2, 0.0, 0.0, 0.0, 0.0, 0.0});
        params.fractal.iterations = 12;
    }
    dqj::test::checkMergeEqualsWhole(*this, params, c.tiling, c.name);
}

// The default bake's index box at 64^3 is 69 voxels a side from -34: halves split at 0 (on a
// leaf boundary), thirds at -11 and 12 (not); at 128^3, 133 voxels from -66, thirds at -22, 22.
// Colour depths (voxels; the region reaches as many 26-neighbour steps below the band, sqrt 3
// times as deep along the diagonals) and halos (tileHalo: level set + the seeds' rounds + that
// reach): 0.05 at 64^3 is 4 (halo 25), 0.08 at 160^3 with band 1 13 (54), 0.06 at 160^3 with
// band 6 10 (48), 0.05 at 128^3 7 (34) and at 200^3 10 (43); seam512 is a crop of the 512^3 bake
// across its 2x1x1 seam, where the colour first differed (11 voxels, halo 46; the 1024^3 crops
// and the whole 512^3 bake are in tiles_long_test.cpp). Each tile's window ends inside the box.
INSTANTIATE_TEST_SUITE_P(
    Tilings, TilesMerge,
    ::testing::Values(Case{"aligned", 64, 3.0, "2x2x2", false, 0.05}, Case{"unaligned", 64, 3.0, "3x2x1", false, 0.05},
                      Case{"band1", 64, 1.0, "3x1x1", false, 0.0}, Case{"band6", 64, 6.0, "1x3x1", false, 0.0},
                      Case{"dual", 64, 3.0, "1x1x3", true, 0.0}, Case{"r128", 128, 3.0, "3x1x1", false, 0.0},
                      Case{"deepBand1", 160, 1.0, "2x2x1", false, 0.08},
                      Case{"deepBand6", 160, 6.0, "3x1x1", false, 0.06},
                      Case{"deepDual", 128, 3.0, "1x2x2", true, 0.05}, Case{"r200", 200, 3.0, "1x1x2", false, 0.05},
                      Case{"seam512", 128, 3.0, "2x1x1", false, 0.02, 512}),
    [](const auto& info) { return std::string(info.param.name); });

TEST_F(Tiles, EachTileKeepsOnlyItsBoxAndSaysWhichItIs) {
    Params params;
    params.bake.resolution = 48;
    const std::vector<std::string> tiles = bakeTiles(params, "2x1x1");
    const VdbFile first = readVdb(tiles[0]), second = readVdb(tiles[1]);
    EXPECT_EQ(first.metadata->metaValue<std::string>("dqjulia_tiling"), "2x1x1");
    EXPECT_EQ(second.metadata->metaValue<openvdb::Int32>("dqjulia_tile"), 2);
    EXPECT_EQ(first.metadata->metaValue<std::string>("dqjulia_version"), DQJ_VERSION_STRING);
    EXPECT_EQ(first.metadata->metaValue<std::string>("dqjulia_parameters_hash").size(), 16u);
    const openvdb::Vec3i fullMin = first.metadata->metaValue<openvdb::Vec3i>("dqjulia_full_min");
    const openvdb::Vec3i firstMax = first.metadata->metaValue<openvdb::Vec3i>("dqjulia_tile_max");
    const openvdb::Vec3i secondMin = second.metadata->metaValue<openvdb::Vec3i>("dqjulia_tile_min");
    EXPECT_EQ(secondMin.x(), firstMax.x() + 1);
    EXPECT_EQ(secondMin.y(), fullMin.y());
    // Tiles hold the surface (and no density: the merge makes it); tile 1's voxels lie at or
    // below its last x, tile 2's above.
    EXPECT_EQ(first.grids.count("density"), 0u);
    auto a = openvdb::gridPtrCast<openvdb::FloatGrid>(first.grids.at("surface"));
    auto b = openvdb::gridPtrCast<openvdb::FloatGrid>(second.grids.at("surface"));
    ASSERT_TRUE(a && b);
    EXPECT_GT(a->activeVoxelCount(), 100u);
    EXPECT_GT(b->activeVoxelCount(), 100u);
    EXPECT_LE(a->evalActiveVoxelBoundingBox().max().x(), firstMax.x());
    EXPECT_GE(b->evalActiveVoxelBoundingBox().min().x(), secondMin.x());
}

TEST_F(Tiles, TheMergeRefusesTilesThatDoNotBelongTogether) {
    Params params;
    params.bake.resolution = 40;
    const std::vector<std::string> tiles = bakeTiles(params, "2x1x1");
    auto refused = [&](const std::vector<std::string>& files, const std::string& message) {
        try {
            mergeTiles(files, path("merged.vdb"));
            ADD_FAILURE() << "merged, expected: " << message;
        } catch (const ParamError& error) {
            EXPECT_NE(std::string(error.what()).find(message), std::string::npos) << error.what();
        }
        EXPECT_FALSE(fs::exists(path("merged.vdb")));
    };
    refused({tiles[0]}, "1 of the 2 tiles of 2x1x1 are missing: 2");
    refused({tiles[0], tiles[0], tiles[1]}, "are both tile 1 of 2x1x1");
    refused({}, "no tiles to merge");
    // Another bake's tile: other parameters.
    params.fractal.iterations = 9;
    BakeOptions options;
    options.tile = parseTiling("2x1x1");
    options.tile->index = 2;
    bakeVdb(params, path("other.tile_2.vdb"), options);
    refused({tiles[0], path("other.tile_2.vdb")}, "is not a tile of the same bake");
    // A whole bake is not a tile.
    bakeVdb(params, path("plain.vdb"));
    refused({path("plain.vdb")}, "is not a tile of a dqjulia bake");
    // Tilings that do not fit are refused before any work.
    for (const std::string& text : {"2x2", "0x1x1", "1x1x300", "2x2x2x2", "ax1x1", ""})
        EXPECT_THROW(parseTiling(text), ParamError) << text;
    options.tile = parseTiling("6x1x1");  // 44 voxels along x: at most 5 tiles of 8
    EXPECT_THROW(bakeVdb(params, path("x.vdb"), options), ParamError);
    options.tile = parseTiling("2x1x1");
    options.tile->index = 3;
    EXPECT_THROW(bakeVdb(params, path("x.vdb"), options), ParamError);
    EXPECT_FALSE(fs::exists(path("x.vdb")));
    EXPECT_EQ(tilePath("out/a.vdb", 3), "out/a.tile_3.vdb");
    EXPECT_EQ(tilePath("out.d/a", 12), "out.d/a.tile_12");
}

}  // namespace
