// memory.hpp - the memory a bake, a mesh or a merge is estimated to take and may take (internal
// to libdqjulia; code in memory.cpp, which also holds bake.hpp's MemoryLimitError,
// processMemoryHeadroom, defaultMemoryLimit and formatBytes). Cost: the estimates are a few
// operations; the limits ask the system (platform.hpp: a few small files of /proc and /sys on
// Linux, the job object on Windows), as does the peak the command's --stats prints
// (platform::peakMemoryBytes).
#pragma once

#include <cstdint>

#include "dqjulia/bake.hpp"

namespace dqj {

/// Bytes the caller's later stages need per sampled leaf, for the memory estimate.
struct MemoryModel {
    double bytesPerLeaf = 0.0;
    double fixedBytes = 0.0;
};

/// What a bake takes beyond its sampled leaves, by the grids it writes (bakeVdb).
MemoryModel bakeMemoryModel(const BakeSettings& bake);

/// What a mesh, in one piece or one slab at a time, takes beyond its sampled leaves, per leaf of
/// the sampler's first wave (what the sampler checks and the slab plan bounds: slabLeaves).
MemoryModel meshMemoryModel();

}  // namespace dqj
