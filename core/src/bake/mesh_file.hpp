// mesh_file.hpp - PLY, OBJ, STL and 3MF files of a mesh, written part by part as a streamed
// mesh's slabs come (mesh_stream.hpp), or a whole mesh as one part (writeMesh) (internal to
// libdqjulia).
//
// MeshFile chooses the format by the path's extension and hands it each part with its positions
// in output units. Without a size (MeshScale) those are the slice coordinates and every part goes
// straight to the format; with a size they are known only once the last part has come (the
// mesh's bounds), so the parts are set aside in a ScratchFile beside the target, as they come,
// and handed on at commit(), scaled (the mesh's bytes written twice; memory: a part).
//
// The formats (MeshFormat):
// - PLY (binary little-endian): float positions and normals, 8-bit sRGB colours, then the faces
//   (quads and triangles, 32-bit indices). Each part's vertices go straight into the file; its
//   faces, which must follow every vertex, go to a ScratchFile and are appended at the end.
// - OBJ (text): each part's `v x y z [r g b]`, `vn` and `f a//a ...` lines in turn (a face names
//   vertices of its own or earlier parts).
//   PLY and OBJ have their counts, known only at the end, in the header, which is written then
//   into room kept for it (padded with spaces in a comment).
// - STL (binary): an 80-byte header, the triangle count (patched at the end), then 50 bytes a
//   triangle: its face normal, its three corners (float), 0. Quads are split along their 0-2
//   diagonal, as Mesh::triangulated does. A triangle needs its corners' positions: the writer
//   keeps those of the current part and of the one before, which is all a face of a streamed mesh
//   can name (mesh_stream.hpp: a face's vertices lie within 2 voxels of its least x, slabs are 8
//   voxels or more, and a vertex goes out with the first slab whose faces use it); a face naming
//   an older vertex is a logic_error, never a wrong triangle. No colours: STL has no standard way.
// - 3MF: mesh_3mf.hpp.
// The file is an AtomicFile: it appears complete at commit() or not at all; a failed write (a full
// disk) is reported by the add() after it.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include <glm/vec3.hpp>

#include "dqjulia/mesh.hpp"
#include "dqjulia/params.hpp"
#include "files/atomic_file.hpp"

namespace dqj {

/// One file format's writer, fed part by part with positions in output units.
class MeshFormat {
public:
    virtual ~MeshFormat() = default;
    /// Writes (or sets aside) `part`, whose first vertex is number `firstVertex` of the mesh; its
    /// faces index the mesh's vertices (from 0). Checks the writes (a full disk throws here).
    virtual void add(const Mesh& part, std::uint64_t firstVertex) = 0;
    /// Writes what is left (header, faces set aside); the file is then ready to commit.
    virtual void finish(const MeshCounts& counts) = 0;
};

/// Where a mesh written with `scale` is placed: output = (position - origin) * factor. With a
/// size, its largest side (of the bounds `least` to `most`) becomes the size and its least corner
/// 0; without one, or for a mesh with no extent, it stays as it is.
struct MeshPlacement {
    glm::dvec3 origin{0.0};
    double factor = 1.0;
};
MeshPlacement meshPlacement(const MeshScale& scale, const glm::dvec3& least, const glm::dvec3& most);

class MeshFile {
public:
    /// Opens the temporary files beside `path` (.ply, .obj, .stl or .3mf, any case: else ParamError,
    /// as for a bad `scale`). `colors`: whether the parts carry colours. Throws like AtomicFile (a
    /// folder not writable, an existing file with Existing::Keep).
    MeshFile(const std::string& path, bool colors, Existing existing, const MeshScale& scale = {});
    ~MeshFile();
    MeshFile(const MeshFile&) = delete;
    MeshFile& operator=(const MeshFile&) = delete;

    /// Appends `part`: its vertices follow those of the parts before, and its faces index every
    /// vertex so far (from 0). Throws std::runtime_error when a write failed or the vertices would
    /// pass 2^32 (the indices' size) or the format's limit (STL: 2^32 - 1 triangles).
    void add(const Mesh& part);
    /// Writes the rest, publishes the file under its name.
    void commit();

    const MeshCounts& counts() const { return counts_; }

private:
    /// Hands `part` to the format, its positions placed (with a size: scaled and moved).
    void write(const Mesh& part);

    bool colors_;
    MeshScale scale_;
    AtomicFile file_;
    std::unique_ptr<MeshFormat> format_;
    std::unique_ptr<ScratchFile> parts_;  // with a size: the parts, until the scale is known
    glm::dvec3 least_, most_;             // the bounds of the positions so far (with a size)
    glm::dvec3 origin_{0.0};              // placed = (position - origin_) * factor_
    double factor_ = 1.0;
    std::uint64_t written_ = 0;  // vertices handed to the format
    MeshCounts counts_;
};

}  // namespace dqj
