// mesh_simplify.hpp - a mesh of at most N triangles by OpenVDB's adaptive meshing, and how far
// it strays from the full mesh (internal to libdqjulia; bake.max_faces, `dqjulia mesh --faces`).
//
// The search: the full mesh (adaptivity 0) if it is small enough; else bisection of the
// adaptivity in (0, 1] for the least that meets N (a mesh's faces fall as its adaptivity grows),
// each try meshing the same sampled grid. The result is then measured against the full mesh,
// the very surface the bake's level set holds (mesh.hpp): the distance from each of its
// vertices, and from 7 points on each of its triangles (the centre, the edge midpoints, and the
// points halfway between the centre and each corner), to the nearest full-mesh triangle, exact
// (a hash of the full mesh's triangles by 2-voxel cell, searched ring by ring until no nearer
// triangle can remain). A result beyond the stated bounds (kSimplifiedVertexBound,
// kSimplifiedSampleBound) is refused with both figures: never written silently.
// Why the bounds hold: OpenVDB merges cells only inside one 8^3 leaf and only where the
// surface's normals there agree within the adaptivity's threshold; a merged vertex is the mean
// of the merged cells' edge crossings, which lie on a surface that is nearly flat there.
// Measured (docs/baking.md): the default fractal and the ball at 128^3 and 256^3, several N.
// Cost: the sampling once; up to 12 meshings of the grid; the measure is about one nearest-
// triangle search per sample point. Memory: the grid, the full mesh and two candidates at once.
#pragma once

#include <cstdint>
#include <functional>

#include "dqjulia/mesh.hpp"
#include "dqjulia/progress.hpp"

namespace dqj {

/// The most a simplified mesh's vertex may lie from the full mesh, in voxels.
constexpr double kSimplifiedVertexBound = 1.5;
/// The most a point on a simplified mesh's face may lie from the full mesh, in voxels.
constexpr double kSimplifiedSampleBound = 4.0;

/// How far a mesh lies from a reference mesh's surface, in voxels: the farthest vertex, the
/// farthest sample point on its faces.
struct MeshDeviation {
    double vertices = 0.0;
    double samples = 0.0;
};

/// The deviation of `mesh` from `reference` (slice units, `voxel` the voxel size). A point
/// farther than 16 voxels from every reference triangle counts as 16 voxels (beyond any bound).
MeshDeviation meshDeviation(const Mesh& reference, const Mesh& mesh, double voxel);

/// What simplifyToFaces made.
struct SimplifiedMesh {
    Mesh mesh;
    double adaptivity = 0.0;          ///< the adaptivity chosen
    std::uint64_t fullTriangles = 0;  ///< the full mesh's triangles (a quad counts as two); 0: kept as it is
    MeshDeviation deviation;          ///< from the full mesh
};

/// The mesh of at most `maxTriangles` triangles (a quad counts as two) that `meshAt` (the mesher
/// at an adaptivity, the same grid each time) makes at the least adaptivity. Throws ParamError
/// ("bake.max_faces") when even adaptivity 1 gives more, or the result strays beyond the
/// bounds; Cancelled when `progress` says stop.
SimplifiedMesh simplifyToFaces(std::uint64_t maxTriangles, double voxel, const std::function<Mesh(double)>& meshAt,
                               const ProgressCallback& progress);

}  // namespace dqj
