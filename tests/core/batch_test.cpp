// The SIMD batch kernel (batch.hpp) against the scalar reference evaluate(), on every instruction
// set compiled in that this CPU runs (the dispatched one and the portable fallback included):
//  - double: escape count, r, ra, rb and trap identical, DE to relative 1e-12;
//  - float: over a million points per variant mix, every escape-count mismatch is a point whose
//    double orbit passes within the float rounding-error bound of the bailout at the deciding
//    iteration (floatErrorBound below), and mismatches are rare.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "dqjulia/batch.hpp"
#include "dqjulia/estimate.hpp"
#include "dqjulia/slice.hpp"

using namespace dqj;

namespace {

const DualQuat kC1{makeQuat(-0.10, 0.8, -0.26, 0.15), makeQuat(-0.23, -0.38, -0.86, 0.64)};
const DualQuat kC2{makeQuat(-0.39054, -0.58679, 0.0, 0.0), makeQuat(0.0, 0.5632, 0.0, 0.05)};
const DualQuat kQuaternionJulia{makeQuat(-0.083, 0.0, -0.83, -0.025), makeQuat(0, 0, 0, 0)};
constexpr Variant kVariants[] = {Variant::Paper, Variant::PaperCoupled, Variant::Dual};

Fractal makeFractal(const DualQuat& c, Variant variant, int iterations) {
    Fractal fractal;
    fractal.c = c;
    fractal.variant = variant;
    fractal.iterations = iterations;
    fractal.bailout = std::max(4.0, minimumBailout(fractal));
    return fractal;
}

std::string describe(const Fractal& fractal) {
    return std::string(variantName(fractal.variant)) + " N=" + std::to_string(fractal.iterations);
}

/// Points of the 8-D space the renderer and the bake ask about: the default slice (b = 0) and a
/// turned slice through the dual axes, inside the containment sphere, plus uniform 8-D points.
std::vector<DualQuat> samplePoints(std::size_t count, unsigned seed) {
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    const Slice flat = sliceFromAxisNames("a.s,a.i,a.j");
    const Slice turned = rotated(sliceFromAxisNames("a.i,a.j,b.s"), {{0, 4, 30.0}});
    std::vector<DualQuat> points;
    points.reserve(count);
    while (points.size() < count) {
        const glm::dvec3 p(1.6 * uniform(random), 1.6 * uniform(random), 1.6 * uniform(random));
        switch (points.size() % 3) {
            case 0: points.push_back(flat.map(p)); break;
            case 1: points.push_back(turned.map(p)); break;
            default: {
                Vec8 v;
                for (double& x : v) x = 1.2 * uniform(random);
                points.push_back(toDualQuat(v));
            }
        }
    }
    // The critical point (zero derivative: DE = +inf under paper) and a far point.
    points[0] = DualQuat{};
    points[1] = toDualQuat(Vec8{5, -3, 2, 1, 0.5, 0, 0, 7});
    return points;
}

/// Points within about 1e-4 of the surface of the finite-N set in the default slice: the hard
/// cases, where the derivative is large and float rounding decides more escape counts.
std::vector<DualQuat> surfacePoints(const Fractal& fractal, std::size_t count, unsigned seed) {
    std::mt19937_64 random(seed);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    const Slice slice = sliceFromAxisNames("a.s,a.i,a.j");
    auto inside = [&](const glm::dvec3& p) { return evaluate(fractal, slice.map(p)).n == 0; };
    std::vector<DualQuat> points;
    glm::dvec3 in(0.0), out(0.0);
    bool haveIn = false, haveOut = false;
    while (points.size() < count) {
        const glm::dvec3 p(1.6 * uniform(random), 1.6 * uniform(random), 1.6 * uniform(random));
        if (inside(p)) {
            in = p;
            haveIn = true;
        } else {
            out = p;
            haveOut = true;
        }
        if (!haveIn || !haveOut) continue;
        glm::dvec3 lo = in, hi = out;  // bisect to the boundary crossed between them
        for (int k = 0; k < 40; ++k) {
            const glm::dvec3 middle = 0.5 * (lo + hi);
            (inside(middle) ? lo : hi) = middle;
        }
        const glm::dvec3 direction = out - in;
        points.push_back(
            slice.map(lo + 1e-4 * uniform(random) / std::sqrt(glm::dot(direction, direction)) * direction));
    }
    return points;
}

template <typename T>
struct Results {
    std::vector<std::int32_t> n;
    std::vector<T> r, ra, rb, de, trap;
};

template <typename T>
Results<T> runBatch(const Fractal& fractal, const std::vector<DualQuat>& points, std::int64_t target) {
    std::vector<T> coords[8];
    for (int k = 0; k < 8; ++k) {
        coords[k].reserve(points.size());
        for (const DualQuat& z : points) coords[k].push_back(static_cast<T>(component(z, k)));
    }
    Results<T> out;
    const std::size_t count = points.size();
    out.n.assign(count, -1);
    for (auto* field : {&out.r, &out.ra, &out.rb, &out.de, &out.trap}) field->assign(count, T(-1));
    PointBatch<T> batch;
    for (int k = 0; k < 8; ++k) batch.coords[k] = coords[k].data();
    batch.count = count;
    evaluateBatch(fractal, batch,
                  EscapeBatch<T>{out.n.data(), out.r.data(), out.ra.data(), out.rb.data(), out.de.data(),
                                 out.trap.data()},
                  target);
    return out;
}

bool sameDistance(double expected, double actual, double relative) {
    if (std::isinf(expected) || expected == 0.0) return actual == expected;
    return std::abs(actual - expected) <= relative * std::abs(expected);
}

/// The float rounding-error bound of an orbit, iterated in double alongside it (first order
/// plus the quadratic term). For each part x (a, b): delta_0 = u |x_0| (rounding the start to
/// float), delta_{k+1} = 2 |x_k| delta_k + delta_k^2 + 8 u (|x_k|^2 + |c_x|), u = 2^-24: the
/// perturbation of x^2 + c, plus the rounding of the square's four-term sums and of adding c.
/// The dual variant's b is not bounded (its escape test reads only a). A float escape count that
/// differs from the double one is explained when, at the first iteration where they disagree,
/// the double norm tested for escape lies within twice that bound (plus the rounding of the norm
/// and of R) of R.
class FloatErrorBound {
public:
    FloatErrorBound(const Fractal& fractal, const DualQuat& start) : fractal_(fractal), a_(start.a), b_(start.b) {
        deltaA_ = kUnit * norm(a_);
        deltaB_ = kUnit * norm(b_);
    }

    /// True if, at iteration `k` (1-based), the tested norm is within rounding of the bailout.
    bool nearBailoutAt(int k) {
        while (iteration_ < k) step();
        const double bailout = fractal_.bailout;
        const double ra = norm(a_), rb = norm(b_);
        auto near = [&](double value, double delta) {
            return std::abs(value - bailout) <= 2.0 * (delta + 4.0 * kUnit * value) + kUnit * bailout;
        };
        switch (fractal_.variant) {
            case Variant::Paper: return near(ra, deltaA_) || near(rb, deltaB_);
            case Variant::PaperCoupled: return near(std::sqrt(ra * ra + rb * rb), deltaA_ + deltaB_);
            case Variant::Dual: return near(ra, deltaA_);
        }
        return false;
    }

private:
    static constexpr double kUnit = 0x1p-24;

    void step() {
        const double ra = norm(a_), rb = norm(b_);
        deltaA_ = 2.0 * ra * deltaA_ + deltaA_ * deltaA_ + 8.0 * kUnit * (ra * ra + norm(fractal_.c.a));
        deltaB_ = 2.0 * rb * deltaB_ + deltaB_ * deltaB_ + 8.0 * kUnit * (rb * rb + norm(fractal_.c.b));
        const Quat previous = a_;
        a_ = square(a_) + fractal_.c.a;
        b_ = fractal_.variant == Variant::Dual ? symmetricProduct(previous, b_) + fractal_.c.b
                                               : square(b_) + fractal_.c.b;
        ++iteration_;
    }

    Fractal fractal_;
    Quat a_, b_;
    double deltaA_ = 0.0, deltaB_ = 0.0;
    int iteration_ = 0;
};

}  // namespace

TEST(BatchTargets, ListsTheDispatchedTargetFirstAndAPortableFallbackLast) {
    const std::vector<BatchTarget> targets = batchTargets();
    ASSERT_FALSE(targets.empty());
    EXPECT_EQ(bestBatchTarget().id, targets.front().id);
    EXPECT_TRUE(targets.back().name == "EMU128" || targets.back().name == "SCALAR") << targets.back().name;
    EXPECT_GE(batchLanes(true), batchLanes(false));
    std::string names;
    for (const BatchTarget& target : targets) names += target.name + " ";
    std::printf("batch targets on this CPU: %s(lanes: %zu double, %zu float)\n", names.c_str(), batchLanes(false),
                batchLanes(true));
}

TEST(BatchTargets, RejectsTargetsThisCpuCannotRunAndNullArrays) {
    const Fractal fractal = makeFractal(kC2, Variant::Paper, 10);
    double x = 0.0;
    std::int32_t n = 0;
    PointBatch<double> points;
    points.coords.fill(&x);
    points.count = 1;
    const EscapeBatch<double> out{&n, &x, &x, &x, &x, &x};
    EXPECT_THROW(evaluateBatch(fractal, points, out, 3), std::invalid_argument);  // two bits: not one target
    std::int64_t compiled = 0;
    for (const BatchTarget& target : batchTargets()) compiled |= target.id;
    for (int bit = 0; bit < 63; ++bit) {  // an instruction set not compiled in or not supported here
        const std::int64_t target = std::int64_t{1} << bit;
        if ((compiled & target) == 0) {
            EXPECT_THROW(evaluateBatch(fractal, points, out, target), std::invalid_argument) << "bit " << bit;
            break;
        }
    }
    points.coords[5] = nullptr;
    EXPECT_THROW(evaluateBatch(fractal, points, out), std::invalid_argument);
    points.count = 0;  // nothing to do: nothing is read
    EXPECT_NO_THROW(evaluateBatch(fractal, points, out));
}

// Double precision: identical to evaluate() on every target, for every variant, several N, the
// three constants, and every tail length (counts that are not a multiple of the lanes).
TEST(BatchDouble, MatchesEvaluateOnEveryTarget) {
    const std::vector<DualQuat> points = samplePoints(20011, 1);
    for (const BatchTarget& target : batchTargets()) {
        for (const DualQuat& c : {kC1, kC2, kQuaternionJulia}) {
            for (const Variant variant : kVariants) {
                for (const int iterations : {1, 6, 15, 40}) {
                    const Fractal fractal = makeFractal(c, variant, iterations);
                    const Results<double> got = runBatch<double>(fractal, points, target.id);
                    int failures = 0;
                    for (std::size_t i = 0; i < points.size() && failures < 5; ++i) {
                        const Escape want = evaluate(fractal, points[i]);
                        const bool same = got.n[i] == want.n && got.r[i] == want.r && got.ra[i] == want.ra &&
                                          got.rb[i] == want.rb && got.trap[i] == want.trap &&
                                          sameDistance(want.de, got.de[i], 1e-12);
                        if (!same) {
                            ++failures;
                            ADD_FAILURE()
                                << target.name << " " << describe(fractal) << " point " << i << ": n " << got.n[i]
                                << " vs " << want.n << ", r " << got.r[i] << " vs " << want.r << ", ra " << got.ra[i]
                                << " vs " << want.ra << ", rb " << got.rb[i] << " vs " << want.rb << ", trap "
                                << got.trap[i] << " vs " << want.trap << ", de " << got.de[i] << " vs " << want.de;
                        }
                    }
                }
            }
        }
    }
}

TEST(BatchDouble, EveryCountAndTail) {
    const std::vector<DualQuat> all = samplePoints(40, 2);
    const Fractal fractal = makeFractal(kC2, Variant::Dual, 12);
    for (const BatchTarget& target : batchTargets()) {
        for (std::size_t count = 1; count <= all.size(); ++count) {
            const std::vector<DualQuat> points(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(count));
            const Results<double> got = runBatch<double>(fractal, points, target.id);
            for (std::size_t i = 0; i < count; ++i) {
                const Escape want = evaluate(fractal, points[i]);
                ASSERT_EQ(got.n[i], want.n) << target.name << " count " << count << " point " << i;
                ASSERT_EQ(got.ra[i], want.ra) << target.name << " count " << count << " point " << i;
            }
        }
    }
}

// Huge, infinite and NaN starts: the kernel follows evaluate() through overflow, NaN included
// (std::min/std::max semantics for the trap, the paper's r and its DE).
TEST(BatchDouble, ExtremeStartsMatchIncludingInfinitiesAndNaN) {
    const double inf = std::numeric_limits<double>::infinity();
    const double values[] = {1e300, 1e160, -1e200, inf, -inf, std::nan(""), 0.0, -0.0, 3.0, 1e-320};
    std::vector<DualQuat> points;
    for (const double x : values) points.push_back(DualQuat{makeQuat(x, 0.1, 0.0, 0.0), makeQuat(0.2, x, 0.0, 0.0)});
    auto same = [](double a, double b) { return a == b || (std::isnan(a) && std::isnan(b)); };
    for (const BatchTarget& target : batchTargets()) {
        for (const Variant variant : kVariants) {
            const Fractal fractal = makeFractal(kC2, variant, 15);
            const Results<double> got = runBatch<double>(fractal, points, target.id);
            for (std::size_t i = 0; i < points.size(); ++i) {
                const Escape want = evaluate(fractal, points[i]);
                EXPECT_EQ(got.n[i], want.n) << target.name << " " << describe(fractal) << " x = " << values[i];
                EXPECT_TRUE(same(got.r[i], want.r) && same(got.ra[i], want.ra) && same(got.rb[i], want.rb) &&
                            same(got.trap[i], want.trap) &&
                            (same(got.de[i], want.de) || sameDistance(want.de, got.de[i], 1e-12)))
                    << target.name << " " << describe(fractal) << " x = " << values[i] << ": r " << got.r[i] << " vs "
                    << want.r << ", de " << got.de[i] << " vs " << want.de << ", trap " << got.trap[i] << " vs "
                    << want.trap;
            }
        }
    }
}

TEST(BatchBuffer, AddEvaluateAndReadBack) {
    const Fractal fractal = makeFractal(kC1, Variant::Paper, 15);
    BatchBuffer<double> buffer;
    const std::vector<DualQuat> points = samplePoints(100, 3);
    for (int round = 0; round < 2; ++round) {  // reuse after clear()
        buffer.clear();
        for (const DualQuat& z : points) buffer.add(z);
        ASSERT_EQ(buffer.size(), points.size());
        buffer.evaluate(fractal);
        for (std::size_t i = 0; i < points.size(); ++i) {
            const Escape want = evaluate(fractal, points[i]);
            const Escape got = buffer.escape(i);
            EXPECT_EQ(got.n, want.n);
            EXPECT_EQ(got.r, want.r);
            EXPECT_EQ(got.trap, want.trap);
            EXPECT_TRUE(sameDistance(want.de, got.de, 1e-12)) << got.de << " vs " << want.de;
        }
    }
}

// Float: escape counts equal the double reference except where rounding decides (documented in
// batch.hpp). Every mismatch must be explained by FloatErrorBound. Over a million points of the
// renderer's and the bake's space they must also be rare; near the surface they are common (the
// derivative amplifies rounding), but still all explained.
struct FloatCounts {
    std::size_t total = 0, mismatches = 0, unexplained = 0;
};

FloatCounts compareFloat(const Fractal& fractal, const std::vector<DualQuat>& points, const BatchTarget& target) {
    FloatCounts counts;
    const Results<float> got = runBatch<float>(fractal, points, target.id);
    for (std::size_t i = 0; i < points.size(); ++i) {
        ++counts.total;
        const Escape want = evaluate(fractal, points[i]);
        if (got.n[i] == want.n) continue;
        ++counts.mismatches;
        const int never = fractal.iterations + 1;
        const int deciding = std::min(want.n ? want.n : never, got.n[i] ? got.n[i] : never);
        FloatErrorBound bound(fractal, points[i]);
        if (!bound.nearBailoutAt(deciding) && ++counts.unexplained <= 5)
            ADD_FAILURE() << target.name << " " << describe(fractal) << " point " << i << ": float n " << got.n[i]
                          << ", double n " << want.n << ", not within rounding of the bailout";
    }
    return counts;
}

TEST(BatchFloat, EscapeCountsMatchExceptWithinRoundingOfTheBailout) {
    const std::vector<DualQuat> points = samplePoints(1000002 / 3, 4);
    for (const BatchTarget& target : batchTargets()) {
        FloatCounts all;
        for (const Variant variant : kVariants) {
            const Fractal fractal = makeFractal(variant == Variant::Paper ? kC2 : kQuaternionJulia, variant, 12);
            const FloatCounts counts = compareFloat(fractal, points, target);
            all.total += counts.total;
            all.mismatches += counts.mismatches;
            all.unexplained += counts.unexplained;
        }
        std::printf("%s float, uniform points: %zu of %zu escape counts differ from double, %zu not near the bailout\n",
                    target.name.c_str(), all.mismatches, all.total, all.unexplained);
        EXPECT_EQ(all.unexplained, 0u) << target.name;
        EXPECT_LT(all.mismatches, all.total / 1000) << target.name << ": more than 0.1% of escape counts differ";
    }
}

TEST(BatchFloat, NearTheSurfaceEveryMismatchIsWithinRounding) {
    for (const Variant variant : kVariants) {
        for (const int iterations : {12, 30}) {
            const Fractal fractal =
                makeFractal(variant == Variant::Paper ? kC2 : kQuaternionJulia, variant, iterations);
            const std::vector<DualQuat> points = surfacePoints(fractal, 50000, 6);
            for (const BatchTarget& target : {batchTargets().front(), batchTargets().back()}) {
                const FloatCounts counts = compareFloat(fractal, points, target);
                std::printf(
                    "%s float, %s, points within 1e-4 of the surface: %zu of %zu escape counts differ, %zu not "
                    "near the bailout\n",
                    target.name.c_str(), describe(fractal).c_str(), counts.mismatches, counts.total,
                    counts.unexplained);
                EXPECT_EQ(counts.unexplained, 0u) << target.name << " " << describe(fractal);
            }
        }
    }
}

// Where the counts agree the float values are close; the DE within 1e-3 relative for the great
// majority (near the surface the derivative amplifies rounding, so a few are further off).
TEST(BatchFloat, DistanceEstimatesAreClose) {
    const std::vector<DualQuat> points = samplePoints(100000, 5);
    for (const Variant variant : kVariants) {
        const Fractal fractal = makeFractal(kQuaternionJulia, variant, 12);
        const Results<float> got = runBatch<float>(fractal, points, 0);
        std::size_t compared = 0, far = 0;
        for (std::size_t i = 0; i < points.size(); ++i) {
            const Escape want = evaluate(fractal, points[i]);
            if (got.n[i] != want.n || want.n == 0 || !std::isfinite(want.de)) continue;
            ++compared;
            if (!(std::abs(got.de[i] - want.de) <= 1e-3 * want.de)) ++far;
        }
        EXPECT_GT(compared, points.size() / 4) << describe(fractal);
        EXPECT_LT(far, compared / 100) << describe(fractal) << ": " << far << " of " << compared;
    }
}
