// voxel_render.hpp - draws a baked VDB's voxels as cubes: the paper's "Voxel vs
// Ray-Traced" figure, where a 50^3 or 100^3 grid loses the detail sphere tracing keeps.
//
// Reads the fog volume `density` of a file written by bakeVdb(), and casts one ray per
// sample through its voxels (Amanatides-Woo traversal in index space); a voxel with
// density >= 0.5 is solid. Faces are shaded with the parameters' lights and material
// (Phong, no occlusion or shadows) over the same background as render(). Camera and
// bounds are the parameters', so the picture lines up with render()'s.
// Cost: width * height * samples^2 rays of at most 3 * resolution voxel steps.
#pragma once

#include <string>

#include "dqjulia/render.hpp"

namespace dqj {

/// Throws std::runtime_error if the file cannot be read or has no float grid `density`,
/// Cancelled if `progress` returned false.
RenderResult renderVoxels(const Params& params, const std::string& vdbPath, const ProgressCallback& progress = {});

}  // namespace dqj
