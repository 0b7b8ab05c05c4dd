// mesh_stream.hpp - the baked surface meshed in one piece or, where that would exceed the memory
// limit, slab by slab across x, each slab handed on as it is made (internal to libdqjulia; the
// one mesher of bakeMesh and bakeMeshFile, mesh.hpp).
//
// A mesh in one piece: the sparse sampling of f (sparse_sampler.hpp), OpenVDB's volumeToMesh,
// vertex normals (area-weighted) and colours. When the sampler refuses the whole surface for
// the limit, the classification alone is run (countLeafLayers) and the slabs are planned from
// its leaves per layer of 8 voxels: each as many layers as its estimate allows; a layer that
// cannot fit alone is refused then, before any sampling.
//
// Slab k owns the faces whose least vertex x (their "x") lies in [X_k, X_k+1) (slab bounds on
// leaf boundaries; the first and last slabs are open outwards). It samples f on its slab grown
// by kSlabHalo voxels, where f is the whole bake's (sparse_sampler.hpp: all but the outer leaf),
// and meshes that: a face's four vertices lie in the 2 x 2 x 1 cells around its edge, so within
// 2 voxels of its x, and every face it owns, and every face around the vertices of those,
// comes from cells within 5 voxels of the slab, meshed from the whole bake's values: the same
// positions to the bit, the same faces, the same normals (summed in another order: to rounding).
// A vertex goes out with the first slab whose faces use it; the vertices the next slab may
// share (those at x >= X_k+1) are remembered by position until it has been made. Adaptivity
// > 0 merges cells across slab bounds, so such meshes are made in one piece only.
// Cost: one piece, as before; in slabs, the classification once more, and a slab's halo
// sampled twice (32 voxels a slab). Memory: the largest slab's sampling and meshing, and the
// seam's vertices.
#pragma once

#include <functional>

#include "dqjulia/bake.hpp"
#include "dqjulia/mesh.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/progress.hpp"

namespace dqj {

/// Voxels a slab is sampled beyond its bounds on either side: a leaf for the faces and normals
/// near its bounds (5 voxels), a leaf where f may differ from the whole bake's.
constexpr int kSlabHalo = 16;

/// Receives the mesh part by part: a part's vertices follow those of the parts before it, its
/// faces index every vertex so far. A mesh in one piece is one part.
using MeshPartSink = std::function<void(Mesh&& part)>;

/// slabVoxels for meshSurface: in one piece, or MemoryLimitError where the limit would ask for slabs.
constexpr int kOnePieceOnly = -1;

/// Meshes `params` (validated) into `sink`. `slabVoxels` > 0 (a multiple of 8) forces slabs that
/// thick (tests); 0 meshes in one piece where the limit allows; kOnePieceOnly in one piece or not at all. Fills `stats`. Throws like
/// bakeMesh: MemoryLimitError (before sampling), Cancelled, ParamError.
void meshSurface(const Params& params, const BakeOptions& options, const ProgressCallback& progress,
                 const MeshPartSink& sink, BakeStats& stats, int slabVoxels = 0);

}  // namespace dqj
