// Tiled bakes at the sizes a farm bakes (label `long`, minutes: `ctest --test-dir build -L long`;
// scripts/test.sh leaves them out, tiles_test.cpp holds the class at small sizes): merged tiles
// equal the one-piece bake voxel for voxel, every grid a bake can hold (surface, density,
// color, trap, iterations), with the default band and colour depth. 512^3 in 2x1x1 is where the
// colour grids first differed on the seam (the halo then added the colour depth below the band,
// not the sqrt 3 times as deep reach of its region along the diagonals, nor the seeds' rounds).
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
};

class TilesLong : public dqj::test::Tiles, public ::testing::WithParamInterface<Case> {};

TEST_P(TilesLong, EqualTheOnePieceBakeVoxelForVoxel) {
    Params params;
    params.bake.resolution = GetParam().resolution;
    params.bake.grids = {BakeGrid::Surface, BakeGrid::Density, BakeGrid::Color, BakeGrid::Trap, BakeGrid::Iterations};
    dqj::test::checkMergeEqualsWhole(*this, params, GetParam().tiling, GetParam().name);
}

// Colour depth 0.02: 11 voxels at 512^3 (8 below the band), 8 at 384^3, 12 at 576^3.
INSTANTIATE_TEST_SUITE_P(Sizes, TilesLong,
                         ::testing::Values(Case{"r512", 512, "2x1x1"}, Case{"r384", 384, "2x2x2"},
                                           Case{"r576", 576, "1x3x1"}),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
