// vdb_file.hpp - OpenVDB files read with every length checked and written through AtomicFile
// (internal to libdqjulia). Cost: reading checks the file's container (header, metadata, grid
// descriptors) without allocating, then reads every grid whole; writing is OpenVDB's own
// (Archive, seekable), every byte checked.
#pragma once

#include <string>

#include <openvdb/openvdb.h>

#include "atomic_file.hpp"

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

/// Writes `grids` and `metadata` into `file` and commits it. Throws std::runtime_error with
/// the path and the reason ("No space left on device") on failure.
void writeVdbFile(AtomicFile& file, const openvdb::GridPtrVec& grids, const openvdb::MetaMap& metadata);

}  // namespace dqj
