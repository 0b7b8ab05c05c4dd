// tile_geometry.hpp - where one tile of a tiled bake lies on the whole bake's voxel grid, and the
// metadata naming a tile in its file, written by its bake and read by the merge (internal to
// libdqjulia; tiles.hpp has the idea; code in tile_geometry.cpp, with tiles.hpp's tiling, halo and
// checks: the bake of one tile needs them, the merge in tiles.cpp builds on them). Cost: a few
// integer operations; readTileHeader reads a file's metadata.
//
// The whole bake's index box (bakeIndexBox) is cut into counts[0] x counts[1] x counts[2]
// boxes, each axis evenly (tile t of c along an axis of n voxels starts at floor(t n / c)),
// so boundaries need not fall on leaves. A tile owns its box; the tiles on the outside also
// own everything beyond the index box (the narrow band reaches past it). It bakes its box
// grown by the halo, the window, and keeps only what it owns.
#pragma once

#include <cstdint>
#include <string>

#include <openvdb/openvdb.h>

#include "dqjulia/bake.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/tiles.hpp"

namespace dqj {

/// The voxels tile `tile` owns within `full` (the whole bake's index box).
openvdb::CoordBBox ownedBox(const openvdb::CoordBBox& full, const Tile& tile);

/// What the tile keeps: its owned box, open outwards where it lies on a face of `full`.
openvdb::CoordBBox keptBox(const openvdb::CoordBBox& full, const openvdb::CoordBBox& owned);

/// The voxels a tile samples: its owned box grown by tileHalo(params.bake).
openvdb::CoordBBox tileWindow(const Params& params, const Tile& tile);

/// The metadata naming a tile in its file: the tiling, the tile, the whole bake's index box,
/// the box the tile owns, the hash of `document` (the parameters, as written in the file),
/// dqjulia's version, and the memory its grids take (`gridBytes`: the merge's estimate).
void addTileMetadata(openvdb::MetaMap& metadata, const Params& params, const Tile& tile, const std::string& document,
                     std::uint64_t gridBytes);

/// "(x, y, z) to (x, y, z)": a box of voxels in a message.
std::string boxText(const openvdb::CoordBBox& box);

/// What a tile's file says about itself (its metadata only).
struct TileHeader {
    std::string path;
    Tile tile;
    openvdb::CoordBBox full, owned;
    std::string document, hash, version;
    double voxelSize = 0.0;
    std::uint64_t gridBytes = 0;  // the memory its grids take
};

/// The metadata of the tile at `path` (no grid is read), checked: a ParamError names what is
/// wrong with a file that is no tile of a dqjulia bake or a damaged one.
TileHeader readTileHeader(const std::string& path);

}  // namespace dqj
