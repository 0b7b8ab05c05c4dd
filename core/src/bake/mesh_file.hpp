// mesh_file.hpp - PLY and OBJ files of a mesh, written part by part as a streamed mesh's slabs
// come (mesh_stream.hpp), or a whole mesh as one part (writeMesh) (internal to libdqjulia).
//
// PLY (binary little-endian): float positions and normals, 8-bit sRGB colours, then the faces
// (quads and triangles, 32-bit indices). Each part's vertices go straight into the file; its
// faces, which must follow every vertex, go to a ScratchFile beside it and are appended at the
// end. OBJ (text): each part's `v x y z [r g b]`, `vn` and `f a//a ...` lines in turn (a face
// names vertices of its own or earlier parts). The counts, known only at the end, are in the
// header, which is written then into room kept for it (padded with spaces in a comment). The file
// is an AtomicFile: it appears complete at commit() or not at all; a failed write (a full disk)
// is reported by the add() after it. Cost: the file's bytes, and a PLY's faces twice.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "dqjulia/mesh.hpp"
#include "dqjulia/params.hpp"
#include "files/atomic_file.hpp"

namespace dqj {

class MeshFile {
public:
    /// Opens the temporary files beside `path` (.ply or .obj, any case: else ParamError). `colors`:
    /// whether the parts carry colours. Throws like AtomicFile (a folder not writable, an existing
    /// file with Existing::Keep).
    MeshFile(const std::string& path, bool colors, Existing existing);
    ~MeshFile();
    MeshFile(const MeshFile&) = delete;
    MeshFile& operator=(const MeshFile&) = delete;

    /// Appends `part`: its vertices follow those of the parts before, and its faces index every
    /// vertex so far (from 0). Throws std::runtime_error when a write failed or the vertices would
    /// pass 2^32 (the indices' size).
    void add(const Mesh& part);
    /// Writes the header, appends the faces and publishes the file under its name.
    void commit();

    const MeshCounts& counts() const { return counts_; }

private:
    bool ply_;
    bool colors_;
    AtomicFile file_;
    std::unique_ptr<ScratchFile> faces_;  // PLY: the faces until the end
    std::size_t headerRoom_ = 0;
    MeshCounts counts_;
};

}  // namespace dqj
