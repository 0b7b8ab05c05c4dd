// mesh_distance.hpp - the narrow-band signed distance to the mesh of a sampled surface function
// (internal to libdqjulia): the bake's level set (level_set.hpp).
//
// f (sparse_sampler.hpp) is zero on the surface but is not a distance. Its mesh (OpenVDB's
// volumeToMesh, one vertex per cell that f crosses, a quad per crossed edge) is, and the level
// set is the distance to that mesh. What OpenVDB's levelSetRebuild gives, at a fraction of its
// cost, because the mesh's shape is known:
//
// - Near voxels, within one voxel of the mesh (the ends of every edge the level set crosses):
//   the exact distance to the nearest triangle, the sign from the side of it the voxel lies on
//   (of the triangles equally near, the one it faces most squarely: right at faces and at the
//   mesh's edges). Each leaf tests the triangles of the quads whose first vertex lies in it or
//   in one of its 26 neighbours (a quad spans at most 2 x 2 x 1 cells), over the voxels of each
//   triangle's box grown by one voxel.
// - The rest of the band: the distance to the nearest of the near voxels' nearest points
//   (nearest_seed.hpp: within 0.1 voxel of the exact distance), the sign f's (a voxel farther
//   than a voxel from the mesh has no edge f crosses, so f's sign holds across it).
//
// The surface (the zero crossings) comes from the near voxels alone, so it is the mesh's.
#pragma once

#include <atomic>

#include <openvdb/openvdb.h>

namespace dqj {

/// The signed distance (world units, negative inside) to the mesh of f = 0, active where it is
/// below `bandWidth` voxels, with f's transform; background +-bandWidth voxels, inside tiles
/// negative. Once meshed, f is let go (freed if the caller moved its last pointer in), and only
/// its signs are kept (a bit a voxel): the band's grids take its memory. Returns nullptr when
/// `stop` became true.
openvdb::FloatGrid::Ptr levelSetOfMesh(openvdb::FloatGrid::Ptr f, float bandWidth, const std::atomic<bool>& stop);

}  // namespace dqj
