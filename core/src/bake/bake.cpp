// Baking to OpenVDB (bake.hpp): the bake's orchestration. The level set (level_set.cpp), the
// attribute grids (attribute_grids.cpp) and the fog volume made from the level set, the memory
// estimate (memory.cpp), and the file with its metadata (a tile's too: tile_geometry.cpp).
#include "dqjulia/bake.hpp"

#include <chrono>
#include <optional>
#include <string>

#include "bake/attribute_grids.hpp"
#include "bake/level_set.hpp"
#include "bake/memory.hpp"
#include "bake/tile_geometry.hpp"
#include "dqjulia/version.h"
#include "files/atomic_file.hpp"
#include "files/vdb_file.hpp"

namespace dqj {

std::string_view bakeStageName(BakeStage stage) {
    switch (stage) {
        case BakeStage::Classifying: return "classifying";
        case BakeStage::Sampling: return "sampling";
        case BakeStage::LevelSet: return "level set";
        case BakeStage::Grids: return "grids";
        case BakeStage::Meshing: return "meshing";
        case BakeStage::Writing: return "writing";
    }
    return "working";
}

BakeStats bakeVdb(const Params& params, const std::string& path, const BakeOptions& options,
                  const ProgressCallback& progress) {
    const auto start = std::chrono::steady_clock::now();
    validate(params);
    if (AtomicFile::lowercaseExtension(path) != ".vdb")
        throw ParamError("output.path", "'" + inputExcerpt(path) + "' must end in .vdb");
    if (options.tile) checkTile(params, *options.tile);
    AtomicFile file(path, options.existing);  // fails now, before the work, if the folder is not writable
    StagedProgress staged(progress, options.monitor);
    BakeStats stats;
    openvdb::FloatGrid::Ptr surface =
        bakeLevelSet(params, options, bakeMemoryModel(params.bake), staged, stats, 0.7, 0.85);
    // A tile keeps what it owns; its file holds the surface (the merge needs it) and the
    // attribute grids, and the merge makes the density from the merged surface.
    std::optional<openvdb::CoordBBox> kept;
    if (options.tile) {
        const openvdb::CoordBBox full = bakeIndexBox(params);
        kept = keptBox(full, ownedBox(full, *options.tile));
    }

    // The attribute grids before the density, so that the density is not held while their
    // seeds and propagation are (the peak at 1024^3); the file keeps its order.
    openvdb::GridPtrVec attributes;
    addAttributeGrids(params, *surface, kept ? &*kept : nullptr, staged.stage(BakeStage::Grids, 0.85, 0.95), stats,
                      attributes);
    openvdb::GridPtrVec grids;
    if (hasGrid(params.bake, BakeGrid::Surface) || kept) grids.push_back(surface);
    if (hasGrid(params.bake, BakeGrid::Density) && !kept) grids.push_back(densityFromSurface(*surface));
    grids.insert(grids.end(), attributes.begin(), attributes.end());
    if (kept) {
        surface->tree().clip(*kept);
        stats.activeVoxels = surface->activeVoxelCount();
    }

    staged.stage(BakeStage::Writing, 0.95, 1.0);
    if (progress && !progress(0.95)) throw Cancelled();
    openvdb::MetaMap metadata;
    metadata.insertMeta("creator", openvdb::StringMetadata(std::string("dqjulia ") + DQJ_VERSION_STRING));
    const std::string document = toJson(params);
    metadata.insertMeta("dqjulia_parameters", openvdb::StringMetadata(document));
    metadata.insertMeta("dqjulia_voxel_size", openvdb::DoubleMetadata(stats.voxelSize));
    if (options.tile) {
        std::uint64_t gridBytes = 0;
        for (const openvdb::GridBase::Ptr& grid : grids) gridBytes += grid->memUsage();
        addTileMetadata(metadata, params, *options.tile, document, gridBytes);
    }
    writeVdbFile(file, grids, metadata);
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (progress) progress(1.0);
    return stats;
}

}  // namespace dqj
