// tile_merge_check.hpp - what the tiled-bake tests share (tiles_test.cpp, tiles_long_test.cpp):
// the bake fixture (bake_fixture.hpp), baking every tile of a tiling, the merged file compared with the one-piece
// bake's voxel for voxel, every grid (values bit for bit and active states, over the bounding
// box of both grids' active voxels grown by 2, so the inside and outside beyond the band too),
// and crops of large bakes at their voxel size.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "dqjulia/bake.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/tiles.hpp"
#include "bake/sparse_sampler.hpp"  // bakeIndexBox, bakeVoxelSize (internal)
#include "bake/tile_geometry.hpp"   // tileWindow (internal)
#include "bake_fixture.hpp"

namespace dqj::test {

namespace fs = std::filesystem;

class Tiles : public BakeFolder {
public:
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
};

/// Voxels compared and those that differ (value bits or active state) between two grids of
/// one type, over the bounding box of both grids' active voxels grown by 2 voxels.
struct Comparison {
    std::uint64_t voxels = 0;
    std::uint64_t differences = 0;
    std::uint64_t active = 0;
    std::uint64_t stateDiffers = 0;  // active in one grid only
    double largest = 0.0;            // the largest value difference where both are active
};

inline double distance(float u, float v) { return std::abs(double(u) - double(v)); }
inline double distance(const openvdb::Vec3s& u, const openvdb::Vec3s& v) { return double((u - v).length()); }
/// Bit for bit, so that -0 and 0 (or two NaNs) are told apart.
inline bool sameBits(float a, float b) { return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b); }
inline bool sameBits(const openvdb::Vec3s& a, const openvdb::Vec3s& b) {
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
inline Comparison compareFiles(const std::string& whole, const std::string& merged) {
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

/// Bakes `params` whole and in the tiles of `tiling`, merges the tiles and compares the merged
/// file with the whole one (compareFiles); prints the figures.
inline Comparison checkMergeEqualsWhole(Tiles& test, const Params& params, const std::string& tiling,
                                        const std::string& label) {
    // A tile whose window (its box grown by the halo) holds the whole bake's box bakes the whole
    // and proves nothing: every case has each tile's window end inside the box on a cut face.
    const openvdb::CoordBBox full = bakeIndexBox(params);
    Tile tile = parseTiling(tiling);
    for (tile.index = 1; tile.index <= tileCount(tile); ++tile.index)
        EXPECT_FALSE(tileWindow(params, tile).isInside(full))
            << label << ": tile " << tile.index << "'s halo of " << tileHalo(params.bake) << " covers the whole box "
            << full << ", so the case tests nothing";
    const BakeStats whole = bakeVdb(params, test.path("whole.vdb"));
    const std::vector<std::string> tiles = test.bakeTiles(params, tiling);
    const MergeStats merged = mergeTiles(tiles, test.path("merged.vdb"));
    EXPECT_EQ(merged.tiles, tileCount(parseTiling(tiling)));
    EXPECT_EQ(merged.activeVoxels, whole.activeVoxels);
    const Comparison comparison = compareFiles(test.path("whole.vdb"), test.path("merged.vdb"));
    EXPECT_EQ(comparison.differences, 0u);
    std::printf(
        "[ figures  ] %s: %s tiles of %d^3, band %g, colour depth %g (halo %d): %llu voxels compared "
        "(%llu active), %llu differ\n",
        label.c_str(), tiling.c_str(), params.bake.resolution, params.bake.bandWidth, params.bake.colorDepth,
        tileHalo(params.bake), static_cast<unsigned long long>(comparison.voxels),
        static_cast<unsigned long long>(comparison.active), static_cast<unsigned long long>(comparison.differences));
    return comparison;
}

/// A crop of the default fractal's bake at `resolution`^3, `extents` voxels along x, y and z,
/// with that bake's voxel size and colour depth in voxels (so its halo): the planes x = 0 and
/// y = 0 (the seams of 2x1x1 and 1x2x1 tilings) through the crop's middle, and the thick middle
/// of the set below it in z (at 512^3 and extents of 128 the box of the voxels where a too
/// small halo first showed, z from 0 to 128 voxels). Its largest side is its resolution.
inline void cropOf(Params& params, int resolution, const openvdb::Coord& extents) {
    Params whole;
    whole.bake.resolution = resolution;
    const double h = bakeVoxelSize(whole);
    const double z = resolution / 8.0 - 64.0;  // 0 at 512^3, 64 at 1024^3
    const glm::dvec3 half(extents.x() / 2.0, extents.y() / 2.0, 0.0);
    params.bake.bounds = Box{glm::dvec3(-half.x, -half.y, z) * h, glm::dvec3(half.x, half.y, z + extents.z()) * h};
    params.bake.resolution = extents[extents.maxIndex()];
    params.bake.colorDepth = (std::ceil(0.02 * resolution) - 0.5) / params.bake.resolution;
}

}  // namespace dqj::test
