// attribute_grids.hpp - the bake's attribute grids ("color", "trap", "iterations"): every voxel
// of the band and of the inside below it to the colour depth holds the value at the surface point
// nearest to it (internal to libdqjulia; code in attribute_grids.cpp). Cost: one fractal
// evaluation per surface seed, and nearestSeeds' propagation over the covered voxels.
#pragma once

#include <openvdb/openvdb.h>

#include "dqjulia/bake.hpp"
#include "dqjulia/params.hpp"

namespace dqj {

/// The attribute grids ("color", "trap", "iterations") on attributeVoxels(), within `kept` if
/// given (a tile's), each an extension field: every voxel holds the value at the surface point
/// nearest to it, so the inside shows, through the depth light reaches, the colour its surface
/// has, as the mesh's vertices and the preview do; a voxel's own orbit would give the inside's
/// colour instead (bounded orbits: the palette's far end). One fractal evaluation per surface
/// seed (surfaceSeeds), then each voxel takes its nearest seed (nearestSeeds, in at most
/// attributeRounds() rounds), one propagation for all the grids; colour and smooth count from
/// coloring.hpp. A tile works on all it baked, its halo included, and keeps its box, where every
/// voxel's seed is the whole bake's (tileHalo says why).
void addAttributeGrids(const Params& params, const openvdb::FloatGrid& surface, const openvdb::CoordBBox* kept,
                       const ProgressCallback& progress, BakeStats& stats, openvdb::GridPtrVec& grids);

}  // namespace dqj
