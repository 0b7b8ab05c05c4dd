// The level set of a bake (level_set.hpp): the sampled surface function rebuilt into a narrow-band
// signed distance, and the fog volume made from it.
#include "bake/level_set.hpp"

#include <mutex>
#include <utility>

#include <openvdb/tools/LevelSetUtil.h>

#include "bake/mesh_distance.hpp"
#include "platform/parallel_progress.hpp"

namespace dqj {

openvdb::FloatGrid::Ptr densityFromSurface(const openvdb::FloatGrid& surface) {
    // Interior 1, a ramp to 0 across the inner half of the band, outside 0 (inactive).
    openvdb::FloatGrid::Ptr density = surface.deepCopy();
    openvdb::tools::sdfToFogVolume(*density);
    density->setName("density");
    density->setCreator("dqjulia");
    return density;
}

void initializeOpenVdb() {
    static std::once_flag once;
    std::call_once(once, [] { openvdb::initialize(); });
}

openvdb::FloatGrid::Ptr bakeLevelSet(const Params& params, const BakeOptions& options, const MemoryModel& memory,
                                     StagedProgress& progress, BakeStats& stats, double sampledAt, double rebuiltAt) {
    initializeOpenVdb();
    SampledSurface sampled = sampleSurface(params, options, memory, progress, 0.03, sampledAt);
    stats = sampled.stats;
    const float band = float(params.bake.bandWidth);
    openvdb::FloatGrid::Ptr surface;
    parallelForWithProgress(1, progress.stage(BakeStage::LevelSet, sampledAt, rebuiltAt),
                            [&](std::size_t, const std::atomic<bool>& stop) {
                                surface = levelSetOfMesh(std::move(sampled.grid), band, stop);
                            });
    sampled.grid.reset();
    surface->setName("surface");
    surface->setGridClass(openvdb::GRID_LEVEL_SET);
    surface->setCreator("dqjulia");
    stats.activeVoxels = surface->activeVoxelCount();
    return surface;
}

}  // namespace dqj
