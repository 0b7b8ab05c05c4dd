// bake_fixture.hpp - the fixture the tests of bakes, tiles and VDB files share: a scratch folder
// per test (test_support.hpp's ScratchFolder) with OpenVDB initialised, and a VDB file read back
// whole with OpenVDB (grids by name, file metadata).
#pragma once

#include <gtest/gtest.h>

#include <map>
#include <string>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "test_support.hpp"

namespace dqj::test {

/// ScratchFolder with OpenVDB initialised for the suite. Suites use it by name
/// (`using Bake = BakeFolder;`) or derive from it (tile_merge_check.hpp's Tiles).
class BakeFolder : public ScratchFolder {
public:
    static void SetUpTestSuite() { openvdb::initialize(); }
};

/// A VDB file read back with OpenVDB: its grids by name and its file metadata.
struct VdbFile {
    std::map<std::string, openvdb::GridBase::Ptr> grids;
    openvdb::MetaMap::Ptr metadata;
};

inline VdbFile readVdb(const std::string& path) {
    openvdb::io::File file(path);
    file.open();
    VdbFile result;
    const openvdb::GridPtrVecPtr grids = file.getGrids();
    for (const openvdb::GridBase::Ptr& grid : *grids) result.grids[grid->getName()] = grid;
    result.metadata = file.getMetadata();
    file.close();
    return result;
}

}  // namespace dqj::test
