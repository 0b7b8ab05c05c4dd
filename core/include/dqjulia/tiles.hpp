// dqjulia/tiles.hpp - tiled bakes for farms: one bake cut into boxes that are baked apart (by
// other processes or machines) and merged into the file the one-piece bake writes, voxel for
// voxel.
// Code: core/src/bake/tile_geometry.cpp (the tiling, tilePath, tileHalo, checkTile: a tile's bake
// needs them) and core/src/tiles/tiles.cpp (mergeTiles).
//
// A tile (BakeOptions::tile) bakes on the whole bake's voxel grid (the same voxel size and
// index space, cut only where the whole is cut, at its bounds): it samples the box it owns
// grown by a halo (tileHalo), rebuilds the level set there, clips it to the box it owns
// (Tree::clip) and writes NAME.tile_K.vdb (tilePath) with the surface, the attribute grids
// clipped the same way, and metadata: the tiling, the tile, the whole's index box, the box it
// owns, the parameters' hash and dqjulia's version. The halo hides the tile's cut faces from
// what it keeps: the rebuilt distance near a cut depends on the surface within a few voxels
// beyond the band.
//
// mergeTiles() checks that the files are tiles of one bake (same tiling, box, parameters and
// dqjulia version) that cover its box once, unites the surfaces one tile at a time
// (csgUnion without pruning, then one pruneLevelSet: exact, where pruning after each union or
// merging trees is not), copies the attribute grids' voxels (each tile holds only its own) and
// makes the density from the merged surface, as the one-piece bake does.
//
// Cost: a tile evaluates its share of the bake's surface plus its halo's; tiles of a 1024^3
// bake are baked in the memory of their part. The merge holds the output's grids and one tile
// at a time: its memory follows the output, not the sum of the tiles.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dqjulia/bake.hpp"
#include "dqjulia/export.h"
#include "dqjulia/params.hpp"
#include "dqjulia/progress.hpp"

namespace dqj {

/// "2x2x2" (or "3x1x1"; counts from 1 to 256) as a Tile with index 1. Throws ParamError
/// (key "tiles") for anything else.
DQJ_API Tile parseTiling(const std::string& text);
/// The counts written as parseTiling() reads them: "2x2x2".
DQJ_API std::string tilingText(const Tile& tile);
/// How many tiles the tiling has.
DQJ_API int tileCount(const Tile& tile);
/// "out/a.vdb", 3 -> "out/a.tile_3.vdb": where tile 3 of the bake written to `path` goes.
DQJ_API std::string tilePath(const std::string& path, int index);
/// Refuses a tiling or tile that does not fit `params` (ParamError "tiles"): 1 to 256 tiles
/// along each axis, each at least 8 voxels wide, the index from 1 to the tile count.
DQJ_API void checkTile(const Params& params, const Tile& tile);
/// Voxels a tile bakes beyond the box it owns: 8 for band widths up to 3, 16 up to 11 (8 more
/// for each 8 of band beyond), and, when attribute grids are baked, what their seeds depend on:
/// the rounds the seeds spread (twice the colour depth in voxels, plus 8) and the region's
/// reach below the band (46 in all at 512^3, 76 at 1024^3, with the default band and depth).
DQJ_API int tileHalo(const BakeSettings& bake);

struct MergeStats {
    int tiles = 0;
    std::uint64_t activeVoxels = 0;  ///< active voxels of the merged surface
    std::uint64_t tileBytes = 0;     ///< the tiles' files added up
    double seconds = 0.0;
};

/// Merges the tiles (any order) into `path`, written as bakeVdb() writes the one-piece bake.
/// Throws ParamError (key "tiles") when the files are not tiles of one bake made by this
/// version of dqjulia, or do not cover it once (saying which are missing or repeated);
/// MemoryLimitError, before any grid is read, when the estimate (from the memory each tile's
/// grids take, in its metadata) exceeds `memoryLimit` (0: defaultMemoryLimit()) or what the
/// process may allocate; std::runtime_error when a file cannot be read or written; Cancelled.
DQJ_API MergeStats mergeTiles(const std::vector<std::string>& tiles, const std::string& path,
                              Existing existing = Existing::Replace, const ProgressCallback& progress = {},
                              std::uint64_t memoryLimit = 0);

}  // namespace dqj
