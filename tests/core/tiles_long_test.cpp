// Tiled bakes at the sizes a farm bakes (label `long`, minutes: `ctest --test-dir build -L long`;
// scripts/test.sh leaves them out, tiles_test.cpp holds the class at small sizes and a crop of
// 512^3): merged tiles equal the one-piece bake voxel for voxel, every grid a bake can hold
// (surface, density, color, trap, iterations), with the default band and colour depth. 512^3 in
// 2x1x1 is where the colour grids first differed on the seam (the halo then added the colour
// depth below the band, not the rounds the seeds spread, which grow with the size).
#include <gtest/gtest.h>

#include "dqjulia/bake.hpp"
#include "dqjulia/params.hpp"
#include "tile_merge_check.hpp"

namespace {

using namespace dqj;

struct Case {
    const char* name;
    int resolution;
    const char* tiling;
    openvdb::Coord crop{0};  // else a crop of the bake at `resolution`^3, these voxels a side (cropOf)
};

class TilesLong : public dqj::test::Tiles, public ::testing::WithParamInterface<Case> {};

TEST_P(TilesLong, EqualTheOnePieceBakeVoxelForVoxel) {
    Params params;
    params.bake.resolution = GetParam().resolution;
    params.bake.grids = {BakeGrid::Surface, BakeGrid::Density, BakeGrid::Color, BakeGrid::Trap, BakeGrid::Iterations};
    if (GetParam().crop.x() > 0) dqj::test::cropOf(params, GetParam().resolution, GetParam().crop);
    dqj::test::checkMergeEqualsWhole(*this, params, GetParam().tiling, GetParam().name);
}

// Colour depth 0.02: 11 voxels at 512^3 (halo 46), 8 at 384^3 (37), 12 at 576^3 (49), 21 at
// 1024^3 (76), 41 at 2048^3 (136); the crops are wide enough across their seams that no tile's
// window holds the whole crop.
INSTANTIATE_TEST_SUITE_P(Sizes, TilesLong,
                         ::testing::Values(Case{"r512", 512, "2x1x1"}, Case{"r384", 384, "2x2x2"},
                                           Case{"r576", 576, "1x3x1"},
                                           Case{"seam1024", 1024, "2x1x1", openvdb::Coord(256, 128, 128)},
                                           Case{"thirds1024", 1024, "3x1x1", openvdb::Coord(256, 128, 128)},
                                           Case{"halves1024y", 1024, "1x2x1", openvdb::Coord(128, 256, 128)},
                                           Case{"seam2048", 2048, "2x1x1", openvdb::Coord(320, 128, 128)}),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
