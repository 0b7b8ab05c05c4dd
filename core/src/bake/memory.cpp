// The memory a bake, a mesh or a merge may take and is estimated to take (memory.hpp,
// bake.hpp): the estimates per sampled leaf, the process's limits and headroom (asked of the
// system through platform.hpp).
#include "bake/memory.hpp"

#include <algorithm>
#include <cstdio>
#include <string>

#include "platform/platform.hpp"

namespace dqj {

/// Memory per sampled 8^3 leaf beyond the sampled leaf itself: the rebuild's mesh and distance
/// grids, the level set, the fog volume; attribute grids on top. Measured on the default
/// fractal (peak RSS minus the 65 MB of a tiny bake, over sampled leaves: 4.3 kB at 256^3,
/// 5.2 kB at 512^3, 4.9 kB at 1024^3) and doubled for headroom. With the colour grid (its
/// seeds, their propagation and the grid) 7.7 kB at 512^3 and 9.8 kB at 1024^3 in all, so
/// about 5 kB more, doubled (the sweeps it replaced took 17 kB: 4.2 GB at 1024^3, above the
/// 12 kB this allowed).
MemoryModel bakeMemoryModel(const BakeSettings& bake) {
    MemoryModel model;
    model.fixedBytes = 96.0 * 1024 * 1024;
    model.bytesPerLeaf = 9.0 * 1024;
    if (hasGrid(bake, BakeGrid::Color)) model.bytesPerLeaf += 10.0 * 1024;
    if (hasGrid(bake, BakeGrid::Trap)) model.bytesPerLeaf += 4.0 * 1024;
    if (hasGrid(bake, BakeGrid::Iterations)) model.bytesPerLeaf += 4.0 * 1024;
    return model;
}

/// Memory per leaf of the sampler's first wave (the leaves it checks against the limit; later
/// waves, inside the set, add about 15 % more) beyond kFloatLeafBytes: the leaf's values, the
/// later waves, the classification's states, volumeToMesh's masks and polygon pools, the mesh's
/// arrays, normals and colours, and in slabs the part handed on beside the slab's mesh. Measured
/// on the default fractal (issue 39; peak RSS from VmHWM, reset before each slab, minus the RSS
/// before it, over the slab's first wave): slabs at 1024^3 (7 under a 500 MB limit) 2.9 to 4.6 kB,
/// at 2048^3 (6 under 2 GB) 2.9 to 3.5 kB; in one piece 2.9 kB at 1024^3. The most is a slab
/// across the middle, where the surface has the most vertices per leaf (39 against 26 on
/// average). 5.5 kB keeps a margin of 20 % over the most and 80 % over the usual; the fixed part
/// covers the process and what it keeps between slabs (the seam, the allocator's: up to 85 MB
/// measured at 2048^3). The model before (10 kB, from 512^3 and doubled) refused 4096^3 under
/// 2 GB, whose slabs fit.
MemoryModel meshMemoryModel() {
    MemoryModel model;
    model.fixedBytes = 96.0 * 1024 * 1024;
    model.bytesPerLeaf = 5.5 * 1024;
    return model;
}

MemoryLimitError::MemoryLimitError(const std::string& message, std::uint64_t estimate, std::uint64_t limit)
    : ParamError("bake.resolution", "bake.resolution: " + message), estimate_(estimate), limit_(limit) {}

std::uint64_t processMemoryHeadroom() { return platform::memoryHeadroom(); }

std::uint64_t defaultMemoryLimit() {
    const std::uint64_t available = platform::availableMemory();
    const std::uint64_t half = available ? available / 2 : std::uint64_t(1) << 31;
    return std::min(half, processMemoryHeadroom());
}

std::string formatBytes(std::uint64_t bytes) {
    char text[32];
    const double value = double(bytes);
    if (value >= 1e9)
        std::snprintf(text, sizeof text, "%.1f GB", value / 1e9);
    else if (value >= 1e6)
        std::snprintf(text, sizeof text, "%.0f MB", value / 1e6);
    else
        std::snprintf(text, sizeof text, "%.0f kB", value / 1e3);
    return text;
}

}  // namespace dqj
