// OpenVDB's mesher step by step (bake/grid_mesher.hpp) against tools::VolumeToMesh as a whole:
// the same points, bit for bit, and the same polygons in the same pools, on a level set, on a
// float grid inside where positive (the faces turned the other way), on a field of many pieces,
// on a grid with no surface, and with adaptivity; the grid is let go in every case.
#include <gtest/gtest.h>

#include <cmath>

#include <openvdb/openvdb.h>
#include <openvdb/tools/VolumeToMesh.h>

#include "bake/grid_mesher.hpp"

using namespace dqj;

namespace {

/// VolumeToMesh on a copy of `grid`, then meshGrid on `grid`, and every point and polygon compared.
void expectSameAsVolumeToMesh(openvdb::FloatGrid::Ptr grid, double adaptivity, std::size_t leastPoints) {
    openvdb::tools::VolumeToMesh reference(0.0, adaptivity);
    reference(*grid->deepCopy());
    GridMesh mesh = meshGrid(grid, adaptivity);
    EXPECT_EQ(grid, nullptr);  // let go
    ASSERT_EQ(mesh.pointCount, reference.pointListSize());
    EXPECT_GE(mesh.pointCount, leastPoints);
    for (std::size_t index = 0; index < mesh.pointCount; ++index)
        ASSERT_EQ(mesh.points[index], reference.pointList()[index]) << "point " << index;
    ASSERT_EQ(mesh.poolCount, reference.polygonPoolListSize());
    std::size_t quads = 0, triangles = 0;
    for (std::size_t pool = 0; pool < mesh.poolCount; ++pool) {
        const openvdb::tools::PolygonPool& ours = mesh.pools[pool];
        const openvdb::tools::PolygonPool& theirs = reference.polygonPoolList()[pool];
        ASSERT_EQ(ours.numQuads(), theirs.numQuads()) << "pool " << pool;
        ASSERT_EQ(ours.numTriangles(), theirs.numTriangles()) << "pool " << pool;
        for (std::size_t index = 0; index < ours.numQuads(); ++index)
            ASSERT_EQ(ours.quad(index), theirs.quad(index)) << "pool " << pool << " quad " << index;
        for (std::size_t index = 0; index < ours.numTriangles(); ++index)
            ASSERT_EQ(ours.triangle(index), theirs.triangle(index)) << "pool " << pool << " triangle " << index;
        quads += ours.numQuads();
        triangles += ours.numTriangles();
    }
    if (adaptivity == 0.0) {  // a closed uniform mesh: a quad per crossed edge, about one per point
        EXPECT_GE(quads, leastPoints);
        EXPECT_EQ(triangles, 0u);
    }
}

/// A level set of a ball of radius 10 voxels, its distance clamped to 3 voxels.
openvdb::FloatGrid::Ptr sphere() {
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(3.0f);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    auto accessor = grid->getAccessor();
    for (int x = -14; x <= 14; ++x)
        for (int y = -14; y <= 14; ++y)
            for (int z = -14; z <= 14; ++z) {
                const double distance =
                    std::sqrt((x - 0.3) * (x - 0.3) + (y + 0.2) * (y + 0.2) + (z - 0.1) * (z - 0.1)) - 10.0;
                if (std::abs(distance) < 3.0) accessor.setValue(openvdb::Coord(x, y, z), float(distance));
            }
    return grid;
}

/// A dense field of many pieces, sin x sin y sin z on a 48^3 block: not a level set, so
/// VolumeToMesh takes positive values as inside.
openvdb::FloatGrid::Ptr pieces() {
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(-1.0f);
    auto accessor = grid->getAccessor();
    for (int x = 0; x < 48; ++x)
        for (int y = 0; y < 48; ++y)
            for (int z = 0; z < 48; ++z)
                accessor.setValue(openvdb::Coord(x, y, z), float(std::sin(0.41 * x + 0.2) * std::sin(0.37 * y - 0.1) *
                                                                 std::sin(0.45 * z + 0.3)));
    return grid;
}

}  // namespace

TEST(GridMesher, LevelSetSameAsVolumeToMesh) {
    auto grid = sphere();
    ASSERT_EQ(grid->getGridClass(), openvdb::GRID_LEVEL_SET);
    expectSameAsVolumeToMesh(grid, 0.0, 500);
}

TEST(GridMesher, InsidePositiveSameAsVolumeToMesh) {
    auto grid = sphere();
    grid->setGridClass(openvdb::GRID_UNKNOWN);
    expectSameAsVolumeToMesh(grid, 0.0, 500);
}

TEST(GridMesher, ManyPiecesSameAsVolumeToMesh) { expectSameAsVolumeToMesh(pieces(), 0.0, 10000); }

TEST(GridMesher, AdaptiveSameAsVolumeToMesh) {
    expectSameAsVolumeToMesh(sphere(), 0.5, 50);
    expectSameAsVolumeToMesh(pieces(), 0.5, 1000);
}

TEST(GridMesher, NoSurfaceGivesNothing) {
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(1.0f);
    grid->tree().setValue(openvdb::Coord(3, 4, 5), 2.0f);  // a leaf, all of it outside
    GridMesh mesh = meshGrid(grid, 0.0);
    EXPECT_EQ(grid, nullptr);
    EXPECT_EQ(mesh.pointCount, 0u);
    EXPECT_EQ(mesh.poolCount, 0u);
}
