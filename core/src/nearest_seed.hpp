// nearest_seed.hpp - for every voxel of a sparse region, the nearest of a set of seed points
// (internal to libdqjulia). The bake's attribute grids use it to give each voxel below the
// surface the colour of the surface point nearest to it (bake.cpp, addAttributeGrids).
//
// The seeds spread outwards from their voxels in rounds of 26-neighbour steps; a voxel reached
// takes, of its own and its neighbours' seeds, the one nearest to it, and a voxel reached
// before is taken up again when a neighbour's seed is nearer, until nothing changes. A vector
// distance transform: not always the nearest seed, but one about as near (below a sphere of
// seeds 88.5 % exact, the rest within 0.09 voxel; nearest_seed_test.cpp). Cost: 26 neighbour
// reads twice per voxel and round it changes in, parallel over each round; memory: an
// Int32Tree of the region's topology.
#pragma once

#include <vector>

#include <openvdb/openvdb.h>

namespace dqj {

/// The index into `points` of the seed nearest to each active voxel of `region` (distances in
/// index space), as an Int32Tree of the region's topology. Seed k starts at voxel `voxels[k]`
/// (seeds outside the region's active voxels are ignored; of two on one voxel the first is
/// kept) and is measured from `points[k]` (index space, usually within that voxel). Voxels no
/// seed reaches through the region's active voxels are inactive (value -1). Deterministic:
/// ties go to the lower seed index.
openvdb::Int32Tree::Ptr nearestSeeds(const openvdb::MaskTree& region, const std::vector<openvdb::Coord>& voxels,
                                     const std::vector<openvdb::Vec3f>& points);

}  // namespace dqj
