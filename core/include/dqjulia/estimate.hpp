// dqjulia/estimate.hpp - the escape iteration and the distance estimate (math.md).
//
// zeta <- zeta^2 + c for at most N iterations with bailout R. Per iteration the
// derivative(s) are updated from the current state, then the state, then escape
// is tested. Norms and derivatives are carried squared (no square root in the loop);
// their square roots are taken once, at exit. Cost: at most N iterations of two
// quaternion squares per point.
#pragma once

#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

#include <glm/vec3.hpp>

#include "dqjulia/algebra.hpp"
#include "dqjulia/export.h"

namespace dqj {

/// What defines the set: constant, algebra, iteration count N and bailout R.
struct Fractal {
    DualQuat c{makeQuat(-0.39054, -0.58679, 0.0, 0.0), makeQuat(0.0, 0.5632, 0.0, 0.05)};
    Variant variant = Variant::Paper;
    int iterations = 15;
    double bailout = 4.0;
};

/// Result of iterating one 8-D point.
struct Escape {
    int n = 0;          ///< iteration at which the orbit escaped; 0 = did not escape within N
    double r = 0.0;     ///< the norm used for the escape test, at exit (paper: max(|a|,|b|))
    double ra = 0.0;    ///< |a| at exit
    double rb = 0.0;    ///< |b| at exit
    double de = 0.0;    ///< distance estimate in 8-D units; 0 inside, +inf for a zero derivative
    double trap = 0.0;  ///< orbit trap: the smallest |a| along the orbit (for colouring)
    DualQuat exit;      ///< the state at exit
};

/// Iterates `start` under the fractal and returns escape count, norms and DE exactly as math.md.
DQJ_API Escape evaluate(const Fractal& fractal, const DualQuat& start);

/// Only the distance estimate (same as evaluate(...).de).
DQJ_API double distanceEstimate(const Fractal& fractal, const DualQuat& start);

/// The largest x of type T with sqrt(x) <= bailout (square roots correctly rounded), so that
/// `s > squaredBailout<T>(R)` is exactly `sqrt(s) > R` for a squared norm s: the iteration tests
/// escape on squared norms and takes square roots once, at exit. max() when R^2 overflows (only
/// an infinite s escapes), +inf for an infinite R, NaN for a NaN R (nothing escapes), -inf for a
/// negative R (everything escapes, as sqrt(s) > R would).
template <typename T>
T squaredBailout(double bailout) {
    const T r = static_cast<T>(bailout);
    if (!(r < std::numeric_limits<T>::infinity())) return r;
    if (r < 0) return -std::numeric_limits<T>::infinity();
    T x = r * r;
    if (x == std::numeric_limits<T>::infinity()) x = std::numeric_limits<T>::max();
    while (x > 0 && std::sqrt(x) > r) x = std::nextafter(x, T(0));
    for (T up = std::nextafter(x, std::numeric_limits<T>::infinity()); std::sqrt(up) <= r;
         up = std::nextafter(x, std::numeric_limits<T>::infinity()))
        x = up;
    return x;
}

/// Any quaternion orbit with |q| > r_K(c) = (1 + sqrt(1 + 4|c|)) / 2 escapes.
DQJ_API double containmentRadius(const Quat& c);

/// The smallest bailout the fractal allows: the largest r_K of the parts tested for escape
/// (paper: both parts; dual: a only); for paper-coupled's single 8-D norm, hypot(r_K(c_a), r_K(c_b)),
/// so that an 8-D norm above R forces one part past its own r_K.
DQJ_API double minimumBailout(const Fractal& fractal);

/// Gradient of ln|a_n| with respect to the real part of the start point, along three
/// real-part directions, from the dual part of the true algebra (math.md, "dual"):
/// with c_b = 0 and b_0 = direction, grad = (a_n . b_n) / |a_n|^2. Exact, no finite differences.
DQJ_API glm::dvec3 realPartGradient(const Fractal& fractal, const Quat& start, const Quat directions[3]);

/// The variant's name in the parameter file: "paper", "paper-coupled" or "dual" (the schema's
/// choices, schema::choiceName; from a name back: schema::choiceIndex).
DQJ_API std::string_view variantName(Variant variant);

}  // namespace dqj
