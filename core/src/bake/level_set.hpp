// level_set.hpp - the first half of every bake: sample the surface function sparsely and turn
// it into an exact narrow-band signed distance (internal to libdqjulia).
//
// f (sparse_sampler.hpp) is zero on the surface but is not a distance; the level set is the
// signed distance to f's mesh with the bake's band width (mesh_distance.hpp: exact within a
// voxel of the mesh, negative inside). Cost: the sampling, then about one mesh vertex and a
// band's worth of voxels per surface voxel; interruptible.
#pragma once

#include <openvdb/openvdb.h>

#include "dqjulia/bake.hpp"
#include "dqjulia/params.hpp"
#include "bake/sparse_sampler.hpp"
#include "bake/staged_progress.hpp"

namespace dqj {

/// Bakes take a surface point's colour (and trap, iteration count) this many voxels outside it,
/// along its normal, where the renderer and the preview take theirs (their hits lie outside the
/// finite-N set): on the surface itself an orbit is bounded (the inside's colour, the palette's
/// other end) about as often as not.
constexpr double kSurfaceColourOffset = 0.5;

/// Registers OpenVDB's grid types once (thread-safe).
void initializeOpenVdb();

/// The level set "surface" of `params` (validated). Progress: classification in [0, 0.03 of
/// the share], sampling up to `sampledAt`, the rebuild up to `rebuiltAt`. Fills `stats` (all
/// but seconds). Throws MemoryLimitError, Cancelled.
openvdb::FloatGrid::Ptr bakeLevelSet(const Params& params, const BakeOptions& options, const MemoryModel& memory,
                                     StagedProgress& progress, BakeStats& stats, double sampledAt, double rebuiltAt);

/// The fog volume "density" of a level set: 1 inside, a ramp to 0 across the inner half of the
/// band, 0 outside (sdfToFogVolume on a copy).
openvdb::FloatGrid::Ptr densityFromSurface(const openvdb::FloatGrid& surface);

}  // namespace dqj
