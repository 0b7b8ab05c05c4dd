// mesh_3mf.hpp - the 3MF writer of MeshFile (mesh_file.hpp; internal to libdqjulia).
//
// A 3MF is an OPC package, a ZIP of XML: [Content_Types].xml, _rels/.rels and 3D/3dmodel.model,
// whose <model> (core specification 1.3, unit from MeshScale) holds one object's mesh - vertices,
// then triangles (quads split along their 0-2 diagonal, as Mesh::triangulated does) - and, with
// colours, a Materials extension <m:colorgroup> of one sRGB colour per vertex, which each triangle
// names per corner (pid, then p1 p2 p3: the colour's number is the vertex's; the object's pid would
// do by the specification, but lib3mf reads p1-p3 only beside a pid). Resources must come before
// what names them, so the colours, the vertices and the triangles each go to a ScratchFile beside
// the target as the parts come, as XML text, and the package is made at the end: the model deflated
// from the three in turn (ZipWriter, files/zip_file.hpp; ZIP64 when the model passes 4 GB).
//
// Why not lib3mf (Debian has lib3mf-dev): it builds the whole model in memory before it writes,
// which would undo the slab streaming of a large mesh (mesh_stream.hpp), and what ships must link it
// statically (one more library to build into the deps cache, with its own libzip and zlib copies).
// The subset written here is small, and the tests read it back with lib3mf's own Python binding
// and trimesh.
#pragma once

#include <memory>

#include "bake/mesh_file.hpp"

namespace dqj {

/// The 3MF format for `file`: colours (the parts carry them) or not, the model's unit.
std::unique_ptr<MeshFormat> makeThreeMfFormat(AtomicFile& file, bool colors, MeshUnit unit);

}  // namespace dqj
