// Inspection: Mandelbrot membership of the equivalent complex constants, inside fractions,
// and the reasons for empty slices that math.md requires.
#include <gtest/gtest.h>

#include "dqjulia/inspect.hpp"

namespace dqj {
namespace {

const DualQuat kC1{makeQuat(-0.10, 0.8, -0.26, 0.15), makeQuat(-0.23, -0.38, -0.86, 0.64)};
const DualQuat kC2{makeQuat(-0.39054, -0.58679, 0.0, 0.0), makeQuat(0.0, 0.5632, 0.0, 0.05)};

Params withConstant(const DualQuat& c, Variant variant, int iterations) {
    Params params;
    params.fractal.c = c;
    params.fractal.variant = variant;
    params.fractal.iterations = iterations;
    return params;
}

TEST(Inspect, EquivalentComplexConstantAndMandelbrotMembership) {
    const PartReport dual = inspectPart(kC1.b);
    EXPECT_DOUBLE_EQ(dual.complexReal, -0.23);
    EXPECT_NEAR(dual.complexImaginary, std::sqrt(0.38 * 0.38 + 0.86 * 0.86 + 0.64 * 0.64), 1e-15);
    EXPECT_FALSE(dual.inMandelbrot);  // math.md: c1's dual part is outside the Mandelbrot set
    EXPECT_GT(dual.mandelbrotEscape, 0);
    EXPECT_TRUE(inspectPart(kC2.a).inMandelbrot);
    EXPECT_TRUE(inspectPart(kC2.b).inMandelbrot);
    EXPECT_TRUE(inspectPart(makeQuat(0, 0, 0, 0)).inMandelbrot);
    EXPECT_FALSE(inspectPart(makeQuat(0.5, 0, 0, 0)).inMandelbrot);
    EXPECT_NEAR(inspectPart(makeQuat(0, 0, 0, 0)).containmentRadius, 1.0, 1e-15);
}

TEST(Inspect, PapersFirstConstantIsEmptyFromSixIterations) {
    for (int n : {6, 10, 15, 30}) {
        const InspectReport report = inspect(withConstant(kC1, Variant::Paper, n), 12);
        EXPECT_EQ(report.insideFraction, 0.0) << n;
        EXPECT_NE(report.emptyReason.find("empty for N >= 6"), std::string::npos) << report.emptyReason;
        EXPECT_NE(report.emptyReason.find("outside the Mandelbrot set"), std::string::npos) << report.emptyReason;
    }
    // math.md: at N <= 5 part of the box is inside (9.5% of its box; ours is the bounding cube).
    const InspectReport five = inspect(withConstant(kC1, Variant::Paper, 5), 24);
    EXPECT_TRUE(five.emptyReason.empty()) << five.emptyReason;
    EXPECT_GT(five.insideFraction, 0.01);
}

TEST(Inspect, DualVariantIgnoresTheDualPartForEscape) {
    // Under the true algebra c1 is an ordinary quaternion Julia set in a: not empty.
    const InspectReport report = inspect(withConstant(kC1, Variant::Dual, 15), 24);
    EXPECT_TRUE(report.emptyReason.empty()) << report.emptyReason;
    EXPECT_GT(report.insideFraction, 0.0);
}

TEST(Inspect, HighDetailConstantIsNotEmpty) {
    const InspectReport report = inspect(withConstant(kC2, Variant::Paper, 15), 24);
    EXPECT_TRUE(report.emptyReason.empty()) << report.emptyReason;
    EXPECT_GT(report.insideFraction, 0.01);
    EXPECT_LT(report.insideFraction, 0.6);
}

TEST(Inspect, SliceMissingTheContainmentBallIsEmptyForEveryN) {
    Params params = withConstant(kC2, Variant::Paper, 15);
    params.slice.base.origin[4] = 5.0;  // b.s = 5, beyond r_K(c_b)
    const InspectReport report = inspect(params, 8);
    EXPECT_FALSE(report.bounds.has_value());
    EXPECT_NE(report.emptyReason.find("empty for every N"), std::string::npos) << report.emptyReason;
}

TEST(Inspect, DustIsExplained) {
    // A real part far outside the Mandelbrot set: dust, no sample inside.
    const InspectReport report =
        inspect(withConstant({makeQuat(0.3, 0.9, 0.4, 0.0), makeQuat(0, 0, 0, 0)}, Variant::Dual, 20), 16);
    EXPECT_FALSE(report.real.inMandelbrot);
    EXPECT_FALSE(report.emptyReason.empty());
    EXPECT_NE(report.emptyReason.find("dust"), std::string::npos) << report.emptyReason;
}

TEST(Inspect, ReportsAreReadable) {
    const InspectReport report = inspect(withConstant(kC1, Variant::Paper, 15), 8);
    const std::string text = formatReport(report);
    EXPECT_NE(text.find("OUTSIDE the Mandelbrot set"), std::string::npos) << text;
    EXPECT_NE(reportJson(report).find("\"empty\": true"), std::string::npos);
}

}  // namespace
}  // namespace dqj
