// The escape iteration of the three variants (math.md). Written once, in double precision;
// the renderer, the C ABI and the CLI all call evaluate().
#include "dqjulia/estimate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "dqjulia/schema.hpp"

namespace dqj {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

/// 0.5 |x| ln|x| / d for an escaped part; +inf when the derivative is zero
/// (the orbit started on the critical point), which the marcher treats as "take the largest step".
double partEstimate(double norm, double derivative) {
    if (derivative == 0.0) return kInfinity;
    return 0.5 * norm * std::log(norm) / derivative;
}

template <Variant V>
Escape iterate(const Fractal& fractal, const DualQuat& start) {
    const Quat ca = fractal.c.a;
    const Quat cb = fractal.c.b;
    // Squared throughout: sa = |a|^2, sb = |b|^2, the derivatives squared; sa > escapeAbove is
    // exactly |a| > R (squaredBailout). Square roots once, after the loop.
    const double escapeAbove = squaredBailout<double>(fractal.bailout);
    Quat a = start.a;
    Quat b = start.b;
    double sa = dot4(a, a);
    double sb = dot4(b, b);
    double s8 = sa + sb;  // paper-coupled: the 8-D norm squared
    double da = 1.0;      // paper, dual: |da|^2; paper-coupled: the 8-D dr^2
    double db = 1.0;
    double trap = sa;
    Escape result;
    for (int k = 1; k <= fractal.iterations; ++k) {
        if constexpr (V == Variant::Paper) {
            da *= 4.0 * sa;
            db *= 4.0 * sb;
            a = square(a) + ca;
            b = square(b) + cb;
        } else if constexpr (V == Variant::PaperCoupled) {
            da *= 4.0 * s8;
            a = square(a) + ca;
            b = square(b) + cb;
        } else {
            da *= 4.0 * sa;
            const Quat previous = a;  // b must use the old a
            a = square(a) + ca;
            b = symmetricProduct(previous, b) + cb;
        }
        sa = dot4(a, a);
        if constexpr (V != Variant::Dual) sb = dot4(b, b);  // dual: only needed at exit
        trap = std::min(trap, sa);
        bool escaped;
        if constexpr (V == Variant::Paper) {
            escaped = sa > escapeAbove || sb > escapeAbove;
        } else if constexpr (V == Variant::PaperCoupled) {
            s8 = sa + sb;
            escaped = s8 > escapeAbove;
        } else {
            escaped = sa > escapeAbove;
        }
        if (escaped) {
            result.n = k;
            break;
        }
    }
    if constexpr (V == Variant::Dual) sb = dot4(b, b);
    const double ra = std::sqrt(sa);
    const double rb = std::sqrt(sb);
    result.ra = ra;
    result.rb = rb;
    result.trap = std::sqrt(trap);
    result.exit = {a, b};
    if constexpr (V == Variant::Paper) {
        result.r = std::max(ra, rb);
        if (result.n != 0) {
            // max, not min: min is 0 wherever one part never escapes and the marcher stalls.
            const double deA = sa > escapeAbove ? partEstimate(ra, std::sqrt(da)) : 0.0;
            const double deB = sb > escapeAbove ? partEstimate(rb, std::sqrt(db)) : 0.0;
            result.de = std::max(deA, deB);
        }
    } else if constexpr (V == Variant::PaperCoupled) {
        result.r = std::sqrt(s8);
        if (result.n != 0) result.de = partEstimate(result.r, std::sqrt(da));
    } else {
        result.r = ra;
        if (result.n != 0) result.de = partEstimate(ra, std::sqrt(da));
    }
    return result;
}

}  // namespace

Escape evaluate(const Fractal& fractal, const DualQuat& start) {
    switch (fractal.variant) {
        case Variant::Paper: return iterate<Variant::Paper>(fractal, start);
        case Variant::PaperCoupled: return iterate<Variant::PaperCoupled>(fractal, start);
        case Variant::Dual: return iterate<Variant::Dual>(fractal, start);
    }
    return {};
}

double distanceEstimate(const Fractal& fractal, const DualQuat& start) { return evaluate(fractal, start).de; }

double containmentRadius(const Quat& c) { return 0.5 * (1.0 + std::sqrt(1.0 + 4.0 * norm(c))); }

double minimumBailout(const Fractal& fractal) {
    const double realRadius = containmentRadius(fractal.c.a);
    if (fractal.variant == Variant::Dual) return realRadius;  // only |a| is tested
    const double dualRadius = containmentRadius(fractal.c.b);
    // One 8-D norm: sqrt(|a|^2 + |b|^2) > R must imply |a| > r_K(c_a) or |b| > r_K(c_b),
    // else points of the set (both parts just inside their r_K) would count as escaped.
    if (fractal.variant == Variant::PaperCoupled) return hypot2(realRadius, dualRadius);
    return std::max(realRadius, dualRadius);
}

glm::dvec3 realPartGradient(const Fractal& fractal, const Quat& start, const Quat directions[3]) {
    Quat a = start;
    Quat b[3] = {directions[0], directions[1], directions[2]};
    const double escapeAbove = squaredBailout<double>(fractal.bailout);
    double normSquared = dot4(a, a);
    for (int k = 1; k <= fractal.iterations; ++k) {
        const Quat previous = a;
        a = square(a) + fractal.c.a;
        for (Quat& tangent : b) tangent = symmetricProduct(previous, tangent);  // c_b = 0
        normSquared = dot4(a, a);
        if (normSquared > escapeAbove) break;
    }
    if (normSquared == 0.0) return glm::dvec3(0.0);
    return glm::dvec3(dot4(a, b[0]), dot4(a, b[1]), dot4(a, b[2])) / normSquared;
}

std::string_view variantName(Variant variant) { return schema::choiceName("fractal.variant", int(variant)); }

}  // namespace dqj
