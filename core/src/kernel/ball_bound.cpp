// The rigorous ball bound (ball_bound.hpp). The escape tests and the DE follow estimate.cpp per
// variant, written in terms of the norms of the two quaternion orbits a <- a^2 + c_a and
// b <- b^2 + c_b: paper tests both, paper-coupled their 8-D norm, dual the real part alone (its
// dual part never enters the escape test or the DE).
#include "dqjulia/ball_bound.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dqj {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// One quaternion orbit with its radius of uncertainty `spread` and an upper bound
/// `derivative` on the derivative product of every orbit within the spread.
struct Tube {
    Quat z;
    double spread;
    double derivative = 1.0;

    double norm() const { return dqj::norm(z); }
    void step(const Quat& c) {
        const double r = norm();
        derivative *= 2.0 * (r + spread);
        spread = 2.0 * r * spread + spread * spread;
        z = square(z) + c;
    }
};

/// The least DE of a point that escapes with a norm of at least `least` (>= R > 1) and a derivative
/// product of at most `derivative`: 0.5 s ln s / D grows with s.
double leastEstimate(double least, double derivative) {
    return derivative > 0.0 ? 0.5 * least * std::log(least) / derivative : kInfinity;
}

/// A little slack on the starting radius covers the rounding of the centre's orbit, which is far
/// smaller than any radius the bake asks about.
double padded(double radius) { return radius * (1.0 + 1e-9) + 1e-12; }

}  // namespace

BallBound boundBall(const Fractal& fractal, const DualQuat& centre, double radiusA, double radiusB) {
    BallBound result;
    result.centre = evaluate(fractal, centre);
    const double bailout = fractal.bailout;
    double least = kInfinity;  // the least DE over the iterations at which a point could escape

    if (fractal.variant == Variant::PaperCoupled) {
        // One 8-D orbit (a, b): its norm spreads as one vector, since each part obeys the bound.
        Quat a = centre.a, b = centre.b;
        double spread = padded(hypot2(radiusA, radiusB));
        double derivative = 1.0;
        for (int k = 1; k <= fractal.iterations; ++k) {
            const double r = hypot2(norm(a), norm(b));
            derivative *= 2.0 * (r + spread);
            spread = 2.0 * r * spread + spread * spread;
            a = square(a) + fractal.c.a;
            b = square(b) + fractal.c.b;
            const double next = hypot2(norm(a), norm(b));
            if (!std::isfinite(next) || !std::isfinite(spread)) return result;
            if (next + spread > bailout)
                least = std::min(least, leastEstimate(std::max(bailout, next - spread), derivative));
            if (next - spread > bailout) {
                result.allEscape = true;
                result.minDe = least;
                return result;
            }
        }
        return result;
    }

    const bool testsDual = fractal.variant == Variant::Paper;  // dual: only the real part escapes
    Tube a{centre.a, padded(radiusA)};
    Tube b{centre.b, padded(radiusB)};
    for (int k = 1; k <= fractal.iterations; ++k) {
        a.step(fractal.c.a);
        if (testsDual) b.step(fractal.c.b);
        const double ra = a.norm();
        const double rb = testsDual ? b.norm() : 0.0;
        if (!std::isfinite(ra) || !std::isfinite(a.spread) || !std::isfinite(rb) || !std::isfinite(b.spread))
            return result;
        // A point escaping now has at least one part beyond R, and its DE is at least that part's.
        double now = kInfinity;
        bool possible = false;
        if (ra + a.spread > bailout) {
            possible = true;
            now = std::min(now, leastEstimate(std::max(bailout, ra - a.spread), a.derivative));
        }
        if (testsDual && rb + b.spread > bailout) {
            possible = true;
            now = std::min(now, leastEstimate(std::max(bailout, rb - b.spread), b.derivative));
        }
        if (possible) least = std::min(least, now);
        if (ra - a.spread > bailout || (testsDual && rb - b.spread > bailout)) {
            result.allEscape = true;
            result.minDe = least;
            return result;
        }
    }
    return result;
}

}  // namespace dqj
