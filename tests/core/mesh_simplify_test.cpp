// Simplified meshes (bake.max_faces, bake/mesh_simplify.hpp): at most N triangles, and within the
// stated bounds of the full mesh, measured again here from a full mesh made separately; the
// measure itself on a shape with a known answer; N too small, and N with the one-piece limit
// or with bake.adaptivity, refused with the reason.
#include <gtest/gtest.h>

#include <string>

#include "dqjulia/bake.hpp"
#include "dqjulia/mesh.hpp"
#include "dqjulia/params.hpp"
#include "bake/memory.hpp"
#include "bake/mesh_simplify.hpp"
#include "bake/sparse_sampler.hpp"
#include "bake_fixture.hpp"

using namespace dqj;

namespace {

using MeshSimplify = dqj::test::BakeFolder;

Params fractalAt(int resolution) {
    Params params = dqj::test::defaultAt(resolution);
    params.bake.meshColors = false;
    return params;
}

using dqj::test::ballAt;

/// A flat square of n x n quads in the plane z = height, unit spacing.
Mesh plane(int n, float height) {
    Mesh mesh;
    for (int y = 0; y <= n; ++y)
        for (int x = 0; x <= n; ++x) mesh.positions.emplace_back(float(x), float(y), height);
    auto at = [n](int x, int y) { return std::uint32_t(y * (n + 1) + x); };
    for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) mesh.quads.push_back({at(x, y), at(x + 1, y), at(x + 1, y + 1), at(x, y + 1)});
    return mesh;
}

TEST(MeshDeviation, MeasuresTheDistanceToTheReferenceSurface) {
    const Mesh reference = plane(20, 0.0f);
    const MeshDeviation same = meshDeviation(reference, reference, 1.0);
    EXPECT_NEAR(same.vertices, 0.0, 1e-5);
    EXPECT_NEAR(same.samples, 0.0, 1e-5);
    // Raised by 0.75 voxel (a voxel of 0.5: 0.375 units); one vertex lifted 3 voxels more.
    Mesh raised = plane(20, 0.375f);
    MeshDeviation deviation = meshDeviation(reference, raised, 0.5);
    EXPECT_NEAR(deviation.vertices, 0.75, 1e-5);
    EXPECT_NEAR(deviation.samples, 0.75, 1e-5);
    raised.positions[10 * 21 + 10].z += 1.5f;
    deviation = meshDeviation(reference, raised, 0.5);
    EXPECT_NEAR(deviation.vertices, 3.75, 1e-5);
    EXPECT_GT(deviation.samples, 0.75 + 1e-3);  // the faces around it rise too
    EXPECT_LT(deviation.samples, 3.75);
    // Beyond the search's reach: counted as its reach, 16 voxels.
    EXPECT_NEAR(meshDeviation(reference, plane(20, 40.0f), 0.5).vertices, 16.0, 1e-5);
}

/// Meshes `params` with bake.max_faces = `faces` and checks the promise: at most that many
/// triangles, and within the bounds of the full mesh (made here on its own).
void expectSimplified(Params params, std::uint64_t faces, const std::string& what) {
    params.bake.maxFaces = int(faces);
    BakeStats stats;
    const Mesh simplified = bakeMesh(params, {}, {}, &stats);
    params.bake.maxFaces = 0;
    const Mesh full = bakeMesh(params);
    ASSERT_GT(full.triangleCount(), faces) << what;
    EXPECT_LE(simplified.triangleCount(), faces) << what;
    EXPECT_GT(simplified.triangleCount(), faces / 4) << what << ": far below what was asked";
    EXPECT_EQ(stats.fullTriangles, full.triangleCount()) << what;
    EXPECT_GT(stats.adaptivity, 0.0) << what;
    const MeshDeviation measured = meshDeviation(full, simplified, stats.voxelSize);
    EXPECT_LE(measured.vertices, kSimplifiedVertexBound) << what;
    EXPECT_LE(measured.samples, kSimplifiedSampleBound) << what;
    EXPECT_DOUBLE_EQ(measured.vertices, stats.deviationVertices) << what;
    EXPECT_DOUBLE_EQ(measured.samples, stats.deviationSamples) << what;
    EXPECT_EQ(simplified.normals.size(), simplified.positions.size()) << what;
}

TEST_F(MeshSimplify, TheDefaultFractalMeetsTheFaceCountWithinTheBounds) {
    const Params params = fractalAt(128);
    const std::uint64_t full = bakeMesh(params).triangleCount();
    for (const double share : {0.7, 0.5, 0.35})
        expectSimplified(params, std::uint64_t(share * double(full)), "fractal, " + std::to_string(share));
}

TEST_F(MeshSimplify, TheBallMeetsTheFaceCountWithinTheBounds) {
    const Params params = ballAt(128);
    const std::uint64_t full = bakeMesh(params).triangleCount();
    for (const double share : {0.5, 0.2, 0.1})
        expectSimplified(params, std::uint64_t(share * double(full)), "ball, " + std::to_string(share));
}

TEST_F(MeshSimplify, AFullMeshWithinTheCountIsKeptAsItIs) {
    Params params = ballAt(48);
    const Mesh full = bakeMesh(params);
    params.bake.maxFaces = int(full.triangleCount());
    BakeStats stats;
    const Mesh kept = bakeMesh(params, {}, {}, &stats);
    EXPECT_TRUE(kept.positions == full.positions && kept.quads == full.quads);
    EXPECT_EQ(stats.fullTriangles, 0u);
    EXPECT_EQ(stats.adaptivity, 0.0);
}

TEST_F(MeshSimplify, TooFewFacesAreRefusedWithTheLeastThatCanBeMade) {
    Params params = ballAt(64);
    params.bake.maxFaces = 10;
    try {
        bakeMeshFile(params, path("m.ply"));
        FAIL() << "not refused";
    } catch (const ParamError& error) {
        const std::string message = error.what();
        EXPECT_EQ(error.key(), "bake.max_faces") << message;
        EXPECT_NE(message.find("at most 10 faces"), std::string::npos) << message;
        EXPECT_NE(message.find("or more"), std::string::npos) << message;
    }
    EXPECT_TRUE(files().empty());
}

TEST_F(MeshSimplify, WithAdaptivityOrPastTheOnePieceLimitItIsRefused) {
    Params params = fractalAt(96);
    params.bake.maxFaces = 1000;
    params.bake.adaptivity = 0.2;
    EXPECT_THROW(validate(params), ParamError);
    params.bake.adaptivity = 0.0;
    BakeStats wholeStats;
    bakeMesh(fractalAt(96), {}, {}, &wholeStats);
    BakeOptions options;
    const std::uint64_t fixed = samplingEstimate(meshMemoryModel(), 0, false);
    options.memoryLimit = fixed + (wholeStats.estimatedBytes - fixed) / 2;  // slabs would fit, one piece not
    try {
        bakeMeshFile(params, path("m.ply"), options);
        FAIL() << "not refused";
    } catch (const MemoryLimitError& error) {
        EXPECT_NE(std::string(error.what()).find("--faces, is simplified in one piece"), std::string::npos)
            << error.what();
    }
    EXPECT_TRUE(files().empty());
}

}  // namespace
