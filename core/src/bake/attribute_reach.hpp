// attribute_reach.hpp - how far below the surface the attribute grids (color, trap, iterations)
// reach and how many rounds their seeds spread (internal to libdqjulia): what bake.cpp builds
// them with and what a tile's halo must cover (tileHalo, tiles.cpp). Cost: a few operations.
#pragma once

#include <algorithm>
#include <cmath>

#include "dqjulia/param_types.hpp"

namespace dqj {

/// The attribute grids' depth below the surface in voxels: bake.color_depth of the bake's
/// largest side, at least the band (which the level set covers anyway).
inline int attributeDepth(const BakeSettings& bake) {
    return std::max(int(std::ceil(bake.colorDepth * bake.resolution)), int(std::ceil(bake.bandWidth)));
}

/// The 26-neighbour steps by which the attribute grids' region reaches below the band: the band
/// dilated by this many steps, of which the inside is kept (attributeVoxels in bake.cpp). Along
/// the diagonals that is sqrt(3) times as deep.
inline int attributeDilation(const BakeSettings& bake) { return attributeDepth(bake) - int(std::ceil(bake.bandWidth)); }

/// The rounds of 26-neighbour steps the surface seeds spread through that region
/// (nearestSeeds' `rounds`): twice the depth, plus 8. The deepest voxel lies up to
/// sqrt(3) x dilation + band, about 1.7 x the depth, from the surface, and its nearest seed
/// arrives in about as many rounds (a 26-neighbour step covers up to sqrt(3) voxels); around
/// concave parts it comes a few rounds later. Measured on the default fractal, the last change
/// came in round 19 at 512^3 (depth 11) and in round 34 at 1024^3 (depth 21), within 5 to 8
/// rounds of the depth on the examples: the bound stops no real bake early. Were it reached, a
/// voxel would keep the seed it holds then (one about as near), and one no seed reached yet
/// would stay out of the grids, in every tiling alike. A fixed bound makes the grids local (a
/// voxel's seed depends on nothing further than this many steps), which is what lets a tile's
/// halo (tileHalo) make them exact.
inline int attributeRounds(const BakeSettings& bake) { return 2 * attributeDepth(bake) + 8; }

}  // namespace dqj
