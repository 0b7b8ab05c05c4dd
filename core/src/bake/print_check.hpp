// print_check.hpp - whether a mesh can be printed, checked before it is written (internal to
// libdqjulia; `dqjulia mesh --min-wall/--min-island/--largest-only`, and every .stl or .3mf).
//
// What is measured, on the mesh as it will be written:
// - Edges: each edge of each face (a quad's four sides, not its diagonal), by its two vertices.
//   An edge in one face is a boundary edge (a hole), in more than two a non-manifold edge. The
//   mesh is closed without boundary edges and edge-manifold without non-manifold ones.
// - Islands: the connected components (faces sharing a vertex), each with its faces, its
//   bounding box and, when it is closed, its volume (the signed volume its faces enclose:
//   the sum over its triangles of a.(b x c)/6, positive with faces counter-clockwise from outside).
// - The thinnest wall: the mesh's signed distance field (OpenVDB's meshToVolume: exact distances
//   to the faces, on the bake's voxel grid, 2 voxels inside and 1 outside). From the
//   centre of each face a ray goes inward along the face's normal, stepping by the distance
//   field (the distance to the nearest face, or 2 voxels deeper inside: a step that cannot pass
//   the far side, at least a quarter voxel), to where the field turns positive (found to about
//   1/500 voxel by halving): the wall's thickness there along the normal. A flat wall gets its thickness in any direction
//   (to the trilinear field's accuracy), a rod or a ball its diameter, a sharp tip its width near
//   the tip; the thinnest over all faces is reported, in output units, with its middle. Walls
//   are measured up to max(2 + --min-wall, kDefaultWallVoxels) voxels thick (256 at most).
//
// Memory: the mesh is checked whole (one piece in memory): the edges (8 bytes each, sorted),
// a label per vertex, and the distance field's band. A mesh that must be made in slabs for the
// memory limit is refused for the check before any sampling (meshForPrint).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "dqjulia/bake.hpp"
#include "dqjulia/mesh.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/progress.hpp"

namespace dqj {

/// Whether the output at `path` is for printing (.stl or .3mf, any case): such files are
/// written only when the check passes.
bool isPrintFormat(const std::string& path);

struct PrintIsland {
    std::uint64_t faces = 0;
    glm::dvec3 min{0.0}, max{0.0};  ///< bounding box, output units
    bool closed = true;             ///< no boundary edge
    double volume = 0.0;            ///< output units cubed; 0 unless closed
};

struct PrintOptions {
    double scale = 1.0;                ///< output units per mesh unit
    glm::dvec3 origin{0.0};            ///< mesh units: the output's 0 (output = (mesh - origin) * scale)
    double voxel = 0.0;                ///< the distance field's voxel, mesh units (the bake's voxel); 0: no wall check
    double minWall = 0.0;              ///< output units; 0: report the thinnest wall up to kDefaultWallVoxels
    std::uint64_t minIslandFaces = 0;  ///< islands with fewer faces are dropped
    bool largestOnly = false;          ///< keep the island with the most faces alone
};

/// Walls measured without --min-wall: up to this many voxels thick.
constexpr double kDefaultWallVoxels = 12.0;

struct PrintReport {
    std::uint64_t faces = 0;  ///< EdgeTally's: the faces seen (checkPrint counts them in islands)
    std::uint64_t edges = 0;
    std::uint64_t boundaryEdges = 0;     ///< in one face
    std::uint64_t nonManifoldEdges = 0;  ///< in three or more faces
    bool islandsCounted = false;         ///< checkPrint: islands and walls; EdgeTally: edges only
    std::vector<PrintIsland> islands;    ///< those kept, most faces first
    std::uint64_t droppedIslands = 0;
    std::uint64_t droppedFaces = 0;
    bool wallMeasured = false;       ///< false: no voxel given, or an empty mesh
    double thinnestWall = 0.0;       ///< output units; when no wall under wallLimit was found: wallLimit
    bool wallFound = false;          ///< a wall under wallLimit was found
    glm::dvec3 thinnestWallAt{0.0};  ///< output units: the middle of the thinnest wall found
    double wallLimit = 0.0;          ///< output units: walls are measured up to this thickness
    double minWall = 0.0;            ///< the minimum asked for (0: none)

    bool closed() const { return boundaryEdges == 0; }
    bool manifold() const { return nonManifoldEdges == 0; }
    /// Why the mesh cannot be printed ("" when it can): not closed, not edge-manifold, a wall
    /// under minWall, no faces left.
    std::string failure() const;
};

/// The island (connected component, by shared vertices) of each vertex, numbered from 0 in the
/// order of the vertices; `count` receives their number.
std::vector<std::uint32_t> vertexIslands(const Mesh& mesh, std::uint32_t& count);

/// Drops the islands under options.minIslandFaces faces, or all but the largest with
/// options.largestOnly, with their vertices (the rest keep their order). Fills the report's
/// droppedIslands and droppedFaces.
void dropIslands(Mesh& mesh, const PrintOptions& options, PrintReport& report);

/// Checks `mesh` (after dropIslands): edges, islands, the thinnest wall. Throws Cancelled when
/// `progress` returns false.
void checkPrint(const Mesh& mesh, const PrintOptions& options, PrintReport& report,
                const ProgressCallback& progress = {});

/// The report as stderr shows it: a few lines, the largest islands first.
std::string printReportText(const PrintReport& report);

/// The edges of a mesh that comes part by part (a MeshPartSink's parts, mesh_stream.hpp), counted
/// in a part's memory: an edge is settled once no later part can name both its vertices (a part's
/// faces name only its own vertices and the part's before), so only the last part's edges are
/// held (8 bytes a face side). Whether a streamed mesh is closed and edge-manifold, without
/// holding it whole; islands and walls need the mesh whole (checkPrint).
class EdgeTally {
public:
    void add(const Mesh& part);
    /// The report: faces, edges, boundaryEdges, nonManifoldEdges (islandsCounted false).
    const PrintReport& finish();

private:
    std::vector<std::uint64_t> open_;  // the edges the next part may still reach, a key a face side
    std::uint64_t vertices_ = 0;
    PrintReport report_;
};

/// bakeMeshFile, and with `approve` the mesh's edges counted as its parts are written (EdgeTally):
/// `approve(report)` runs before the file is published and may throw, which publishes nothing.
/// Memory and time as bakeMeshFile's, plus a part's edges.
MeshCounts bakeMeshFileChecked(const Params& params, const std::string& path, const BakeOptions& options,
                               const ProgressCallback& progress, BakeStats* stats, const MeshScale& scale,
                               const std::function<void(const PrintReport&)>& approve);

/// Meshes `params` in one piece like bakeMesh, drops islands and checks the rest (options.voxel
/// 0: the bake's voxel), in the units of a file written with `scale` (writeMesh: with a size, the
/// kept mesh's largest side is the size, its least corner 0). Throws like bakeMesh, and MemoryLimitError, before any sampling, when the
/// limit would mesh it in slabs; ParamError when the islands dropped would be all.
Mesh meshForPrint(const Params& params, const BakeOptions& options, PrintOptions print,
                  const ProgressCallback& progress, BakeStats& stats, PrintReport& report, const MeshScale& scale = {});

}  // namespace dqj
