// vdb_file.hpp - OpenVDB files read with every length checked and written through AtomicFile
// (internal to libdqjulia). Cost: reading checks the file's container (header, metadata, grid
// descriptors) without allocating, then reads every grid whole; writing is OpenVDB's own
// (Archive, seekable), every byte checked, with Blosc (LZ4) compression by default: OpenVDB
// compresses every leaf twice, once on all threads (the sizes of its delayed-load metadata)
// and once on one thread as it writes.
#pragma once

#include <cstdint>
#include <string>

#include <openvdb/openvdb.h>

#include "files/atomic_file.hpp"

namespace dqj {

/// A file's metadata and grids.
struct VdbContents {
    openvdb::MetaMap::Ptr metadata;
    openvdb::GridPtrVecPtr grids;
};

/// Reads a whole VDB file. OpenVDB trusts the file's lengths and offsets (a truncated or
/// damaged file made it allocate gigabytes), so they are checked against the file's size
/// first, and any read past the end is an error. Throws std::runtime_error ("cannot read
/// 'path': reason").
VdbContents readVdbFile(const std::string& path);

/// The file's metadata alone (checked as readVdbFile checks; no grid is read).
openvdb::MetaMap::Ptr readVdbMetadata(const std::string& path);

/// The first grid named `name`, or null.
openvdb::GridBase::Ptr findGrid(const VdbContents& contents, const std::string& name);

/// How writeVdbFile compresses the grids' voxels (OpenVDB's io/Compression.h), always with
/// OpenVDB's active-mask compression (inactive voxels of the background value are left out):
/// Blosc = LZ4 through c-blosc, what every current VDB reader (Blender, Houdini, OpenVDB 3+)
/// reads; Zip = zlib's deflate, which OpenVDB applies to no level set or fog volume (those
/// are then written as with None); None = the voxels as they are. Every kind reads back.
enum class VdbCompression { Blosc, Zip, None };

/// OpenVDB's compression flags (io::COMPRESS_*) for `compression`.
std::uint32_t vdbCompressionFlags(VdbCompression compression);

/// Writes `grids` and `metadata` into `file` and commits it. Throws std::runtime_error with
/// the path and the reason ("No space left on device") on failure. Each grid records the
/// compression it was written with in its "file_compression" metadata (OpenVDB's words:
/// "blosc + active values").
void writeVdbFile(AtomicFile& file, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& metadata,
                  VdbCompression compression = VdbCompression::Blosc);

}  // namespace dqj
