// Where a tile of a tiled bake lies (tile_geometry.hpp, tiles.hpp): the tiling, its file names,
// the halo, each tile's box on the whole bake's grid, and the metadata naming a tile in its file,
// written by its bake and read by the merge.
#include "bake/tile_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "bake/attribute_reach.hpp"
#include "bake/sparse_sampler.hpp"
#include "dqjulia/version.h"
#include "files/message_text.hpp"
#include "files/vdb_file.hpp"

namespace dqj {

using openvdb::Coord;
using openvdb::CoordBBox;

namespace {

constexpr int kMaxTilesPerAxis = 256;
constexpr int kMinTileVoxels = 8;
constexpr int kOpenMargin = 64;  // voxels: further than a bake's band (32 at most) and leaves reach past its box

// The metadata of a tile's file (besides a bake's own: creator, dqjulia_parameters, dqjulia_voxel_size).
constexpr const char* kTilingKey = "dqjulia_tiling";
constexpr const char* kTileKey = "dqjulia_tile";
constexpr const char* kFullMinKey = "dqjulia_full_min";
constexpr const char* kFullMaxKey = "dqjulia_full_max";
constexpr const char* kOwnedMinKey = "dqjulia_tile_min";
constexpr const char* kOwnedMaxKey = "dqjulia_tile_max";
constexpr const char* kHashKey = "dqjulia_parameters_hash";
constexpr const char* kVersionKey = "dqjulia_version";
constexpr const char* kGridBytesKey = "dqjulia_tile_grid_bytes";

const char* const kAxisNames[3] = {"x", "y", "z"};

/// FNV-1a, 64 bits, as 16 hex digits: tells documents apart, not a defence against forgery.
std::string hashText(const std::string& text) {
    std::uint64_t hash = 14695981039346656037ull;
    for (const unsigned char byte : text) hash = (hash ^ byte) * 1099511628211ull;
    char digits[17];
    std::snprintf(digits, sizeof digits, "%016llx", static_cast<unsigned long long>(hash));
    return digits;
}

/// Where tile t of c starts along an axis of n voxels (relative to the axis' start).
int axisStart(int voxels, int count, int t) { return int(std::int64_t(t) * voxels / count); }

openvdb::Vec3i asVec(const Coord& ijk) { return openvdb::Vec3i(ijk.x(), ijk.y(), ijk.z()); }
Coord asCoord(const openvdb::Vec3i& v) { return Coord(v.x(), v.y(), v.z()); }

}  // namespace

std::string boxText(const CoordBBox& box) {
    const Coord lo = box.min(), hi = box.max();
    return "(" + std::to_string(lo.x()) + ", " + std::to_string(lo.y()) + ", " + std::to_string(lo.z()) + ") to (" +
           std::to_string(hi.x()) + ", " + std::to_string(hi.y()) + ", " + std::to_string(hi.z()) + ")";
}

TileHeader readTileHeader(const std::string& path) {
    const openvdb::MetaMap::Ptr metadata = readVdbMetadata(path);
    auto fail = [&](const std::string& why) { return ParamError("tiles", "'" + inputExcerpt(path) + "' " + why); };
    if (!(*metadata)[kTilingKey])
        throw fail("is not a tile of a dqjulia bake (no " + std::string(kTilingKey) +
                   " metadata): bake tiles with dqjulia bake --tiles AxBxC");
    TileHeader header;
    header.path = path;
    try {
        header.tile = parseTiling(metadata->metaValue<std::string>(kTilingKey));
        header.tile.index = metadata->metaValue<openvdb::Int32>(kTileKey);
        header.full = CoordBBox(asCoord(metadata->metaValue<openvdb::Vec3i>(kFullMinKey)),
                                asCoord(metadata->metaValue<openvdb::Vec3i>(kFullMaxKey)));
        header.owned = CoordBBox(asCoord(metadata->metaValue<openvdb::Vec3i>(kOwnedMinKey)),
                                 asCoord(metadata->metaValue<openvdb::Vec3i>(kOwnedMaxKey)));
        header.document = metadata->metaValue<std::string>("dqjulia_parameters");
        header.hash = metadata->metaValue<std::string>(kHashKey);
        header.version = metadata->metaValue<std::string>(kVersionKey);
        header.voxelSize = metadata->metaValue<double>("dqjulia_voxel_size");
        header.gridBytes =
            std::uint64_t(std::max<openvdb::Int64>(0, metadata->metaValue<openvdb::Int64>(kGridBytesKey)));
    } catch (const ParamError&) {
        throw fail("is a damaged tile: its tiling metadata cannot be read");
    } catch (const openvdb::Exception&) {
        throw fail("is a damaged tile: some of its metadata is missing or of the wrong type");
    }
    if (hashText(header.document) != header.hash)
        throw fail("is a damaged tile: its parameters do not match their hash");
    if (header.tile.index < 1 || header.tile.index > tileCount(header.tile) ||
        ownedBox(header.full, header.tile) != header.owned)
        throw fail("is a damaged tile: its box " + boxText(header.owned) + " is not tile " +
                   std::to_string(header.tile.index) + " of " + tilingText(header.tile));
    return header;
}

Tile parseTiling(const std::string& text) {
    Tile tile;
    std::size_t position = 0;
    bool ok = true;
    for (int axis = 0; axis < 3 && ok; ++axis) {
        if (axis > 0) ok = position < text.size() && (text[position] == 'x' || text[position] == 'X') && ++position;
        const std::size_t begin = position;
        while (position < text.size() && position - begin < 4 && text[position] >= '0' && text[position] <= '9')
            ++position;
        ok = ok && position > begin && position - begin < 4;
        if (ok) tile.counts[axis] = std::stoi(text.substr(begin, position - begin));
        ok = ok && tile.counts[axis] >= 1 && tile.counts[axis] <= kMaxTilesPerAxis;
    }
    if (!ok || position != text.size())
        throw ParamError("tiles", "tiles \"" + inputExcerpt(text) +
                                      "\": expected AxBxC, tiles along x, y and z from 1 to " +
                                      std::to_string(kMaxTilesPerAxis) + " each, e.g. 2x2x2");
    return tile;
}

std::string tilingText(const Tile& tile) {
    return std::to_string(tile.counts[0]) + "x" + std::to_string(tile.counts[1]) + "x" + std::to_string(tile.counts[2]);
}

int tileCount(const Tile& tile) { return tile.counts[0] * tile.counts[1] * tile.counts[2]; }

std::string tilePath(const std::string& path, int index) {
    const std::size_t slash = path.find_last_of('/');
    std::size_t dot = path.rfind('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) dot = path.size();
    return path.substr(0, dot) + ".tile_" + std::to_string(index) + path.substr(dot);
}

int tileHalo(const BakeSettings& bake) {
    // The level set: the rebuilt distance near a cut face depends on the surface a few voxels
    // beyond the band (at least 5, 6, 7 voxels for band widths 1, 3, 6): leaves of 8, two for
    // wider bands. So the tile's level set (its band's values and active states, the inside's
    // signs) is the whole bake's at every voxel at least this far inside the tile's window.
    const int band = int(std::ceil(bake.bandWidth));
    const int levelSet = 8 * ((band + 5 + 7) / 8);
    if (!hasGrid(bake, BakeGrid::Color) && !hasGrid(bake, BakeGrid::Trap) && !hasGrid(bake, BakeGrid::Iterations))
        return levelSet;
    // The attribute grids (bake.cpp, addAttributeGrids) are the whole bake's on the kept box K:
    // - Their region and seeds are made from the level set alone, each voxel's from a few
    //   around it: a voxel is in the region if it is in the band, or inside and within
    //   attributeDilation() 26-neighbour steps of the band; it is a seed if it and a face
    //   neighbour lie on either side of the surface, its point and its values (the orbit
    //   there) taken from it and its 6 face neighbours. So both are the whole bake's wherever
    //   the level set is, within max(dilation, 1) steps: up to levelSet + max(dilation, 1)
    //   voxels inside the window.
    // - nearestSeeds runs at most attributeRounds() rounds, and after r rounds a voxel's seed
    //   depends on the region and the seeds within r steps of it alone (nearest_seed.hpp), ties
    //   going to the lower seed index. Both bakes number the seeds in the level set tree's
    //   order of their voxels (leaf by leaf, each leaf's in offset order), a fixed order of
    //   coordinates, so any two seeds they share compare alike.
    // So a halo of levelSet + rounds + max(dilation, 1) gives every voxel of K the whole bake's
    // seed, ties included, hence its colour, trap and iteration count. Nothing in this uses the
    // resolution, the tiling or where the tile lies (on the whole bake's outer faces the window
    // is cut where the whole is), only the band and the colour depth in voxels, which the halo
    // follows: it holds at any size. (Before, the halo added only the dilation and the seeds
    // spread until nothing changed, so nothing bounded how far a seed travels: at 512^3 a few
    // seam voxels took seeds from near the tile's cut face, where the tile's level set, and so
    // its seeds, are not the whole bake's. tiles_test.cpp, seam512, holds that case.)
    return levelSet + attributeRounds(bake) + std::max(attributeDilation(bake), 1);
}

void checkTile(const Params& params, const Tile& tile) {
    for (int axis = 0; axis < 3; ++axis)
        if (tile.counts[axis] < 1 || tile.counts[axis] > kMaxTilesPerAxis)
            throw ParamError("tiles", "tiles " + tilingText(tile) + ": expected from 1 to " +
                                          std::to_string(kMaxTilesPerAxis) + " tiles along each axis");
    const CoordBBox full = bakeIndexBox(params);
    for (int axis = 0; axis < 3; ++axis) {
        const int voxels = full.dim()[axis];
        if (voxels / tile.counts[axis] < kMinTileVoxels)
            throw ParamError("tiles", "tiles " + tilingText(tile) + ": the bake is " + std::to_string(voxels) +
                                          " voxels along " + kAxisNames[axis] + ", so at most " +
                                          std::to_string(voxels / kMinTileVoxels) + " tiles of at least " +
                                          std::to_string(kMinTileVoxels) + " voxels fit along it");
    }
    if (tile.index < 1 || tile.index > tileCount(tile))
        throw ParamError("tiles", "tile " + std::to_string(tile.index) + ": the tiling " + tilingText(tile) +
                                      " has tiles 1 to " + std::to_string(tileCount(tile)));
}

CoordBBox ownedBox(const CoordBBox& full, const Tile& tile) {
    const int index = tile.index - 1;
    const int t[3] = {index % tile.counts[0], (index / tile.counts[0]) % tile.counts[1],
                      index / (tile.counts[0] * tile.counts[1])};
    Coord lo, hi;
    for (int axis = 0; axis < 3; ++axis) {
        const int voxels = full.dim()[axis];
        lo[axis] = full.min()[axis] + axisStart(voxels, tile.counts[axis], t[axis]);
        hi[axis] = full.min()[axis] + axisStart(voxels, tile.counts[axis], t[axis] + 1) - 1;
    }
    return CoordBBox(lo, hi);
}

CoordBBox keptBox(const CoordBBox& full, const CoordBBox& owned) {
    Coord lo = owned.min(), hi = owned.max();
    for (int axis = 0; axis < 3; ++axis) {
        if (lo[axis] == full.min()[axis]) lo[axis] -= kOpenMargin;
        if (hi[axis] == full.max()[axis]) hi[axis] += kOpenMargin;
    }
    return CoordBBox(lo, hi);
}

CoordBBox tileWindow(const Params& params, const Tile& tile) {
    CoordBBox window = ownedBox(bakeIndexBox(params), tile);
    window.expand(tileHalo(params.bake));
    return window;
}

void addTileMetadata(openvdb::MetaMap& metadata, const Params& params, const Tile& tile, const std::string& document,
                     std::uint64_t gridBytes) {
    const CoordBBox full = bakeIndexBox(params);
    const CoordBBox owned = ownedBox(full, tile);
    metadata.insertMeta(kTilingKey, openvdb::StringMetadata(tilingText(tile)));
    metadata.insertMeta(kTileKey, openvdb::Int32Metadata(tile.index));
    metadata.insertMeta(kFullMinKey, openvdb::Vec3IMetadata(asVec(full.min())));
    metadata.insertMeta(kFullMaxKey, openvdb::Vec3IMetadata(asVec(full.max())));
    metadata.insertMeta(kOwnedMinKey, openvdb::Vec3IMetadata(asVec(owned.min())));
    metadata.insertMeta(kOwnedMaxKey, openvdb::Vec3IMetadata(asVec(owned.max())));
    metadata.insertMeta(kHashKey, openvdb::StringMetadata(hashText(document)));
    metadata.insertMeta(kVersionKey, openvdb::StringMetadata(DQJ_VERSION_STRING));
    metadata.insertMeta(kGridBytesKey, openvdb::Int64Metadata(openvdb::Int64(gridBytes)));
}

}  // namespace dqj
