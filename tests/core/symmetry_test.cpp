// Symmetries of the iteration (math.md, "Symmetries") as property tests on pseudo-random
// points and constants, plus the algebra helpers they rest on.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>

#include "dqjulia/algebra.hpp"
#include "dqjulia/estimate.hpp"
#include "test_support.hpp"

namespace {

using dqj::DualQuat;
using dqj::Escape;
using dqj::Fractal;
using dqj::makeQuat;
using dqj::Quat;
using dqj::Variant;

const DualQuat kC1{makeQuat(-0.10, 0.8, -0.26, 0.15), makeQuat(-0.23, -0.38, -0.86, 0.64)};
const DualQuat kC2{makeQuat(-0.39054, -0.58679, 0.0, 0.0), makeQuat(0.0, 0.5632, 0.0, 0.05)};
constexpr Variant kVariants[] = {Variant::Paper, Variant::PaperCoupled, Variant::Dual};
constexpr int kPointsPerFractal = 400;

using dqj::test::Random;

/// A quaternion uniform in the 4-D ball of `radius`.
Quat inBall(Random& random, double radius) {
    while (true) {
        const Quat q =
            makeQuat(random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1));
        if (dqj::dot4(q, q) <= 1.0) return q * radius;
    }
}

/// A random quaternion constant whose set is connected: its equivalent complex number
/// c0 + |c_v| i (math.md) keeps the critical orbit bounded. Dust would leave nothing inside.
Quat randomConstant(Random& random) {
    while (true) {
        const Quat c = makeQuat(random.uniform(-0.8, 0.3), random.uniform(-0.6, 0.6), random.uniform(-0.6, 0.6),
                                random.uniform(-0.6, 0.6));
        const double re = c.w;
        const double im = std::sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
        double x = 0.0;
        double y = 0.0;
        int step = 0;
        for (; step < 500 && x * x + y * y <= 4.0; ++step) {
            const double next = x * x - y * y + re;
            y = 2.0 * x * y + im;
            x = next;
        }
        if (step == 500) return c;
    }
}

/// c1, c2 and a few random constants, each under every variant; N = 15 (the paper's default), R = 4.
std::vector<Fractal> testFractals(Random& random) {
    std::vector<DualQuat> constants{kC1, kC2};
    for (int index = 0; index < 4; ++index) constants.push_back({randomConstant(random), randomConstant(random)});
    std::vector<Fractal> fractals;
    for (const DualQuat& c : constants) {
        for (Variant variant : kVariants) {
            Fractal fractal;
            fractal.c = c;
            fractal.variant = variant;
            fractal.iterations = 15;
            fractal.bailout = 4.0;
            fractals.push_back(fractal);
        }
    }
    return fractals;
}

std::string describe(const Fractal& fractal, const DualQuat& z) {
    std::string text = std::string(dqj::variantName(fractal.variant)) + " c=(";
    for (double value : dqj::toVec8(fractal.c)) text += std::to_string(value) + " ";
    text += ") z=(";
    for (double value : dqj::toVec8(z)) text += std::to_string(value) + " ";
    return text + ")";
}

/// A third of the points uniform (a and b in the 4-D ball of radius 1.5), a third with b small
/// (near 0, which lies in K(c_b) for the connected sets), and a third pushed onto the boundary by
/// bisecting along the ray through such a point: long orbits, large derivatives, small DE.
DualQuat samplePoint(const Fractal& fractal, int index, DualQuat direction) {
    if (index % 3 == 0) return direction;
    direction.b = direction.b * 0.2;
    if (index % 3 == 1) return direction;
    auto scaled = [&](double t) { return DualQuat{direction.a * t, direction.b * t}; };
    if (dqj::evaluate(fractal, scaled(0.0)).n != 0 || dqj::evaluate(fractal, direction).n == 0) return direction;
    double inside = 0.0;
    double outside = 1.0;
    for (int step = 0; step < 30; ++step) {
        const double middle = 0.5 * (inside + outside);
        (dqj::evaluate(fractal, scaled(middle)).n == 0 ? inside : outside) = middle;
    }
    return scaled(outside);
}

/// A point whose escape count changes under perturbations far larger than rounding: some
/// iterate sits within rounding of the bailout sphere, so a symmetry that only holds up to
/// rounding may legitimately change its count there.
bool nearBailout(const Fractal& fractal, const DualQuat& z, const Escape& reference, Random& random) {
    for (int trial = 0; trial < 4; ++trial) {
        DualQuat moved = z;
        for (int index = 0; index < 8; ++index) dqj::component(moved, index) += random.uniform(-1e-12, 1e-12);
        const Escape escape = dqj::evaluate(fractal, moved);
        if (escape.n != reference.n) return true;
    }
    return false;
}

double relativeDifference(double actual, double expected) {
    if (actual == expected) return 0.0;  // also covers +inf == +inf
    return std::abs(actual - expected) / std::max(std::abs(expected), 1e-300);
}

Quat transform(const glm::dmat3& m, const Quat& q) {
    const glm::dvec3 v = m * glm::dvec3(q.x, q.y, q.z);
    return makeQuat(q.w, v.x, v.y, v.z);
}

DualQuat transform(const glm::dmat3& m, const DualQuat& z) { return {transform(m, z.a), transform(m, z.b)}; }

glm::dmat3 randomRotation(Random& random) {
    const glm::dvec3 axis = random.unitVector();
    const double angle = random.uniform(0.3, 3.0);
    return glm::mat3_cast(glm::angleAxis(angle, axis));
}

/// Householder reflection x - 2 (n.x) n: orthogonal with determinant -1.
glm::dmat3 randomReflection(Random& random) {
    const glm::dvec3 n = random.unitVector();
    return glm::dmat3(1.0) - 2.0 * glm::outerProduct(n, n);
}

/// Counts of checked and skipped (near-bailout) points, and the worst DE disagreement.
struct Tally {
    int checked = 0;
    int skipped = 0;
    double worstDe = 0.0;
    void report(const std::string& what) const {
        std::cout << "[ Symmetry ] " << what << ": " << checked << " points checked, " << skipped
                  << " skipped near the bailout, worst relative DE difference " << worstDe << "\n";
    }
};

/// Both evaluations must agree: escape count exactly, DE and norms to relative 1e-10.
void expectSame(const Escape& expected, const Escape& actual, Tally& tally, const std::string& context) {
    EXPECT_EQ(actual.n, expected.n) << context;
    const double deDifference = relativeDifference(actual.de, expected.de);
    tally.worstDe = std::max(tally.worstDe, deDifference);
    EXPECT_LE(deDifference, 1e-10) << context << " DE " << actual.de << " vs " << expected.de;
    EXPECT_LE(relativeDifference(actual.ra, expected.ra), 1e-10) << context;
    EXPECT_LE(relativeDifference(actual.rb, expected.rb), 1e-10) << context;
    ++tally.checked;
}

// ---- q -> -q ---------------------------------------------------------------------------------

TEST(Symmetry, NegationIsBitIdentical) {
    Random random(20240611);
    int escaped = 0;
    int evaluated = 0;
    for (const Fractal& fractal : testFractals(random)) {
        for (int point = 0; point < kPointsPerFractal; ++point) {
            const DualQuat z = samplePoint(fractal, point, {inBall(random, 1.5), inBall(random, 1.5)});
            const Escape reference = dqj::evaluate(fractal, z);
            escaped += reference.n != 0;
            ++evaluated;
            // The paper rules square a and b separately, so each may be negated on its own;
            // the dual rule couples them through ab + ba, so only the pair flips.
            std::vector<DualQuat> images{{-z.a, -z.b}};
            if (fractal.variant != Variant::Dual) {
                images.push_back({-z.a, z.b});
                images.push_back({z.a, -z.b});
            }
            for (const DualQuat& image : images) {
                const Escape negated = dqj::evaluate(fractal, image);
                const std::string context = describe(fractal, z);
                EXPECT_EQ(negated.n, reference.n) << context;
                EXPECT_EQ(negated.r, reference.r) << context;
                EXPECT_EQ(negated.ra, reference.ra) << context;
                EXPECT_EQ(negated.rb, reference.rb) << context;
                EXPECT_EQ(negated.de, reference.de) << context;
            }
        }
    }
    // Both outcomes must be well represented, or the test says little (c1 and the paper rules
    // leave few points inside: the paper's first constant has a dust dual part).
    EXPECT_GT(escaped, evaluated / 2);
    EXPECT_GT(evaluated - escaped, evaluated / 20);
}

// ---- orthogonal maps of the imaginary axes -----------------------------------------------------

void checkOrthogonalMap(const glm::dmat3& m, const Fractal& fractal, const DualQuat& z, Random& random, Tally& tally) {
    const Escape reference = dqj::evaluate(fractal, z);
    if (nearBailout(fractal, z, reference, random)) {
        ++tally.skipped;
        return;
    }
    Fractal mapped = fractal;
    mapped.c = transform(m, fractal.c);
    const Escape image = dqj::evaluate(mapped, transform(m, z));
    expectSame(reference, image, tally, describe(fractal, z));
    // The exit state maps too: f_{Mc}(Mq) = M f_c(q), to rounding relative to each part's size.
    const DualQuat expectedExit = transform(m, reference.exit);
    const Quat aError = image.exit.a - expectedExit.a;
    const Quat bError = image.exit.b - expectedExit.b;
    EXPECT_LE(dqj::norm(aError), 1e-9 * dqj::norm(expectedExit.a)) << describe(fractal, z);
    EXPECT_LE(dqj::norm(bError), 1e-9 * dqj::norm(expectedExit.b)) << describe(fractal, z);
}

TEST(Symmetry, OrthogonalMapsOfImaginaryAxes) {
    Random random(77);
    Tally rotations;
    Tally reflections;
    for (const Fractal& fractal : testFractals(random)) {
        for (int point = 0; point < kPointsPerFractal; ++point) {
            const DualQuat z = samplePoint(fractal, point, {inBall(random, 1.5), inBall(random, 1.5)});
            checkOrthogonalMap(randomRotation(random), fractal, z, random, rotations);
            checkOrthogonalMap(randomReflection(random), fractal, z, random, reflections);
        }
    }
    rotations.report("rotations");
    reflections.report("reflections");
    for (const Tally* tally : {&rotations, &reflections}) {
        EXPECT_GT(tally->checked, 0);
        EXPECT_LE(tally->skipped, (tally->checked + tally->skipped) / 100);
    }
}

// ---- solids of revolution ----------------------------------------------------------------------

/// `z` and `turned` differ by a rotation that fixes c, so they must give the same result.
void checkRevolution(const Fractal& fractal, const DualQuat& z, const DualQuat& turned, Random& random, Tally& tally) {
    const Escape reference = dqj::evaluate(fractal, z);
    if (nearBailout(fractal, z, reference, random)) {
        ++tally.skipped;
        return;
    }
    expectSame(reference, dqj::evaluate(fractal, turned), tally, describe(fractal, z));
}

TEST(Symmetry, ConstantInOneIPlaneGivesSolidOfRevolution) {
    Random random(4242);
    Tally tally;
    for (int constant = 0; constant < 6; ++constant) {
        // c = c2 first, then random constants in the 1-i plane for both parts.
        DualQuat c = kC2;
        c.b = makeQuat(0.0, 0.5632, 0.0, 0.0);
        if (constant > 0)
            c = {makeQuat(random.uniform(-0.6, 0.4), random.uniform(-0.7, 0.7), 0, 0),
                 makeQuat(random.uniform(-0.6, 0.4), random.uniform(-0.7, 0.7), 0, 0)};
        for (Variant variant : kVariants) {
            Fractal fractal;
            fractal.c = c;
            fractal.variant = variant;
            for (int point = 0; point < kPointsPerFractal; ++point) {
                // b0 in the 1-i plane too, so the rotation in the j-k plane fixes it.
                const DualQuat z =
                    samplePoint(fractal, point,
                                {inBall(random, 1.5), makeQuat(random.uniform(-1, 1), random.uniform(-1, 1), 0, 0)});
                const DualQuat turned{makeQuat(z.a.w, z.a.x, std::hypot(z.a.y, z.a.z), 0.0), z.b};
                checkRevolution(fractal, z, turned, random, tally);
            }
        }
    }
    tally.report("c in the 1-i plane");
    EXPECT_GT(tally.checked, 0);
    EXPECT_LE(tally.skipped, (tally.checked + tally.skipped) / 100);
}

TEST(Symmetry, RealConstantGivesSolidOfRevolutionAboutRealAxis) {
    Random random(9001);
    Tally tally;
    for (int constant = 0; constant < 6; ++constant) {
        const DualQuat c{makeQuat(random.uniform(-1.5, 0.25), 0, 0, 0), makeQuat(random.uniform(-1.5, 0.25), 0, 0, 0)};
        for (Variant variant : kVariants) {
            Fractal fractal;
            fractal.c = c;
            fractal.variant = variant;
            for (int point = 0; point < kPointsPerFractal; ++point) {
                const DualQuat z =
                    samplePoint(fractal, point, {inBall(random, 1.5), makeQuat(random.uniform(-1, 1), 0, 0, 0)});
                const double vector = std::sqrt(z.a.x * z.a.x + z.a.y * z.a.y + z.a.z * z.a.z);
                const DualQuat turned{makeQuat(z.a.w, vector, 0.0, 0.0), z.b};
                checkRevolution(fractal, z, turned, random, tally);
            }
        }
    }
    tally.report("real c");
    EXPECT_GT(tally.checked, 0);
    EXPECT_LE(tally.skipped, (tally.checked + tally.skipped) / 100);
}

// ---- algebra helpers ---------------------------------------------------------------------------

TEST(SymmetryAlgebra, ComponentOrderMapsToGlmByName) {
    const Quat q = makeQuat(1, 2, 3, 4);
    EXPECT_EQ(q.w, 1.0);
    EXPECT_EQ(q.x, 2.0);
    EXPECT_EQ(q.y, 3.0);
    EXPECT_EQ(q.z, 4.0);
    EXPECT_EQ(dqj::scalarPart(q), 1.0);
    for (int index = 0; index < 4; ++index) EXPECT_EQ(dqj::component(q, index), index + 1.0);

    const dqj::Vec8 v{1, 2, 3, 4, 5, 6, 7, 8};
    const DualQuat z = dqj::toDualQuat(v);
    EXPECT_EQ(z.a.w, 1.0);
    EXPECT_EQ(z.a.z, 4.0);
    EXPECT_EQ(z.b.w, 5.0);
    EXPECT_EQ(z.b.x, 6.0);
    EXPECT_EQ(z.b.z, 8.0);
    for (int index = 0; index < 8; ++index) EXPECT_EQ(dqj::component(z, index), v[index]);
    EXPECT_EQ(dqj::toVec8(z), v);

    DualQuat written;
    dqj::component(written, 6) = 2.5;  // b.j
    EXPECT_EQ(written.b.y, 2.5);
}

TEST(SymmetryAlgebra, SquareAndSymmetricProductMatchHamiltonProduct) {
    Random random(12345);
    for (int trial = 0; trial < 1000; ++trial) {
        const Quat a = inBall(random, 1.5);
        const Quat b = inBall(random, 1.5);
        const Quat square = dqj::square(a);
        const Quat product = a * a;  // glm's Hamilton product
        const double squareScale = 1e-15 * std::max(1.0, dqj::dot4(a, a));
        for (int index = 0; index < 4; ++index)
            EXPECT_NEAR(dqj::component(square, index), dqj::component(product, index), squareScale);

        const Quat symmetric = dqj::symmetricProduct(a, b);
        const Quat sum = a * b + b * a;
        const double symmetricScale = 4e-15 * std::max(1.0, dqj::norm(a) * dqj::norm(b));
        for (int index = 0; index < 4; ++index)
            EXPECT_NEAR(dqj::component(symmetric, index), dqj::component(sum, index), symmetricScale);
    }
    // A fixed case by hand: (1 + 2i)^2 = 1 - 4 + 4i.
    const Quat square = dqj::square(makeQuat(1, 2, 0, 0));
    EXPECT_EQ(square.w, -3.0);
    EXPECT_EQ(square.x, 4.0);
    // i j + j i = k - k = 0; (1 + i)(2 j) + (2 j)(1 + i) = 4 j.
    const Quat anticommuting = dqj::symmetricProduct(makeQuat(0, 1, 0, 0), makeQuat(0, 0, 1, 0));
    EXPECT_EQ(dqj::dot4(anticommuting, anticommuting), 0.0);
    const Quat mixed = dqj::symmetricProduct(makeQuat(1, 1, 0, 0), makeQuat(0, 0, 2, 0));
    EXPECT_EQ(mixed.w, 0.0);
    EXPECT_EQ(mixed.x, 0.0);
    EXPECT_EQ(mixed.y, 4.0);
    EXPECT_EQ(mixed.z, 0.0);
}

}  // namespace
