// dqj_mesh_estimate (dqjulia.h): what a mesh will take, known before it starts, as the Blender
// add-on shows it: the one piece's estimate is the one the mesh then checks, the slabs the limit
// asks for, the faces near the mesh's; a mesh that cannot fit refused with the reason; a cancel.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "dqjulia/dqjulia.h"

namespace {

class MeshEstimateCApi : public ::testing::Test {
protected:
    void SetUp() override {
        ASSERT_EQ(dqj_context_create(&context_), DQJ_OK);
        ASSERT_EQ(dqj_context_set_bake_resolution(context_, 96), DQJ_OK);
    }
    void TearDown() override { dqj_context_destroy(context_); }
    std::string error() const { return dqj_context_error(context_); }
    dqj_context context_ = nullptr;
};

int cancelAtOnce(double, void*) { return 0; }

TEST_F(MeshEstimateCApi, TheEstimateIsTheMeshsOwn) {
    uint64_t bytes = 0, slabs = 0, faces = 0;
    ASSERT_EQ(dqj_mesh_estimate(context_, &bytes, &slabs, &faces, nullptr, nullptr), DQJ_OK) << error();
    EXPECT_EQ(slabs, 1u);
    ASSERT_EQ(dqj_mesh_compute(context_, nullptr, nullptr), DQJ_OK) << error();
    dqj_bake_stats stats = DQJ_BAKE_STATS_INIT;
    ASSERT_EQ(dqj_bake_get_stats(context_, &stats), DQJ_OK);
    EXPECT_EQ(bytes, stats.estimated_bytes);
    size_t vertices = 0, triangles = 0;
    ASSERT_EQ(dqj_mesh_get_sizes(context_, &vertices, &triangles), DQJ_OK);
    EXPECT_GT(double(faces), 0.7 * double(triangles)) << triangles;
    EXPECT_LT(double(faces), 1.3 * double(triangles)) << triangles;
    EXPECT_EQ(dqj_mesh_estimate(context_, nullptr, nullptr, nullptr, nullptr, nullptr), DQJ_OK);
    EXPECT_EQ(dqj_mesh_estimate(context_, &bytes, &slabs, &faces, cancelAtOnce, nullptr), DQJ_ERROR_CANCELLED);
    EXPECT_EQ(dqj_mesh_estimate(nullptr, &bytes, &slabs, &faces, nullptr, nullptr), DQJ_ERROR_INVALID_HANDLE);

    // bake.max_faces caps the faces.
    ASSERT_EQ(dqj_context_set_params_json(context_, R"({"bake": {"resolution": 96, "max_faces": 5000}})"), DQJ_OK);
    ASSERT_EQ(dqj_mesh_estimate(context_, &bytes, &slabs, &faces, nullptr, nullptr), DQJ_OK) << error();
    EXPECT_EQ(faces, 5000u);
}

TEST_F(MeshEstimateCApi, TheLimitChoosesTheSlabsOrRefusesWithTheReason) {
    ASSERT_EQ(dqj_context_set_bake_resolution(context_, 192), DQJ_OK);  // slabs thin beside the whole
    uint64_t whole = 0, slabs = 0, faces = 0;
    ASSERT_EQ(dqj_mesh_estimate(context_, &whole, &slabs, &faces, nullptr, nullptr), DQJ_OK) << error();
    const uint64_t fixed = 96ull * 1024 * 1024;  // meshMemoryModel's fixed part
    ASSERT_GT(whole, fixed);
    const uint64_t limit = fixed + (whole - fixed) / 2;
    ASSERT_EQ(dqj_context_set_memory_limit(context_, limit), DQJ_OK);
    uint64_t bytes = 0;
    ASSERT_EQ(dqj_mesh_estimate(context_, &bytes, &slabs, &faces, nullptr, nullptr), DQJ_OK) << error();
    EXPECT_GE(slabs, 2u);
    EXPECT_LE(bytes, limit);
    ASSERT_EQ(dqj_mesh_compute(context_, nullptr, nullptr), DQJ_OK) << error();  // and the mesh fits

    // Simplified meshes are made in one piece: refused, the reason named, before any work.
    ASSERT_EQ(dqj_context_set_params_json(context_, R"({"bake": {"resolution": 192, "max_faces": 5000}})"), DQJ_OK);
    EXPECT_EQ(dqj_mesh_estimate(context_, &bytes, &slabs, &faces, nullptr, nullptr), DQJ_ERROR_OUT_OF_MEMORY);
    EXPECT_NE(error().find("simplified in one piece"), std::string::npos) << error();

    ASSERT_EQ(dqj_context_set_memory_limit(context_, 1000), DQJ_OK);
    EXPECT_EQ(dqj_mesh_estimate(context_, &bytes, &slabs, &faces, nullptr, nullptr), DQJ_ERROR_OUT_OF_MEMORY);
    EXPECT_NE(error().find("does not fit the limit"), std::string::npos) << error();
}

}  // namespace
