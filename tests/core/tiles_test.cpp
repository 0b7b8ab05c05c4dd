// Tiled bakes (tiles.hpp): tiles merged equal the one-piece bake voxel for voxel (every grid,
// values bit for bit, active states, the inside and outside beyond the band), on leaf-aligned
// and unaligned tilings and for band widths 1, 3 and 6; each tile keeps only its box; the merge
// refuses tiles that do not belong together or do not cover the box once.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdint>
#include <cmath>
#include <filesystem>
#include <map>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "dqjulia/bake.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/tiles.hpp"
#include "dqjulia/version.h"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace dqj;

namespace {

class Tiles : public ::testing::Test {
protected:
    static void SetUpTestSuite() { openvdb::initialize(); }
    void SetUp() override { dir_ = dqj::test::freshTestFolder("dqjulia_tiles"); }
    void TearDown() override { fs::remove_all(dir_); }
    std::string path(const std::string& name) const { return (dir_ / name).string(); }

    /// Bakes every tile of `tiling` beside "whole.vdb" and returns their paths.
    std::vector<std::string> bakeTiles(const Params& params, const std::string& tiling) {
        Tile tile = parseTiling(tiling);
        std::vector<std::string> paths;
        for (tile.index = 1; tile.index <= tileCount(tile); ++tile.index) {
            BakeOptions options;
            options.tile = tile;
            paths.push_back(tilePath(path("whole.vdb"), tile.index));
            bakeVdb(params, paths.back(), options);
        }
        return paths;
    }
    fs::path dir_;
};

struct VdbFile {
    std::map<std::string, openvdb::GridBase::Ptr> grids;
    openvdb::MetaMap::Ptr metadata;
};

VdbFile readVdb(const std::string& path) {
    openvdb::io::File file(path);
    file.open();
    VdbFile result;
    const openvdb::GridPtrVecPtr grids = file.getGrids();
    for (const openvdb::GridBase::Ptr& grid : *grids) result.grids[grid->getName()] = grid;
    result.metadata = file.getMetadata();
    file.close();
    return result;
}

/// Voxels compared and those that differ (value bits or active state) between two grids of
/// one type, over the bounding box of both grids' active voxels grown by 2 voxels.
struct Comparison {
    std::uint64_t voxels = 0;
    std::uint64_t differences = 0;
    std::uint64_t active = 0;
    std::uint64_t stateDiffers = 0;  // active in one grid only
    double largest = 0.0;            // the largest value difference where both are active
};

double distance(float u, float v) { return std::abs(double(u) - double(v)); }
double distance(const openvdb::Vec3s& u, const openvdb::Vec3s& v) { return double((u - v).length()); }
/// Bit for bit, so that -0 and 0 (or two NaNs) are told apart.
bool sameBits(float a, float b) { return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b); }
bool sameBits(const openvdb::Vec3s& a, const openvdb::Vec3s& b) {
    return sameBits(a.x(), b.x()) && sameBits(a.y(), b.y()) && sameBits(a.z(), b.z());
}

template <typename GridT>
Comparison compareGrids(const GridT& a, const GridT& b) {
    openvdb::CoordBBox box = a.evalActiveVoxelBoundingBox();
    box.expand(b.evalActiveVoxelBoundingBox());
    box.expand(2);
    auto x = a.getConstAccessor();
    auto y = b.getConstAccessor();
    Comparison result;
    for (auto ijk = box.begin(); ijk; ++ijk) {
        const auto u = x.getValue(*ijk), v = y.getValue(*ijk);
        const bool on = x.isValueOn(*ijk);
        ++result.voxels;
        result.active += on;
        if (on != y.isValueOn(*ijk) || !sameBits(u, v)) {
            ++result.differences;
            if (on != y.isValueOn(*ijk))
                ++result.stateDiffers;
            else
                result.largest = std::max(result.largest, distance(u, v));
        }
    }
    return result;
}

/// Every grid of the one-piece file against the merged file's; both hold the same grids and
/// the same file metadata.
Comparison compareFiles(const std::string& whole, const std::string& merged) {
    const VdbFile a = readVdb(whole), b = readVdb(merged);
    Comparison total;
    EXPECT_EQ(a.grids.size(), b.grids.size());
    for (const auto& [name, grid] : a.grids) {
        const auto other = b.grids.find(name);
        if (other == b.grids.end()) {
            ADD_FAILURE() << "the merged file has no grid " << name;
            continue;
        }
        EXPECT_EQ(grid->transform(), other->second->transform()) << name;
        EXPECT_EQ(grid->getGridClass(), other->second->getGridClass()) << name;
        Comparison one;
        if (auto vectors = openvdb::gridPtrCast<openvdb::Vec3SGrid>(grid))
            one = compareGrids(*vectors, *openvdb::gridPtrCast<openvdb::Vec3SGrid>(other->second));
        else
            one = compareGrids(*openvdb::gridPtrCast<openvdb::FloatGrid>(grid),
                               *openvdb::gridPtrCast<openvdb::FloatGrid>(other->second));
        // Every grid the one-piece bake's exactly; the attribute grids too, since each voxel's
        // nearest seed (nearest_seed.hpp) is within the tile's halo (the fast sweeps they were
        // made by before depended a little on the swept domain near a tile's edge).
        EXPECT_EQ(one.stateDiffers, 0u) << name;
        EXPECT_EQ(one.differences, 0u) << name << ": " << one.differences << " of " << one.voxels
                                       << " voxels differ, by at most " << one.largest;
        EXPECT_GT(one.active, 100u) << name;
        total.voxels += one.voxels;
        total.differences += one.differences;
        total.active += one.active;
    }
    for (const char* key : {"creator", "dqjulia_parameters"})
        EXPECT_EQ(a.metadata->metaValue<std::string>(key), b.metadata->metaValue<std::string>(key)) << key;
    EXPECT_EQ(a.metadata->metaValue<double>("dqjulia_voxel_size"), b.metadata->metaValue<double>("dqjulia_voxel_size"));
    EXPECT_FALSE((*b.metadata)["dqjulia_tiling"]);
    return total;
}

struct Case {
    const char* name;
    int resolution;
    double band;
    const char* tiling;
    bool dual;
    bool attributes;  // the colour and trap grids too, reaching below the band
};

class TilesMerge : public Tiles, public ::testing::WithParamInterface<Case> {};

TEST_P(TilesMerge, EqualTheOnePieceBakeVoxelForVoxel) {
    const Case& c = GetParam();
    Params params;
    params.bake.resolution = c.resolution;
    params.bake.bandWidth = c.band;
    params.bake.grids = {BakeGrid::Surface, BakeGrid::Density};
    if (c.attributes) {
        params.bake.grids.insert(params.bake.grids.end(), {BakeGrid::Color, BakeGrid::Trap});
        params.bake.colorDepth = 0.1;  // 7 voxels below the band: the halo grows for them
    }
    if (c.dual) {
        params.fractal.variant = Variant::Dual;
        params.fractal.c = toDualQuat({-0.2, 0.6, 0.2, 0.0, 0.0, 0.0, 0.0, 0.0});
        params.fractal.iterations = 12;
    }
    const BakeStats whole = bakeVdb(params, path("whole.vdb"));
    const std::vector<std::string> tiles = bakeTiles(params, c.tiling);
    const MergeStats merged = mergeTiles(tiles, path("merged.vdb"));
    EXPECT_EQ(merged.tiles, tileCount(parseTiling(c.tiling)));
    EXPECT_EQ(merged.activeVoxels, whole.activeVoxels);
    const Comparison comparison = compareFiles(path("whole.vdb"), path("merged.vdb"));
    EXPECT_EQ(comparison.differences, 0u);
    std::printf("[ figures  ] %s: %s tiles of %d^3, band %g: %llu voxels compared (%llu active), %llu differ\n", c.name,
                c.tiling, c.resolution, c.band, static_cast<unsigned long long>(comparison.voxels),
                static_cast<unsigned long long>(comparison.active),
                static_cast<unsigned long long>(comparison.differences));
}

// The default bake's index box at 64^3 is 69 voxels a side from -34: halves split at 0 (on a
// leaf boundary), thirds at -11 and 12 (not); at 128^3, 133 voxels from -66, thirds at -22, 22.
INSTANTIATE_TEST_SUITE_P(
    Tilings, TilesMerge,
    ::testing::Values(Case{"aligned", 64, 3.0, "2x2x2", false, true}, Case{"unaligned", 64, 3.0, "3x2x1", false, true},
                      Case{"band1", 64, 1.0, "3x1x1", false, false}, Case{"band6", 64, 6.0, "1x3x1", false, false},
                      Case{"dual", 64, 3.0, "1x1x3", true, false}, Case{"r128", 128, 3.0, "3x1x1", false, false}),
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
