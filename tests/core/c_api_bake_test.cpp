// The C ABI's bake and mesh calls (dqjulia.h, c_api.cpp), as the Blender add-on uses them: a mesh
// into the caller's buffers; bakes with cancelling, the memory limit and frames.
#include <gtest/gtest.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "bake_fixture.hpp"
#include "dqjulia/dqjulia.h"

namespace fs = std::filesystem;

namespace {

/// The C ABI's bake and mesh calls, as the Blender add-on uses them.
class BakeCApi : public dqj::test::BakeFolder {
protected:
    void SetUp() override {
        BakeFolder::SetUp();
        ASSERT_EQ(dqj_context_create(&context_), DQJ_OK);
    }
    void TearDown() override {
        dqj_context_destroy(context_);
        BakeFolder::TearDown();
    }
    dqj_context context_ = nullptr;
};

TEST_F(BakeCApi, MeshIntoCallerBuffers) {
    ASSERT_EQ(dqj_context_set_params_json(context_, R"({"fractal": {"c": [0,0,0,0,0,0,0,0]},
        "bake": {"bounds": {"min": [-1.5,-1.5,-1.5], "max": [1.5,1.5,1.5]}}})"),
              DQJ_OK);
    ASSERT_EQ(dqj_context_set_bake_resolution(context_, 24), DQJ_OK);
    EXPECT_EQ(dqj_context_set_bake_resolution(context_, 3), DQJ_ERROR_PARAMETERS);
    EXPECT_NE(std::string(dqj_context_error(context_)).find("bake.resolution"), std::string::npos);
    size_t vertices = 99, triangles = 99;
    ASSERT_EQ(dqj_mesh_get_sizes(context_, &vertices, &triangles), DQJ_OK);
    EXPECT_EQ(vertices, 0u);
    EXPECT_EQ(triangles, 0u);
    ASSERT_EQ(dqj_mesh_compute(context_, nullptr, nullptr), DQJ_OK) << dqj_context_error(context_);
    ASSERT_EQ(dqj_mesh_get_sizes(context_, &vertices, &triangles), DQJ_OK);
    ASSERT_GT(vertices, 100u);
    std::vector<float> positions(3 * vertices), normals(3 * vertices), colors(3 * vertices);
    std::vector<uint32_t> indices(3 * triangles);
    EXPECT_EQ(dqj_mesh_copy(context_, positions.data(), nullptr, nullptr, vertices - 1, indices.data(), triangles),
              DQJ_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(dqj_context_error(context_)).find("too small"), std::string::npos);
    ASSERT_EQ(dqj_mesh_copy(context_, positions.data(), normals.data(), colors.data(), vertices, indices.data(),
                            triangles),
              DQJ_OK);
    dqj_bake_stats stats = DQJ_BAKE_STATS_INIT;
    ASSERT_EQ(dqj_bake_get_stats(context_, &stats), DQJ_OK);
    for (size_t index = 0; index < vertices; ++index) {
        const glm::vec3 p(positions[3 * index], positions[3 * index + 1], positions[3 * index + 2]);
        EXPECT_NEAR(glm::length(p), 1.0, 3.0 / 24);
        EXPECT_GE(colors[3 * index], 0.0f);
    }
    std::map<std::pair<uint32_t, uint32_t>, int> uses;
    for (size_t index = 0; index < indices.size(); index += 3)
        for (int corner = 0; corner < 3; ++corner) {
            const uint32_t a = indices[index + corner], b = indices[index + (corner + 1) % 3];
            ASSERT_LT(a, vertices);
            ++uses[{std::min(a, b), std::max(a, b)}];
        }
    for (const auto& [edge, count] : uses) ASSERT_EQ(count, 2);
    EXPECT_GT(stats.voxels_evaluated, 0u);
    EXPECT_EQ(stats.voxels_dense, 24u * 24u * 24u);
    // The faces as the core made them: every quad and triangle, and the triangulated copy
    // above is the same faces split.
    size_t quads = 0, faceTriangles = 0;
    ASSERT_EQ(dqj_mesh_get_face_counts(context_, &quads, &faceTriangles), DQJ_OK);
    EXPECT_EQ(2 * quads + faceTriangles, triangles);
    EXPECT_GT(quads, faceTriangles);
    std::vector<uint32_t> quadIndices(4 * quads), triangleIndices(3 * faceTriangles + 3);
    EXPECT_EQ(dqj_mesh_copy_faces(context_, quadIndices.data(), quads - 1, triangleIndices.data(), faceTriangles),
              DQJ_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(dqj_mesh_copy_faces(context_, nullptr, 0, triangleIndices.data(), faceTriangles),
              quads ? DQJ_ERROR_INVALID_ARGUMENT : DQJ_OK);
    ASSERT_EQ(dqj_mesh_copy_faces(context_, quadIndices.data(), quads, triangleIndices.data(), faceTriangles), DQJ_OK);
    EXPECT_TRUE(std::equal(triangleIndices.begin(), triangleIndices.begin() + 3 * faceTriangles, indices.begin()));
    for (size_t face = 0; face < quads; ++face) {  // after the triangles, split along the 0-2 diagonal
        const uint32_t* q = &quadIndices[4 * face];
        const std::vector<uint32_t> split{q[0], q[1], q[2], q[0], q[2], q[3]};
        const auto first = indices.begin() + 3 * faceTriangles + 6 * face;
        const std::vector<uint32_t> copied(first, first + 6);
        ASSERT_EQ(copied, split) << "quad " << face;
    }
    std::vector<float> vertexOnly(3 * vertices);
    ASSERT_EQ(dqj_mesh_copy(context_, vertexOnly.data(), nullptr, nullptr, vertices, nullptr, 0), DQJ_OK);
    EXPECT_EQ(vertexOnly, positions);
    ASSERT_EQ(dqj_mesh_write(context_, path("c.ply").c_str()), DQJ_OK);
    EXPECT_TRUE(fs::exists(path("c.ply")));
    // STL and 3MF by the extension (tests/core/mesh_formats_test.cpp and mesh_files_test.py read them).
    ASSERT_EQ(dqj_mesh_write(context_, path("c.stl").c_str()), DQJ_OK);
    EXPECT_EQ(fs::file_size(path("c.stl")), 84 + 50 * triangles);
    ASSERT_EQ(dqj_mesh_write(context_, path("c.3mf").c_str()), DQJ_OK);
    EXPECT_EQ(dqj::test::readFile(path("c.3mf")).substr(0, 4), std::string("PK\x03\x04", 4));
    EXPECT_EQ(dqj_mesh_write(context_, path("c.amf").c_str()), DQJ_ERROR_PARAMETERS);
    EXPECT_EQ(dqj_mesh_copy(nullptr, positions.data(), nullptr, nullptr, vertices, indices.data(), triangles),
              DQJ_ERROR_INVALID_HANDLE);
}

int cancelAfterStart(double fraction, void* calls) {
    ++*static_cast<int*>(calls);
    return fraction == 0.0;  // 0: cancel once the work is under way
}

TEST_F(BakeCApi, BakeWithCancelMemoryLimitAndFrames) {
    ASSERT_EQ(dqj_context_set_bake_resolution(context_, 32), DQJ_OK);
    const std::string target = path("b.vdb");
    ASSERT_EQ(dqj_bake_vdb(context_, target.c_str(), nullptr, nullptr), DQJ_OK) << dqj_context_error(context_);
    EXPECT_EQ(dqj::test::readVdb(target).grids.count("density"), 1u);
    const auto size = fs::file_size(target);

    ASSERT_EQ(dqj_context_set_bake_resolution(context_, 64), DQJ_OK);
    int calls = 0;
    EXPECT_EQ(dqj_bake_vdb(context_, target.c_str(), cancelAfterStart, &calls), DQJ_ERROR_CANCELLED);
    EXPECT_EQ(fs::file_size(target), size);  // the old file is untouched
    EXPECT_EQ(files(), std::vector<std::string>{"b.vdb"});

    ASSERT_EQ(dqj_context_set_memory_limit(context_, 1000), DQJ_OK);
    EXPECT_EQ(dqj_bake_vdb(context_, path("c.vdb").c_str(), nullptr, nullptr), DQJ_ERROR_OUT_OF_MEMORY);
    EXPECT_NE(std::string(dqj_context_error(context_)).find("--max-memory"), std::string::npos);
    EXPECT_FALSE(fs::exists(path("c.vdb")));
    ASSERT_EQ(dqj_context_set_memory_limit(context_, 0), DQJ_OK);

    // Keyframed iterations: frame 1 and frame 3 bake different surfaces.
    ASSERT_EQ(dqj_context_set_params_json(context_, R"({"bake": {"resolution": 32},
        "animation": {"fractal.iterations": [{"frame": 1, "value": 4}, {"frame": 3, "value": 15}]}})"),
              DQJ_OK);
    dqj_bake_stats first = DQJ_BAKE_STATS_INIT, third = DQJ_BAKE_STATS_INIT;
    ASSERT_EQ(dqj_context_set_frame(context_, 1), DQJ_OK);
    ASSERT_EQ(dqj_bake_vdb(context_, path("f1.vdb").c_str(), nullptr, nullptr), DQJ_OK);
    ASSERT_EQ(dqj_bake_get_stats(context_, &first), DQJ_OK);
    ASSERT_EQ(dqj_context_set_frame(context_, 3), DQJ_OK);
    ASSERT_EQ(dqj_bake_vdb(context_, path("f3.vdb").c_str(), nullptr, nullptr), DQJ_OK);
    ASSERT_EQ(dqj_bake_get_stats(context_, &third), DQJ_OK);
    EXPECT_NE(first.active_voxels, third.active_voxels);
    EXPECT_EQ(dqj_context_set_frame(context_, NAN), DQJ_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(dqj_bake_vdb(context_, nullptr, nullptr, nullptr), DQJ_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(dqj_bake_vdb(context_, path("x.png").c_str(), nullptr, nullptr), DQJ_ERROR_PARAMETERS);
    EXPECT_EQ(dqj_bake_vdb(context_, path("no/such/folder/x.vdb").c_str(), nullptr, nullptr), DQJ_ERROR_IO);
    EXPECT_NE(std::string(dqj_context_error(context_)).find("no/such/folder"), std::string::npos);
}

}  // namespace
