// boundBall (ball_bound.hpp): every point of a ball it proves escaping escapes, with a distance
// estimate at least its bound, over random balls of every variant.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "dqjulia/ball_bound.hpp"
#include "dqjulia/estimate.hpp"
#include "dqjulia/params.hpp"

using namespace dqj;

namespace {

TEST(BallBound, EveryPointOfAProvenBallEscapesWithADeAboveTheBound) {
    std::mt19937 random(7);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    int proven = 0;
    for (const Variant variant : {Variant::Paper, Variant::PaperCoupled, Variant::Dual}) {
        Fractal fractal;
        fractal.variant = variant;
        fractal.bailout = minimumBailout(fractal) + 0.5;
        for (int trial = 0; trial < 300; ++trial) {
            DualQuat centre;
            for (int index = 0; index < 8; ++index)
                component(centre, index) = 1.6 * unit(random) * (index < 4 ? 1.0 : 0.3);
            const double radius = 0.05 * (1 + trial % 4);
            const BallBound bound = boundBall(fractal, centre, radius, radius);
            if (!bound.allEscape) continue;
            ++proven;
            for (int sample = 0; sample < 40; ++sample) {
                DualQuat q = centre;
                // A point of the ball (each part within the radius).
                double a[4], b[4], na = 0, nb = 0;
                for (int k = 0; k < 4; ++k) na += (a[k] = unit(random)) * a[k], nb += (b[k] = unit(random)) * b[k];
                const double sa = radius * std::abs(unit(random)) / std::sqrt(na),
                             sb = radius * std::abs(unit(random)) / std::sqrt(nb);
                for (int k = 0; k < 4; ++k) component(q, k) += sa * a[k], component(q, 4 + k) += sb * b[k];
                const Escape escape = evaluate(fractal, q);
                ASSERT_NE(escape.n, 0) << variantName(variant);
                ASSERT_GE(escape.de, bound.minDe * (1 - 1e-9)) << variantName(variant);
            }
        }
    }
    EXPECT_GT(proven, 100);
}

}  // namespace
