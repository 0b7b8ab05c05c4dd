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

/// Memory per sampled 8^3 leaf beyond the sampled leaf itself: volumeToMesh's masks and polygon
/// pools, and the mesh's arrays. Measured on the default fractal (peak RSS minus the 65 MB of a
/// tiny mesh, over sampled leaves: 3.0 kB at 256^3, 5.6 kB at 512^3) and doubled for headroom.
MemoryModel meshMemoryModel() {
    MemoryModel model;
    model.fixedBytes = 96.0 * 1024 * 1024;
    model.bytesPerLeaf = 10.0 * 1024;
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
