// nearestSeeds (core/src/bake/nearest_seed.hpp, internal): against the brute-force nearest seed, on a
// box (convex: every seed's nearest voxels are reachable) and on two pieces, one without seeds;
// with its rounds bounded, a voxel's seed depends on nothing further than that many steps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>

#include <openvdb/openvdb.h>

#include "bake/nearest_seed.hpp"

namespace {

using openvdb::Coord;
using openvdb::Vec3f;

struct Seeds {
    std::vector<Coord> voxels;
    std::vector<Vec3f> points;
};

/// `count` seeds at random points of the box [0, size)^3, each starting at its rounded voxel.
Seeds randomSeeds(int count, int size, unsigned seed) {
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> at(0.0f, float(size - 1));
    Seeds seeds;
    for (int index = 0; index < count; ++index) {
        const Vec3f point(at(random), at(random), at(random));
        seeds.points.push_back(point);
        seeds.voxels.emplace_back(int(std::lround(point.x())), int(std::lround(point.y())),
                                  int(std::lround(point.z())));
    }
    return seeds;
}

openvdb::MaskTree box(const Coord& low, const Coord& high) {
    openvdb::MaskTree mask;
    mask.sparseFill(openvdb::CoordBBox(low, high), true, true);
    mask.voxelizeActiveTiles();
    return mask;
}

float distance(const Coord& ijk, const Vec3f& point) { return (Vec3f(ijk.asVec3s()) - point).length(); }

/// How near the seeds nearestSeeds() gave are, against the brute-force nearest seed of each voxel.
struct Nearness {
    std::size_t exact = 0, voxels = 0;
    float worst = 0.0f;  ///< the largest excess distance, in voxels
};

Nearness nearness(const openvdb::Int32Tree& ids, const Seeds& seeds) {
    Nearness result;
    for (auto on = ids.cbeginValueOn(); on; ++on) {
        const Coord ijk = on.getCoord();
        float nearest = 1e30f;
        for (const Vec3f& point : seeds.points) nearest = std::min(nearest, distance(ijk, point));
        const int id = *on;
        EXPECT_GE(id, 0);
        if (id < 0) continue;
        const float taken = distance(ijk, seeds.points[std::size_t(id)]);
        result.exact += taken == nearest;
        result.worst = std::max(result.worst, taken - nearest);
        ++result.voxels;
    }
    return result;
}

TEST(NearestSeeds, EachVoxelTakesTheNearestSeedOrOneAboutAsNear) {
    const int size = 40;
    const openvdb::MaskTree region = box(Coord(0), Coord(size - 1));
    const Seeds seeds = randomSeeds(60, size, 7);
    const openvdb::Int32Tree::Ptr ids = dqj::nearestSeeds(region, seeds.voxels, seeds.points);
    EXPECT_EQ(ids->activeVoxelCount(), region.activeVoxelCount()) << "every voxel of a connected region is reached";
    const auto [exact, voxels, worst] = nearness(*ids, seeds);
    std::printf("nearest seed: %.2f %% of %zu voxels exact, worst %.3f voxels farther\n",
                100.0 * double(exact) / double(voxels), voxels, double(worst));
    // Measured: all exact (first arrivals alone, without the later rounds: 90 %, up to 6 voxels off).
    EXPECT_GT(double(exact), 0.995 * double(voxels));
    EXPECT_LT(worst, 0.5f);
}

TEST(NearestSeeds, BelowACurvedSurfaceEachVoxelTakesItsNearestPoint) {
    // As the bake uses it: seeds on a sphere of radius 20 (one per voxel it crosses, measured
    // from the sphere's point nearest to it), a shell 3 voxels outside to 9 inside.
    const float radius = 20.0f;
    openvdb::MaskTree region;
    Seeds seeds;
    for (int x = -24; x <= 24; ++x)
        for (int y = -24; y <= 24; ++y)
            for (int z = -24; z <= 24; ++z) {
                const Vec3f at{float(x), float(y), float(z)};
                const float r = at.length();
                if (r > radius + 3.0f || r < radius - 9.0f) continue;
                region.setValueOn(Coord(x, y, z));
                if (std::abs(r - radius) < 0.5f) {
                    seeds.voxels.emplace_back(x, y, z);
                    seeds.points.push_back(at * (radius / r));
                }
            }
    const openvdb::Int32Tree::Ptr ids = dqj::nearestSeeds(region, seeds.voxels, seeds.points);
    EXPECT_EQ(ids->activeVoxelCount(), region.activeVoxelCount());
    const auto [exact, voxels, worst] = nearness(*ids, seeds);
    std::printf("below a sphere: %.2f %% of %zu voxels exact, worst %.4f voxels farther\n",
                100.0 * double(exact) / double(voxels), voxels, double(worst));
    // Measured: 88.5 % exact, the others at most 0.088 voxels farther than the nearest point
    // (with 18 neighbours a step: 81 % and 0.37; with 6: 65 % and 0.67).
    EXPECT_GT(double(exact), 0.85 * double(voxels));
    EXPECT_LT(worst, 0.15f);
}

TEST(NearestSeeds, SeedsOutsideTheRegionAreIgnoredAndPiecesWithoutSeedsStayOff) {
    // Two boxes apart: seeds in the first only, and one outside both.
    openvdb::MaskTree region = box(Coord(0), Coord(15));
    region.topologyUnion(box(Coord(40, 0, 0), Coord(55, 15, 15)));
    Seeds seeds = randomSeeds(5, 16, 3);
    seeds.voxels.emplace_back(30, 5, 5);
    seeds.points.emplace_back(30.0f, 5.0f, 5.0f);
    const openvdb::Int32Tree::Ptr ids = dqj::nearestSeeds(region, seeds.voxels, seeds.points);
    EXPECT_EQ(ids->activeVoxelCount(), 16u * 16u * 16u);
    for (auto on = ids->cbeginValueOn(); on; ++on) {
        EXPECT_LT(on.getCoord().x(), 16);
        EXPECT_LT(*on, 5);
    }
    // The same again (the layers' order of work varies from run to run; the result does not).
    const openvdb::Int32Tree::Ptr again = dqj::nearestSeeds(region, seeds.voxels, seeds.points);
    EXPECT_TRUE(again->hasSameTopology(*ids));
    for (auto on = ids->cbeginValueOn(); on; ++on) EXPECT_EQ(again->getValue(on.getCoord()), *on);
}

TEST(NearestSeeds, OfTwoSeedsOnOneVoxelTheFirstIsKept) {
    const openvdb::MaskTree region = box(Coord(0), Coord(7));
    const std::vector<Coord> voxels{Coord(3), Coord(3)};
    const std::vector<Vec3f> points{Vec3f(3.0f), Vec3f(3.0f)};
    const openvdb::Int32Tree::Ptr ids = dqj::nearestSeeds(region, voxels, points);
    EXPECT_EQ(ids->activeVoxelCount(), 512u);
    for (auto on = ids->cbeginValueOn(); on; ++on) EXPECT_EQ(*on, 0);
}

/// A region of [0, size)^3 with about one voxel in `holes` missing, and `count` seeds in it, half
/// of them at their voxels' centres (so that some voxels lie equally near two seeds).
struct Input {
    openvdb::MaskTree region;
    std::vector<Coord> voxels;
    std::vector<Vec3f> points;
};

Input randomInput(int size, int holes, int count, unsigned seed) {
    std::mt19937 random(seed);
    Input input{box(Coord(0), Coord(size - 1)), {}, {}};
    std::uniform_int_distribution<int> at(0, size - 1);
    for (int hole = 0; hole < size * size * size / holes; ++hole)
        input.region.setValueOff(Coord(at(random), at(random), at(random)));
    std::uniform_real_distribution<float> off(-0.5f, 0.5f);
    for (int index = 0; index < count; ++index) {
        const Coord voxel(at(random), at(random), at(random));
        const bool centre = index % 2 == 0;
        input.voxels.push_back(voxel);
        input.points.push_back(voxel.asVec3s() + (centre ? Vec3f(0.0f) : Vec3f(off(random), off(random), off(random))));
    }
    return input;
}

/// The seeds sorted by voxel (x, then y, then z), the first of a voxel kept: the order the bake
/// numbers its seeds in is one fixed order of their voxels too.
void sortByVoxel(Input& input) {
    std::vector<std::size_t> order(input.voxels.size());
    for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
    std::stable_sort(order.begin(), order.end(),
                     [&](std::size_t a, std::size_t b) { return input.voxels[a] < input.voxels[b]; });
    std::vector<Coord> voxels;
    std::vector<Vec3f> points;
    for (const std::size_t k : order) {
        if (!voxels.empty() && voxels.back() == input.voxels[k]) continue;
        voxels.push_back(input.voxels[k]);
        points.push_back(input.points[k]);
    }
    input.voxels = std::move(voxels);
    input.points = std::move(points);
}

/// `inner` as `outer` has it within `box` and as it has it elsewhere: the region's voxels and
/// the seeds on them.
Input agreeWithin(const Input& inner, const Input& outer, const openvdb::CoordBBox& box) {
    Input result{outer.region, {}, {}};
    for (auto ijk = box.begin(); ijk; ++ijk) result.region.setValueOff(*ijk);
    for (auto ijk = box.begin(); ijk; ++ijk)
        if (inner.region.isValueOn(*ijk)) result.region.setValueOn(*ijk);
    for (const Input* from : {&inner, &outer})
        for (std::size_t k = 0; k < from->voxels.size(); ++k)
            if (box.isInside(from->voxels[k]) == (from == &inner)) {
                result.voxels.push_back(from->voxels[k]);
                result.points.push_back(from->points[k]);
            }
    sortByVoxel(result);
    return result;
}

TEST(NearestSeeds, AfterRRoundsAVoxelsSeedDependsOnNothingFurtherThanRSteps) {
    // What makes tiled bakes exact (tileHalo, tiles.cpp): two inputs that agree within R steps
    // of a box and differ everywhere beyond it (the region's holes, seeds missing, moved and
    // added, many equally near two seeds) give every voxel of the box the same seed, ties
    // included, after R rounds; one step less of agreement, or rounds without a bound, and they
    // do not.
    const int size = 40, rounds = 7;
    const openvdb::CoordBBox compared(Coord(15), Coord(24));
    openvdb::CoordBBox agreed = compared;
    agreed.expand(rounds);
    int differingWithoutBound = 0, differingTooClose = 0;
    std::size_t voxels = 0, ties = 0;
    for (unsigned trial = 0; trial < 6; ++trial) {
        Input a = randomInput(size, 6, 120, 2 * trial + 1);
        sortByVoxel(a);
        const Input other = randomInput(size, 4, 400, 2 * trial + 2);
        const Input b = agreeWithin(a, other, agreed);
        auto seedVoxel = [](const openvdb::Int32Tree& ids, const Input& input, const Coord& ijk) {
            const int id = ids.getValue(ijk);
            return ids.isValueOn(ijk) ? input.voxels[std::size_t(id)] : Coord(-1);
        };
        auto differing = [&](const openvdb::Int32Tree& x, const Input& xi, const openvdb::Int32Tree& y,
                             const Input& yi) {
            int count = 0;
            for (auto ijk = compared.begin(); ijk; ++ijk) count += seedVoxel(x, xi, *ijk) != seedVoxel(y, yi, *ijk);
            return count;
        };
        const auto idsA = dqj::nearestSeeds(a.region, a.voxels, a.points, rounds);
        const auto idsB = dqj::nearestSeeds(b.region, b.voxels, b.points, rounds);
        EXPECT_EQ(differing(*idsA, a, *idsB, b), 0) << "trial " << trial;
        for (auto ijk = compared.begin(); ijk; ++ijk) {
            if (!idsA->isValueOn(*ijk)) continue;
            ++voxels;
            const Vec3f at = (*ijk).asVec3s();
            const float taken = (at - a.points[std::size_t(idsA->getValue(*ijk))]).lengthSqr();
            for (std::size_t k = 0; k < a.points.size(); ++k)
                if (std::int32_t(k) != idsA->getValue(*ijk) && (at - a.points[k]).lengthSqr() == taken) {
                    ++ties;
                    break;
                }
        }
        differingWithoutBound += differing(*dqj::nearestSeeds(a.region, a.voxels, a.points), a,
                                           *dqj::nearestSeeds(b.region, b.voxels, b.points), b);
        openvdb::CoordBBox closer = compared;
        closer.expand(rounds - 1);
        const Input c = agreeWithin(a, other, closer);
        differingTooClose += differing(*idsA, a, *dqj::nearestSeeds(c.region, c.voxels, c.points, rounds), c);
    }
    std::printf(
        "%zu voxels alike after %d rounds (%zu of them as near to another seed); without a bound %d "
        "differ, with one step less agreed %d\n",
        voxels, rounds, ties, differingWithoutBound, differingTooClose);
    EXPECT_GT(voxels, 4000u);
    EXPECT_GT(ties, 10u);
    EXPECT_GT(differingWithoutBound, 0);
    EXPECT_GT(differingTooClose, 0);
}

TEST(NearestSeeds, ZeroRoundsLeaveTheSeedsVoxelsAlone) {
    const openvdb::MaskTree region = box(Coord(0), Coord(7));
    const std::vector<Coord> voxels{Coord(1), Coord(6)};
    const std::vector<Vec3f> points{Vec3f(1.0f), Vec3f(6.0f)};
    const openvdb::Int32Tree::Ptr ids = dqj::nearestSeeds(region, voxels, points, 0);
    EXPECT_EQ(ids->activeVoxelCount(), 2u);
    EXPECT_EQ(ids->getValue(Coord(6)), 1);
    EXPECT_EQ(dqj::nearestSeeds(region, voxels, points, 1)->activeVoxelCount(), 2u * 27u);
    EXPECT_THROW(dqj::nearestSeeds(region, voxels, points, -1), std::invalid_argument);
}

}  // namespace
