// dqjulia/mesh.hpp - a polygon mesh of the baked surface, and PLY / OBJ / STL / 3MF files of it.
//
// The mesh is OpenVDB's volumeToMesh of the bake's surface function (bake.hpp) at
// bake.adaptivity - the very surface the bake's level set holds, since levelSetRebuild is the
// distance to this mesh. Quads (and, with adaptivity, triangles), one vertex per surface cell,
// closed wherever the surface is closed (always: the solid is cut to the bounds), no face with
// a repeated vertex. Vertex normals are the area-weighted average of the faces around them;
// colours are the material's colouring of the orbit at each vertex (as the renderer shades it).
// Cost: the bake's sparse sampling, a volumeToMesh, and one fractal evaluation per vertex for
// colours; no level set is built.
//
// Where the surface's sampling and meshing would exceed the memory limit (BakeOptions), the
// surface is meshed in slabs across x, each as thick as the limit allows (mesh_stream.hpp in the
// core): the same mesh, geometry and connectivity (at adaptivity 0; with adaptivity > 0 a mesh is
// made in one piece), with vertices in another order. bakeMeshFile writes each slab out as it
// comes, so its memory is bounded by a slab; bakeMesh holds the whole mesh.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "dqjulia/bake.hpp"
#include "dqjulia/export.h"
#include "dqjulia/params.hpp"
#include "dqjulia/progress.hpp"

namespace dqj {

struct Mesh {
    std::vector<glm::vec3> positions;                     ///< slice coordinates
    std::vector<glm::vec3> normals;                       ///< unit, out of the solid; one per vertex
    std::vector<glm::vec3> colors;                        ///< linear RGB per vertex; empty without mesh colours
    std::vector<std::array<std::uint32_t, 3>> triangles;  ///< counter-clockwise seen from outside
    std::vector<std::array<std::uint32_t, 4>> quads;      ///< counter-clockwise seen from outside

    /// Triangles once every quad is split in two.
    std::size_t triangleCount() const { return triangles.size() + 2 * quads.size(); }
    /// Every face as triangles (quads split along their 0-2 diagonal), 3 indices each.
    DQJ_API std::vector<std::uint32_t> triangulated() const;
};

/// What a mesh file holds.
struct MeshCounts {
    std::uint64_t vertices = 0;
    std::uint64_t quads = 0;
    std::uint64_t triangles = 0;
};

/// Meshes `params` (validated; see bakeVdb for frames). Throws like bakeVdb. `stats` (optional)
/// receives the bake's counters.
DQJ_API Mesh bakeMesh(const Params& params, const BakeOptions& options = {}, const ProgressCallback& progress = {},
                      BakeStats* stats = nullptr);

/// The length unit of a mesh file's coordinates (`dqjulia mesh --units`).
enum class MeshUnit { Millimeter, Centimeter, Meter, Inch };

/// A mesh file's physical size: a `size` scales the mesh uniformly so that its largest side is
/// `size` units long and moves it into the positive octant (least corner at 0, as printers
/// expect); none writes slice coordinates as they are. `unit` is the 3MF's unit attribute (the
/// other formats carry no unit). Sizes above 0 up to kMaxMeshSizeMetres (1 km) are accepted.
struct MeshScale {
    MeshUnit unit = MeshUnit::Millimeter;
    std::optional<double> size;
};

/// The unit's name in flags and docs ("mm", "cm", "m", "in") and its length in metres.
DQJ_API const char* meshUnitName(MeshUnit unit);
DQJ_API double meshUnitMetres(MeshUnit unit);
/// The largest MeshScale::size, in metres (1 km: no print and no scene is larger).
constexpr double kMaxMeshSizeMetres = 1000.0;
/// Throws ParamError ("mesh.size") unless `scale.size` is none or a number above 0 no larger than
/// kMaxMeshSizeMetres in its unit.
DQJ_API void checkMeshScale(const MeshScale& scale);

/// Throws ParamError ("output.path") unless `path` ends in a mesh file's extension: .ply, .obj,
/// .stl or .3mf (any case).
DQJ_API void checkMeshPath(const std::string& path);

/// Meshes `params` into the file `path` (as writeMesh writes it), slab by slab where the memory
/// limit asks for it, each slab written as it is made: the file appears complete or not at all
/// (options.existing decides whether it may replace one). Throws like bakeMesh and writeMesh;
/// Cancelled (the callback returned false, at any slab, or at 1.0 just before the file is published)
/// leaves no file behind.
DQJ_API MeshCounts bakeMeshFile(const Params& params, const std::string& path, const BakeOptions& options = {},
                                const ProgressCallback& progress = {}, BakeStats* stats = nullptr,
                                const MeshScale& scale = {});

/// What meshing `params` will take, known before it starts (estimateMesh).
struct MeshEstimate {
    std::uint64_t bytes = 0;  ///< the memory estimate checked against the limit: the one piece's, or the largest slab's
    std::uint64_t slabs = 0;  ///< 1: in one piece
    std::uint64_t faces =
        0;  ///< about how many triangles (a quad counts as two): within a third; at most bake.max_faces
    std::uint64_t limit = 0;  ///< the limit the estimate was checked against, in bytes
};

/// What bakeMesh or bakeMeshFile would take with `params` (validated) and `options`, from the
/// classification of the blocks alone (no sampling: a few percent of the mesh's time). Throws
/// MemoryLimitError with the reason when the mesh cannot fit the limit even slab by slab (or,
/// for adaptive and bake.max_faces meshes, in one piece), as bakeMesh would; Cancelled.
DQJ_API MeshEstimate estimateMesh(const Params& params, const BakeOptions& options = {},
                                  const ProgressCallback& progress = {});

/// Writes a mesh file by the path's extension:
/// - `.ply`: binary little-endian, float positions and normals, 8-bit sRGB colours, quads and
///   triangles;
/// - `.obj`: text, `v x y z [r g b]`, `vn`, `f a//a ...`;
/// - `.stl`: binary STL, triangles (quads split along their 0-2 diagonal) with their face normals;
///   no colours (STL has no standard way to hold them);
/// - `.3mf`: the 3MF core mesh (triangles, as STL), vertex colours (sRGB) through the Materials
///   extension's colour group, the unit from `scale`.
/// Temporary file + rename. Throws ParamError for another extension or a bad `scale`,
/// std::runtime_error for I/O.
DQJ_API void writeMesh(const Mesh& mesh, const std::string& path, Existing existing = Existing::Replace,
                       const MeshScale& scale = {});

}  // namespace dqj
