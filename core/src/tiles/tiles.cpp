// The merge of a tiled bake's tiles into the one-piece bake's file (tiles.hpp, mergeTiles): the
// tiles checked against each other and the memory limit, merged grid by grid, the density made
// from the merged surface. The tiling and a tile's place and metadata: bake/tile_geometry.cpp.
#include "dqjulia/tiles.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>

#include <openvdb/tools/Composite.h>
#include <openvdb/tools/Prune.h>

#include "files/atomic_file.hpp"
#include "bake/attribute_reach.hpp"
#include "dqjulia/version.h"
#include "platform/platform.hpp"
#include "bake/level_set.hpp"
#include "bake/sparse_sampler.hpp"
#include "bake/tile_geometry.hpp"
#include "files/vdb_file.hpp"

namespace dqj {

using openvdb::Coord;
using openvdb::CoordBBox;

namespace {

/// Refuses tiles of different bakes, another dqjulia's tiles, repeated and missing tiles.
void checkTilesBelongTogether(const std::vector<TileHeader>& headers) {
    const TileHeader& first = headers.front();
    for (const TileHeader& header : headers) {
        if (header.version != DQJ_VERSION_STRING)
            throw ParamError("tiles", "'" + inputExcerpt(header.path) + "' was baked by dqjulia " + header.version +
                                          " and this is dqjulia " + DQJ_VERSION_STRING +
                                          ": bake and merge with the same version on every machine");
        std::string differs;
        if (header.hash != first.hash)
            differs = "its parameters differ";
        else if (tilingText(header.tile) != tilingText(first.tile))
            differs = "its tiling is " + tilingText(header.tile) + ", not " + tilingText(first.tile);
        else if (header.full != first.full || header.voxelSize != first.voxelSize)
            differs = "its grid differs";
        if (!differs.empty())
            throw ParamError("tiles", "'" + inputExcerpt(header.path) + "' is not a tile of the same bake as '" +
                                          inputExcerpt(first.path) + "': " + differs);
    }
    std::map<int, const TileHeader*> byIndex;
    for (const TileHeader& header : headers) {
        const auto [at, added] = byIndex.emplace(header.tile.index, &header);
        if (!added)
            throw ParamError("tiles", "'" + inputExcerpt(at->second->path) + "' and '" + inputExcerpt(header.path) +
                                          "' are both tile " + std::to_string(header.tile.index) + " of " +
                                          tilingText(first.tile));
    }
    const int count = tileCount(first.tile);
    std::string missing;
    int missingCount = 0;
    for (int index = 1; index <= count; ++index) {
        if (byIndex.count(index)) continue;
        if (++missingCount <= 10) missing += (missing.empty() ? "" : ", ") + std::to_string(index);
    }
    if (missingCount > 0)
        throw ParamError("tiles", std::to_string(missingCount) + " of the " + std::to_string(count) + " tiles of " +
                                      tilingText(first.tile) + " are missing: " + missing +
                                      (missingCount > 10 ? ", ..." : "") + " (given " + std::to_string(headers.size()) +
                                      " files)");
    // Each tile's box was checked against its index; together they cover the box once.
    std::uint64_t voxels = 0;
    for (const TileHeader& header : headers) voxels += header.owned.volume();
    if (voxels != first.full.volume())
        throw ParamError("tiles", "the tiles' boxes do not cover the bake's box " + boxText(first.full) + " once");
}

/// Refuses (MemoryLimitError) before any grid is read a merge whose estimate exceeds the limit
/// (`memoryLimit`, 0: defaultMemoryLimit()), or what the process may allocate. The merge holds
/// the merged grids (as much as the tiles' grids together), one tile being merged, and the
/// density made from the merged surface (at most as much again), besides the bake's fixed part.
void checkMergeMemory(const std::vector<TileHeader>& headers, const Params& params, std::uint64_t memoryLimit) {
    std::uint64_t total = 0, largest = 0;
    for (const TileHeader& header : headers) {
        total += header.gridBytes;
        largest = std::max(largest, header.gridBytes);
    }
    const std::uint64_t estimate = (std::uint64_t(96) << 20) + 2 * total + largest;
    const std::uint64_t processLimit = processMemoryHeadroom();
    const std::uint64_t requested = memoryLimit ? memoryLimit : defaultMemoryLimit();
    const std::uint64_t limit = std::min(requested, processLimit);
    if (estimate <= limit) return;
    const bool processLimited = processLimit <= requested;
    throw MemoryLimitError(
        "merging the " + std::to_string(headers.size()) + " tiles of resolution " +
            std::to_string(params.bake.resolution) + " needs an estimated " + formatBytes(estimate) +
            " (their grids take " + formatBytes(total) + "), more than the limit of " + formatBytes(limit) +
            (processLimited ? " (what this process may still allocate under its memory limits: ulimit -v, ulimit -d "
                              "or its cgroup's memory.max); merge where the process may use more memory"
             : memoryLimit  ? "; raise the limit (--max-memory)"
                            : " (half of the available memory); raise the limit (--max-memory)"),
        estimate, limit);
}

}  // namespace

MergeStats mergeTiles(const std::vector<std::string>& tiles, const std::string& path, Existing existing,
                      const ProgressCallback& progress, std::uint64_t memoryLimit) {
    const auto start = std::chrono::steady_clock::now();
    if (tiles.empty()) throw ParamError("tiles", "no tiles to merge");
    if (AtomicFile::lowercaseExtension(path) != ".vdb")
        throw ParamError("output.path", "'" + inputExcerpt(path) + "' must end in .vdb");
    initializeOpenVdb();
    // First every tile's metadata: nothing heavy is read before the tiles are known to fit.
    std::vector<TileHeader> headers;
    headers.reserve(tiles.size());
    for (const std::string& tile : tiles) headers.push_back(readTileHeader(tile));
    checkTilesBelongTogether(headers);
    std::sort(headers.begin(), headers.end(),
              [](const TileHeader& a, const TileHeader& b) { return a.tile.index < b.tile.index; });
    const Params params = parseParams(headers.front().document, "'" + inputExcerpt(headers.front().path) + "'");
    if (bakeIndexBox(params) != headers.front().full)
        throw ParamError("tiles",
                         "'" + inputExcerpt(headers.front().path) + "' is a damaged tile: its box is not its bake's");
    checkMergeMemory(headers, params, memoryLimit);
    AtomicFile file(path, existing);  // fails now, before the work, if the folder is not writable

    // Then one tile at a time: its surface united into the result, its attribute voxels copied.
    const BakeGrid attributes[] = {BakeGrid::Color, BakeGrid::Trap, BakeGrid::Iterations};
    openvdb::FloatGrid::Ptr surface;
    std::map<BakeGrid, openvdb::GridBase::Ptr> merged;
    MergeStats stats;
    for (std::size_t index = 0; index < headers.size(); ++index) {
        if (progress && !progress(0.9 * double(index) / double(headers.size()))) throw Cancelled();
        const TileHeader& header = headers[index];
        VdbContents contents = readVdbFile(header.path);
        stats.tileBytes += std::filesystem::file_size(platform::pathFromUtf8(header.path));
        auto tileSurface = openvdb::gridPtrCast<openvdb::FloatGrid>(findGrid(contents, "surface"));
        if (!tileSurface || tileSurface->getGridClass() != openvdb::GRID_LEVEL_SET)
            throw ParamError("tiles",
                             "'" + inputExcerpt(header.path) + "' is a damaged tile: it has no level set \"surface\"");
        if (!surface) {
            surface = tileSurface;
        } else {
            if (tileSurface->transform() != surface->transform() || tileSurface->background() != surface->background())
                throw ParamError("tiles", "'" + inputExcerpt(header.path) +
                                              "' is a damaged tile: its grid differs from '" +
                                              inputExcerpt(headers.front().path) + "''s");
            openvdb::tools::csgUnion(surface->tree(), tileSurface->tree(), /*prune=*/false);
        }
        for (const BakeGrid grid : attributes) {
            if (!hasGrid(params.bake, grid)) continue;
            const std::string name(bakeGridName(grid));
            openvdb::GridBase::Ptr part = findGrid(contents, name);
            const bool vector = grid == BakeGrid::Color;
            if (!part || (vector ? !openvdb::gridPtrCast<openvdb::Vec3SGrid>(part)
                                 : !openvdb::gridPtrCast<openvdb::FloatGrid>(part)))
                throw ParamError("tiles", "'" + inputExcerpt(header.path) + "' is a damaged tile: it has no grid \"" +
                                              name + "\"");
            auto& into = merged[grid];
            if (!into)
                into = part;
            else if (vector)
                openvdb::tools::compReplace(*openvdb::gridPtrCast<openvdb::Vec3SGrid>(into),
                                            *openvdb::gridPtrCast<openvdb::Vec3SGrid>(part));
            else
                openvdb::tools::compReplace(*openvdb::gridPtrCast<openvdb::FloatGrid>(into),
                                            *openvdb::gridPtrCast<openvdb::FloatGrid>(part));
        }
        platform::releaseFreedMemory();  // the tile's nodes that the union did not take
    }
    openvdb::tools::pruneLevelSet(surface->tree());
    stats.tiles = int(headers.size());
    stats.activeVoxels = surface->activeVoxelCount();

    if (progress && !progress(0.9)) throw Cancelled();
    openvdb::GridPtrVec grids;
    if (hasGrid(params.bake, BakeGrid::Surface)) grids.push_back(surface);
    if (hasGrid(params.bake, BakeGrid::Density)) grids.push_back(densityFromSurface(*surface));
    for (const BakeGrid grid : attributes)
        if (merged[grid]) grids.push_back(merged[grid]);
    openvdb::MetaMap metadata;
    metadata.insertMeta("creator", openvdb::StringMetadata(std::string("dqjulia ") + DQJ_VERSION_STRING));
    metadata.insertMeta("dqjulia_parameters", openvdb::StringMetadata(headers.front().document));
    metadata.insertMeta("dqjulia_voxel_size", openvdb::DoubleMetadata(headers.front().voxelSize));
    writeVdbFile(file, grids, metadata);
    stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (progress) progress(1.0);
    return stats;
}

}  // namespace dqj
