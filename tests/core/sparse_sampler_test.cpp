// The surface function f of the bake's sampler (sparse_sampler.hpp): its batch path leaves the
// region's distance uncomputed where every point lies deeper inside than the band, and must
// give the very values it gives with the distance computed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <glm/geometric.hpp>

#include "dqjulia/params.hpp"
#include "bake/sparse_sampler.hpp"

using namespace dqj;

namespace {

/// The default fractal in a box region, or in the default (sphere) region.
Params regionParams(bool box) {
    Params params;
    params.bake.resolution = 128;
    if (box) params.bake.bounds = Box{glm::dvec3(-0.9, -0.8, -0.7), glm::dvec3(0.8, 0.9, 0.6)};
    return params;
}

/// f at `points` in one batch.
std::vector<float> batchValues(const SurfaceFunction& f, const std::vector<glm::dvec3>& points) {
    std::vector<float> values(points.size());
    std::uint64_t evaluations = 0;
    f(points.data(), points.size(), values.data(), evaluations);
    return values;
}

/// An 8^3 block of voxel centres from `corner`, voxel size h.
std::vector<glm::dvec3> block(const glm::dvec3& corner, double h) {
    std::vector<glm::dvec3> points;
    for (int x = 0; x < 8; ++x)
        for (int y = 0; y < 8; ++y)
            for (int z = 0; z < 8; ++z) points.push_back(corner + h * glm::dvec3(x, y, z));
    return points;
}

}  // namespace

TEST(SparseSampler, ARegionContainsABoxOnlyWithItsMargin) {
    const BakeRegion box(regionParams(true));
    EXPECT_TRUE(box.containsWithMargin(glm::dvec3(-0.8, -0.7, -0.6), glm::dvec3(0.7, 0.8, 0.5), 0.1));
    EXPECT_FALSE(box.containsWithMargin(glm::dvec3(-0.8, -0.7, -0.6), glm::dvec3(0.7, 0.8, 0.5), 0.11));
    EXPECT_FALSE(box.containsWithMargin(glm::dvec3(-0.85, -0.7, -0.6), glm::dvec3(0.7, 0.8, 0.5), 0.1));
    const BakeRegion sphere(regionParams(false));
    const Bounds bounds = renderBounds(regionParams(false));
    const glm::dvec3 c = bounds.center;
    const double half = 0.5 * bounds.radius / std::sqrt(3.0);  // the corners at half the radius
    EXPECT_TRUE(sphere.containsWithMargin(c - half, c + half, 0.49 * bounds.radius));
    EXPECT_FALSE(sphere.containsWithMargin(c - half, c + half, 0.51 * bounds.radius));
    EXPECT_FALSE(sphere.containsWithMargin(c + glm::dvec3(0.9 * bounds.radius, 0, 0),
                                           c + glm::dvec3(0.95 * bounds.radius, 0, 0), 0.1 * bounds.radius));
}

TEST(SparseSampler, ValuesDeepInsideTheRegionAreThoseWithTheDistanceComputed) {
    for (const bool box : {true, false}) {
        SCOPED_TRACE(box ? "box region" : "sphere region");
        const Params params = regionParams(box);
        const SurfaceFunction f(params, bakeVoxelSize(params));
        const double h = f.voxelSize();
        // Blocks across the set's surface, deep inside the region: their own batch skips the
        // region's distance; with a point outside the region added, it is computed for all.
        int blocks = 0, crossing = 0;
        for (int i = 0; i < 5; ++i)
            for (int j = 0; j < 5; ++j) {
                const std::vector<glm::dvec3> points = block(glm::dvec3(-0.5 + 0.2 * i, -0.4 + 0.2 * j, -0.1), h);
                const glm::dvec3 lo = points.front(), hi = points.back();
                ASSERT_TRUE(f.region().containsWithMargin(lo, hi, f.background() + h));
                std::vector<glm::dvec3> mixed = points;
                mixed.emplace_back(10.0);  // outside every region here
                const std::vector<float> deep = batchValues(f, points);
                const std::vector<float> computed = batchValues(f, mixed);
                EXPECT_GT(computed.back(), 0.0f);
                EXPECT_EQ(std::memcmp(deep.data(), computed.data(), deep.size() * sizeof(float)), 0);
                bool inside = false, outside = false;
                for (const float value : deep) (value < 0.0f ? inside : outside) = true;
                crossing += inside && outside;
                ++blocks;
            }
        EXPECT_EQ(blocks, 25);
        EXPECT_GE(crossing, 3);  // the comparison covers the surface, not only empty space
    }
}

TEST(SparseSampler, ValuesNearTheRegionsFacesTakeItsDistance) {
    const Params params = regionParams(true);
    const SurfaceFunction f(params, bakeVoxelSize(params));
    const double h = f.voxelSize();
    // A block astride the box's face x = 0.8: beyond it f is the distance to the region.
    const std::vector<glm::dvec3> points = block(glm::dvec3(0.8 - 3.5 * h, 0.0, 0.0), h);
    const std::vector<float> values = batchValues(f, points);
    for (std::size_t i = 0; i < points.size(); ++i) {
        const double distance = f.region().signedDistance(points[i]);
        if (distance > 0.0) EXPECT_FLOAT_EQ(values[i], float(std::min(distance, double(f.background()))));
        EXPECT_GE(values[i], float(std::max(distance, -double(f.background()))) - 1e-6f);
    }
}
