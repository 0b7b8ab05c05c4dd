// The print check (bake/print_check.hpp) on shapes with known answers: two spheres (two islands,
// their sizes and volumes), plates of known thickness (the thinnest wall, axis-aligned and
// tilted), the c = 0 ball (one closed island, its volume, its diameter as its wall), an open box
// (boundary edges), three faces on one edge (non-manifold), and dropping islands.
#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <numbers>

#include <glm/geometric.hpp>
#include <glm/gtc/quaternion.hpp>
#include "bake/mesh_stream.hpp"
#include "bake/print_check.hpp"
#include "bake_fixture.hpp"
#include "dqjulia/mesh.hpp"

using namespace dqj;

namespace {

/// A box as six quads, counter-clockwise from outside, turned by `turn` about its centre.
void addBox(Mesh& mesh, glm::dvec3 min, glm::dvec3 max, glm::dquat turn = glm::dquat(1, 0, 0, 0)) {
    const auto first = std::uint32_t(mesh.positions.size());
    const glm::dvec3 centre = (min + max) / 2.0;
    for (int corner = 0; corner < 8; ++corner) {
        const glm::dvec3 p((corner & 1) ? max.x : min.x, (corner & 2) ? max.y : min.y, (corner & 4) ? max.z : min.z);
        mesh.positions.emplace_back(centre + turn * (p - centre));
        mesh.normals.emplace_back(0.0f);
    }
    const std::array<std::array<std::uint32_t, 4>, 6> faces = {{
        {0, 2, 3, 1},
        {4, 5, 7, 6},  // z-, z+
        {0, 1, 5, 4},
        {2, 6, 7, 3},  // y-, y+
        {0, 4, 6, 2},
        {1, 3, 7, 5},  // x-, x+
    }};
    for (const auto& face : faces)
        mesh.quads.push_back({first + face[0], first + face[1], first + face[2], first + face[3]});
}

/// A sphere: an octahedron's faces split in four `levels` times, the vertices pushed out onto
/// the sphere (so the box is exact: the octahedron's corners stay).
void addSphere(Mesh& mesh, glm::dvec3 centre, double radius, int levels = 5) {
    std::vector<glm::dvec3> points;
    std::vector<std::array<std::uint32_t, 3>> triangles;
    for (int axis = 0; axis < 3; ++axis)
        for (const double sign : {1.0, -1.0}) {
            glm::dvec3 p(0.0);
            p[axis] = sign;
            points.push_back(p);
        }
    for (int corner = 0; corner < 8; ++corner) {
        const std::uint32_t x = corner & 1, y = 2 + ((corner >> 1) & 1), z = 4 + ((corner >> 2) & 1);
        const bool flipped = ((corner & 1) + ((corner >> 1) & 1) + ((corner >> 2) & 1)) % 2 == 1;
        triangles.push_back(flipped ? std::array<std::uint32_t, 3>{x, z, y} : std::array<std::uint32_t, 3>{x, y, z});
    }
    for (int level = 0; level < levels; ++level) {
        std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> middles;
        auto middle = [&](std::uint32_t a, std::uint32_t b) {
            const auto key = std::minmax(a, b);
            const auto found = middles.find(key);
            if (found != middles.end()) return found->second;
            points.push_back(glm::normalize(points[a] + points[b]));
            return middles[key] = std::uint32_t(points.size() - 1);
        };
        std::vector<std::array<std::uint32_t, 3>> split;
        for (const auto& [a, b, c] : triangles) {
            const std::uint32_t ab = middle(a, b), bc = middle(b, c), ca = middle(c, a);
            split.insert(split.end(), {{a, ab, ca}, {ab, b, bc}, {ca, bc, c}, {ab, bc, ca}});
        }
        triangles = std::move(split);
    }
    const auto first = std::uint32_t(mesh.positions.size());
    for (const glm::dvec3& p : points) {
        mesh.positions.emplace_back(centre + radius * p);
        mesh.normals.emplace_back(p);
    }
    for (const auto& [a, b, c] : triangles) mesh.triangles.push_back({first + a, first + b, first + c});
}

PrintReport check(const Mesh& mesh, double voxel, double minWall = 0.0) {
    PrintOptions options;
    options.voxel = voxel;
    options.minWall = minWall;
    PrintReport report;
    checkPrint(mesh, options, report);
    return report;
}

constexpr double kPi = std::numbers::pi;

TEST(PrintCheck, TwoSpheresAreTwoClosedIslandsOfTheirSizes) {
    Mesh mesh;
    addSphere(mesh, glm::dvec3(0.0), 1.0);
    addSphere(mesh, glm::dvec3(3.0, 0.0, 0.0), 0.5, 4);
    const PrintReport report = check(mesh, 0.05);
    EXPECT_TRUE(report.closed()) << report.boundaryEdges;
    EXPECT_TRUE(report.manifold()) << report.nonManifoldEdges;
    ASSERT_EQ(report.islands.size(), 2u);
    const double radii[2] = {1.0, 0.5};
    const glm::dvec3 centres[2] = {glm::dvec3(0.0), glm::dvec3(3.0, 0.0, 0.0)};
    for (int index = 0; index < 2; ++index) {
        const PrintIsland& island = report.islands[std::size_t(index)];  // the larger first
        EXPECT_TRUE(island.closed);
        for (int axis = 0; axis < 3; ++axis) {
            EXPECT_NEAR(island.max[axis] - island.min[axis], 2.0 * radii[index], 0.02) << index << " " << axis;
            EXPECT_NEAR((island.max[axis] + island.min[axis]) / 2.0, centres[index][axis], 0.01);
        }
        const double volume = 4.0 / 3.0 * kPi * std::pow(radii[index], 3.0);
        EXPECT_NEAR(island.volume, volume, 0.02 * volume) << index;
    }
    EXPECT_GT(report.islands[0].faces, 3 * report.islands[1].faces);  // four times the area
    EXPECT_EQ(report.failure(), "");
    // The thinnest wall: the small sphere's diameter, once walls that thick are measured.
    const PrintReport walls = check(mesh, 0.05, 1.2);
    ASSERT_TRUE(walls.wallFound);
    EXPECT_NEAR(walls.thinnestWall, 1.0, 0.05);
    EXPECT_NEAR(walls.thinnestWallAt.x, 3.0, 0.05);  // its middle: the small sphere's centre
    EXPECT_NE(walls.failure().find("its thinnest wall, 0.99"), std::string::npos) << walls.failure();
    EXPECT_NE(walls.failure().find("is under --min-wall 1.2"), std::string::npos) << walls.failure();
}

TEST(PrintCheck, APlateIsAsThickAsItIsWhateverItsDirection) {
    const double voxel = 0.02;
    const glm::dquat turns[] = {glm::dquat(1, 0, 0, 0), glm::angleAxis(0.5, glm::normalize(glm::dvec3(1, 2, 0))),
                                glm::angleAxis(0.9, glm::normalize(glm::dvec3(1, 1, 1)))};
    for (const double thickness : {0.1, 0.3, 0.45}) {
        for (const glm::dquat& turn : turns) {
            Mesh mesh;
            addBox(mesh, glm::dvec3(-1.0, -1.0, 0.013), glm::dvec3(1.0, 1.0, 0.013 + thickness), turn);
            const PrintReport report = check(mesh, voxel, 0.5);
            const std::string what = "thickness " + std::to_string(thickness) + ", turn " + std::to_string(turn.w);
            EXPECT_TRUE(report.closed() && report.manifold()) << what;
            ASSERT_EQ(report.islands.size(), 1u) << what;
            EXPECT_NEAR(report.islands[0].volume, 4.0 * thickness, 1e-5) << what;
            ASSERT_TRUE(report.wallFound) << what;
            EXPECT_NEAR(report.thinnestWall, thickness, voxel / 20) << what;
        }
    }
}

TEST(PrintCheck, AThickBlockHasNoThinWallAtItsEdges) {
    // A cube's edges and corners are not walls: none under its side.
    Mesh mesh;
    addBox(mesh, glm::dvec3(0.0), glm::dvec3(0.5), glm::angleAxis(0.3, glm::dvec3(0, 0, 1)));
    const PrintReport report = check(mesh, 0.02, 0.6);
    ASSERT_TRUE(report.wallFound);
    EXPECT_NEAR(report.thinnestWall, 0.5, 0.02);
}

TEST(PrintCheck, OutputUnitsScaleTheReport) {
    Mesh mesh;
    addBox(mesh, glm::dvec3(0.0), glm::dvec3(2.0, 2.0, 0.2));
    PrintOptions options;
    options.voxel = 0.02;
    options.scale = 10.0;  // e.g. millimetres per unit
    options.minWall = 2.5;
    PrintReport report;
    checkPrint(mesh, options, report);
    ASSERT_EQ(report.islands.size(), 1u);
    EXPECT_NEAR(report.islands[0].max.x - report.islands[0].min.x, 20.0, 1e-4);
    EXPECT_NEAR(report.islands[0].volume, 0.8 * 1000.0, 1e-2);
    EXPECT_NEAR(report.thinnestWall, 2.0, 0.01);
    EXPECT_NE(report.failure().find("under --min-wall 2.5"), std::string::npos) << report.failure();
}

TEST(PrintCheck, AnOpenBoxHasItsHoleCounted) {
    Mesh mesh;
    addBox(mesh, glm::dvec3(0.0), glm::dvec3(1.0));
    addBox(mesh, glm::dvec3(2.0), glm::dvec3(3.0));
    mesh.quads.erase(mesh.quads.begin() + 1);  // the first box's top
    const PrintReport report = check(mesh, 0.0);
    EXPECT_EQ(report.edges, 24u);
    EXPECT_EQ(report.boundaryEdges, 4u);
    EXPECT_FALSE(report.closed());
    EXPECT_TRUE(report.manifold());
    ASSERT_EQ(report.islands.size(), 2u);
    EXPECT_EQ(report.islands[0].faces, 6u);  // the closed box first: more faces
    EXPECT_TRUE(report.islands[0].closed);
    EXPECT_NEAR(report.islands[0].volume, 1.0, 1e-6);
    EXPECT_FALSE(report.islands[1].closed);
    EXPECT_EQ(report.islands[1].volume, 0.0);
    EXPECT_FALSE(report.wallMeasured);
    EXPECT_EQ(report.failure(), "it is not closed: 4 boundary edges (holes)");
}

TEST(PrintCheck, ThreeFacesOnAnEdgeAreNotManifold) {
    Mesh mesh;
    addBox(mesh, glm::dvec3(0.0), glm::dvec3(1.0));
    // A fin on the box's edge from (1,0,0) to (1,1,0) (vertices 1 and 3).
    mesh.positions.emplace_back(2.0f, 0.0f, -1.0f);
    mesh.positions.emplace_back(2.0f, 1.0f, -1.0f);
    mesh.normals.resize(mesh.positions.size());
    mesh.quads.push_back({1, 8, 9, 3});
    const PrintReport report = check(mesh, 0.0);
    EXPECT_EQ(report.nonManifoldEdges, 1u);
    EXPECT_EQ(report.boundaryEdges, 3u);  // the fin's other sides
    EXPECT_NE(report.failure().find("not edge-manifold: 1 edges in more than two faces"), std::string::npos)
        << report.failure();
    EXPECT_EQ(check(Mesh{}, 0.05).failure(), "the mesh has no faces");
}

TEST(PrintCheck, IslandsAreDroppedBySizeOrAllButTheLargest) {
    Mesh spheres;
    addSphere(spheres, glm::dvec3(0.0), 0.5, 4);
    addSphere(spheres, glm::dvec3(2.0, 0.0, 0.0), 1.0);  // the largest, not first
    addSphere(spheres, glm::dvec3(0.0, 3.0, 0.0), 0.25, 3);
    spheres.colors.assign(spheres.positions.size(), glm::vec3(0.5f));
    std::uint32_t count = 0;
    const std::vector<std::uint32_t> labels = vertexIslands(spheres, count);
    ASSERT_EQ(count, 3u);
    std::array<std::uint64_t, 3> faces{};
    for (const auto& quad : spheres.quads) ++faces[labels[quad[0]]];
    for (const auto& triangle : spheres.triangles) ++faces[labels[triangle[0]]];

    auto dropped = [&](std::uint64_t minFaces, bool largest, PrintReport& report) {
        Mesh mesh = spheres;
        PrintOptions options;
        options.minIslandFaces = minFaces;
        options.largestOnly = largest;
        dropIslands(mesh, options, report);
        for (const auto& quad : mesh.quads)
            for (const std::uint32_t index : quad) EXPECT_LT(index, mesh.positions.size());
        for (const auto& triangle : mesh.triangles)
            for (const std::uint32_t index : triangle) EXPECT_LT(index, mesh.positions.size());
        EXPECT_EQ(mesh.normals.size(), mesh.positions.size());
        EXPECT_EQ(mesh.colors.size(), mesh.positions.size());
        checkPrint(mesh, options, report);
        return mesh;
    };
    {  // Under the middle sphere's faces: the smallest goes.
        PrintReport report;
        dropped(faces[0], false, report);
        EXPECT_EQ(report.droppedIslands, 1u);
        EXPECT_EQ(report.droppedFaces, faces[2]);
        ASSERT_EQ(report.islands.size(), 2u);
        EXPECT_EQ(report.islands[0].faces, faces[1]);
        EXPECT_EQ(report.islands[1].faces, faces[0]);
        EXPECT_TRUE(report.closed());
    }
    {  // The largest alone, with its vertices alone.
        PrintReport report;
        const Mesh mesh = dropped(0, true, report);
        EXPECT_EQ(report.droppedIslands, 2u);
        EXPECT_EQ(report.droppedFaces, faces[0] + faces[2]);
        ASSERT_EQ(report.islands.size(), 1u);
        EXPECT_EQ(report.islands[0].faces, faces[1]);
        EXPECT_NEAR(report.islands[0].min.x, 1.0, 0.01);
        for (const glm::vec3& p : mesh.positions)
            EXPECT_NEAR(glm::distance(glm::dvec3(p), glm::dvec3(2, 0, 0)), 1.0, 0.05);
        EXPECT_TRUE(report.closed());
    }
    {  // Nothing dropped under the smallest's faces.
        PrintReport report;
        const Mesh mesh = dropped(faces[2], false, report);
        EXPECT_EQ(report.droppedIslands, 0u);
        EXPECT_EQ(mesh.positions.size(), spheres.positions.size());
    }
    {  // Every island under the limit: refused, not an empty mesh.
        PrintReport report;
        Mesh mesh = spheres;
        PrintOptions options;
        options.minIslandFaces = faces[1] + 1;
        try {
            dropIslands(mesh, options, report);
            FAIL() << "every island dropped";
        } catch (const ParamError& error) {
            EXPECT_NE(std::string(error.what()).find("drops every island: the largest has " + std::to_string(faces[1])),
                      std::string::npos)
                << error.what();
        }
    }
}

TEST(PrintCheck, EdgesCountedPartByPartEqualTheWholeMesh) {
    // Two parts as the mesher streams them: the second's faces name its own vertices and the
    // first's (a fin on the first box's edge 1-3), never older ones.
    Mesh first, second;
    addBox(first, glm::dvec3(0.0), glm::dvec3(1.0));
    first.quads.erase(first.quads.begin() + 1);  // an open box: 4 boundary edges
    addBox(second, glm::dvec3(2.0), glm::dvec3(3.0));
    for (auto& quad : second.quads)
        for (std::uint32_t& vertex : quad) vertex += 8;  // after the first part's 8 vertices
    second.positions.emplace_back(2.0f, 0.0f, -1.0f);
    second.positions.emplace_back(2.0f, 1.0f, -1.0f);
    second.normals.resize(second.positions.size());
    second.quads.push_back({1, 16, 17, 3});  // the fin: 1 non-manifold edge, 3 boundary edges more

    Mesh whole = first;
    whole.positions.insert(whole.positions.end(), second.positions.begin(), second.positions.end());
    whole.normals.insert(whole.normals.end(), second.normals.begin(), second.normals.end());
    whole.quads.insert(whole.quads.end(), second.quads.begin(), second.quads.end());
    const PrintReport expected = check(whole, 0.0);
    EdgeTally tally;
    tally.add(first);
    tally.add(second);
    const PrintReport& streamed = tally.finish();
    EXPECT_FALSE(streamed.islandsCounted);
    EXPECT_EQ(streamed.faces, whole.quads.size());
    EXPECT_EQ(streamed.edges, expected.edges);
    EXPECT_EQ(streamed.boundaryEdges, expected.boundaryEdges);
    EXPECT_EQ(streamed.nonManifoldEdges, expected.nonManifoldEdges);
    EXPECT_EQ(streamed.boundaryEdges, 7u);
    EXPECT_EQ(streamed.nonManifoldEdges, 1u);
}

TEST(PrintCheck, ASlabbedMeshIsClosedAndManifoldPartByPart) {
    Params params = dqj::test::defaultAt(96);  // meshed in 16-voxel slabs
    params.bake.meshColors = false;
    EdgeTally tally;
    BakeStats stats;
    meshSurface(
        params, {}, {}, [&](Mesh&& part) { tally.add(part); }, stats, 16);
    EXPECT_GT(stats.slabs, 3u);
    const PrintReport& streamed = tally.finish();
    const Mesh onePiece = bakeMesh(params);
    const PrintReport expected = check(onePiece, 0.0);
    EXPECT_EQ(streamed.faces, onePiece.quads.size() + onePiece.triangles.size());
    EXPECT_EQ(streamed.edges, expected.edges);
    EXPECT_EQ(streamed.boundaryEdges, 0u);
    EXPECT_EQ(streamed.nonManifoldEdges, 0u);
    EXPECT_EQ(streamed.failure(), "");
}

TEST(PrintCheck, TheBallIsOneClosedIslandAsWideAsItsWall) {
    const Params params = dqj::test::ballAt(60);
    PrintOptions options;
    options.minWall = 2.5;
    BakeStats stats;
    PrintReport report;
    const Mesh mesh = meshForPrint(params, {}, options, {}, stats, report);
    EXPECT_EQ(stats.slabs, 1u);
    EXPECT_FALSE(mesh.quads.empty());
    EXPECT_TRUE(report.closed());
    EXPECT_TRUE(report.manifold());
    ASSERT_EQ(report.islands.size(), 1u);
    const double voxel = 3.0 / 60;
    for (int axis = 0; axis < 3; ++axis)
        EXPECT_NEAR(report.islands[0].max[axis] - report.islands[0].min[axis], 2.0, voxel) << axis;
    EXPECT_NEAR(report.islands[0].volume, 4.0 / 3.0 * kPi, 4.0 * kPi * voxel);  // within a voxel-thick shell
    ASSERT_TRUE(report.wallFound);
    EXPECT_NEAR(report.thinnestWall, 2.0, voxel);              // its diameter
    EXPECT_LT(glm::length(report.thinnestWallAt), 3 * voxel);  // a chord near the centre
    EXPECT_NE(report.failure().find("is under --min-wall 2.5"), std::string::npos) << report.failure();
}

TEST(PrintCheck, AMeshTooLargeForOnePieceIsRefusedBeforeSampling) {
    Params params;
    params.bake.resolution = 256;
    BakeOptions options;
    options.memoryLimit = 40u << 20;  // slabs would fit; one piece does not
    BakeStats stats;
    PrintReport report;
    try {
        meshForPrint(params, options, {}, {}, stats, report);
        FAIL() << "meshed";
    } catch (const MemoryLimitError& error) {
        EXPECT_NE(std::string(error.what()).find("needs the mesh in one piece"), std::string::npos) << error.what();
    }
    EXPECT_EQ(stats.evaluated, 0u);
}

TEST(PrintCheck, PrintFormatsAreStlAnd3mf) {
    EXPECT_TRUE(isPrintFormat("a/b.stl"));
    EXPECT_TRUE(isPrintFormat("B.STL"));
    EXPECT_TRUE(isPrintFormat("x.3MF"));
    EXPECT_FALSE(isPrintFormat("x.ply"));
    EXPECT_FALSE(isPrintFormat("x.obj"));
    EXPECT_FALSE(isPrintFormat("stl"));
}

}  // namespace
