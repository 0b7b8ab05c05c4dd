// bake_fixture.hpp - the fixture the tests of bakes, tiles and VDB files share: a scratch folder
// per test (test_support.hpp's ScratchFolder) with OpenVDB initialised, and a VDB file read back
// whole with OpenVDB (grids by name, file metadata).
#pragma once

#include <gtest/gtest.h>

#include <map>
#include <string>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>

#include "dqjulia/params.hpp"
#include "test_support.hpp"

namespace dqj::test {

/// ScratchFolder with OpenVDB initialised for the suite. Suites use it by name
/// (`using Bake = BakeFolder;`) or derive from it (tile_merge_check.hpp's Tiles).
class BakeFolder : public ScratchFolder {
public:
    static void SetUpTestSuite() { openvdb::initialize(); }
};

/// The default fractal baked at `resolution` voxels across.
inline Params defaultAt(int resolution) {
    Params params;
    params.bake.resolution = resolution;
    return params;
}

/// c = 0 and bailout 4: the unit ball, in the box [-1.5, 1.5]^3 at `resolution`, no colours.
inline Params ballAt(int resolution) {
    Params params = defaultAt(resolution);
    params.fractal.c = DualQuat{};
    params.fractal.bailout = 4.0;
    params.bake.bounds = Box{glm::dvec3(-1.5), glm::dvec3(1.5)};
    params.bake.meshColors = false;
    return params;
}

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
