// nearest_seed.hpp - for every voxel of a sparse region, the nearest of a set of seed points
// (internal to libdqjulia). The bake's attribute grids use it to give each voxel below the
// surface the colour of the surface point nearest to it (bake.cpp, addAttributeGrids).
//
// The seeds spread outwards from their voxels in rounds of 26-neighbour steps; a voxel reached
// takes, of its own and its neighbours' seeds, the one nearest to it, and a voxel reached
// before is taken up again when a neighbour's seed is nearer, until nothing changes. A vector
// distance transform: not always the nearest seed, but one about as near (below a sphere of
// seeds 88.5 % exact, the rest within 0.09 voxel; nearest_seed_test.cpp).
//
// Local: a round reads and writes only a voxel and its 26 neighbours, so after r rounds a
// voxel's seed is a function of the region and the seeds (their voxels, points and order)
// within r steps of it (Chebyshev distance r), and nothing beyond. With the rounds bounded,
// two regions that agree within that many steps of a voxel give it the same seed: a tile of a
// bake computes its voxels' seeds exactly as the whole bake does (tileHalo, tiles.cpp).
//
// Cost: 26 neighbour reads twice per voxel and round it changes in, parallel over each round;
// memory: an Int32Tree of the region's topology.
#pragma once

#include <limits>
#include <vector>

#include <openvdb/openvdb.h>

namespace dqj {

/// The index into `points` of the seed nearest to each active voxel of `region` (distances in
/// index space), as an Int32Tree of the region's topology. Seed k starts at voxel `voxels[k]`
/// (seeds outside the region's active voxels are ignored; of two on one voxel the first is
/// kept) and is measured from `points[k]` (index space, usually within that voxel). Voxels no
/// seed reaches through the region's active voxels are inactive (value -1). At most `rounds`
/// rounds (26-neighbour steps) after the seeds' own voxels: a voxel keeps the seed it has then,
/// and one no seed reached in that many steps is inactive; without a bound, until nothing
/// changes. Deterministic: ties go to the lower seed index.
openvdb::Int32Tree::Ptr nearestSeeds(const openvdb::MaskTree& region, const std::vector<openvdb::Coord>& voxels,
                                     const std::vector<openvdb::Vec3f>& points,
                                     int rounds = std::numeric_limits<int>::max());

}  // namespace dqj
