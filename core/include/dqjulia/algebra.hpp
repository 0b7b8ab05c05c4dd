// dqjulia/algebra.hpp - quaternion and dual-quaternion arithmetic (math.md, "Conventions").
//
// A quaternion is written (s, i, j, k), scalar first. We store it in glm::dquat,
// whose scalar is the member `w` and whose constructor takes (w, x, y, z): the
// mapping s->w, i->x, j->y, k->z is done here, by name, never by memory layout.
// A dual quaternion is a + b*eps with eps^2 = 0: `a` the real part, `b` the dual
// part; in files and on the command line it is 8 numbers, a's four then b's four.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>

#include <glm/gtc/quaternion.hpp>

namespace dqj {

using Quat = glm::dquat;

/// Quaternion from its components in the project's (s, i, j, k) order.
inline Quat makeQuat(double s, double i, double j, double k) { return Quat(s, i, j, k); }
inline double scalarPart(const Quat& q) { return q.w; }
/// Component by the project's index: 0 = s, 1 = i, 2 = j, 3 = k.
inline double component(const Quat& q, int index) {
    switch (index) {
        case 0: return q.w;
        case 1: return q.x;
        case 2: return q.y;
        default: return q.z;
    }
}
inline double& component(Quat& q, int index) {
    switch (index) {
        case 0: return q.w;
        case 1: return q.x;
        case 2: return q.y;
        default: return q.z;
    }
}

inline double dot4(const Quat& p, const Quat& q) { return p.w * q.w + p.x * q.x + p.y * q.y + p.z * q.z; }
inline double norm(const Quat& q) { return std::sqrt(dot4(q, q)); }

/// sqrt(x^2 + y^2) without overflow or underflow: the length of the 8-D vector (a, b) from
/// |a| and |b|. The library's own, rather than std::hypot, so every build of it (the static
/// archive, the self-contained shared library, any glibc) rounds the same way.
inline double hypot2(double x, double y) {
    x = std::fabs(x);
    y = std::fabs(y);
    const double big = std::max(x, y);
    if (!(big > 0.0) || std::isinf(big)) return x + y;  // zero, infinity or NaN
    const double u = x / big, v = y / big;
    return big * std::sqrt(u * u + v * v);
}

/// Hamilton square: (s^2 - |v|^2, 2 s v). Cheaper than q*q and equal to it.
inline Quat square(const Quat& q) {
    return Quat(q.w * q.w - q.x * q.x - q.y * q.y - q.z * q.z, 2.0 * q.w * q.x, 2.0 * q.w * q.y, 2.0 * q.w * q.z);
}

/// sym(a, b) = ab + ba = (2(a0 b0 - a_v.b_v), 2(a0 b_v + b0 a_v)); the cross products cancel.
/// It is the dual part of (a + b eps)^2 in the true algebra.
inline Quat symmetricProduct(const Quat& a, const Quat& b) {
    return Quat(2.0 * (a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z), 2.0 * (a.w * b.x + b.w * a.x),
                2.0 * (a.w * b.y + b.w * a.y), 2.0 * (a.w * b.z + b.w * a.z));
}

/// A point of the 8-D space: real part a, dual part b.
struct DualQuat {
    Quat a{0.0, 0.0, 0.0, 0.0};
    Quat b{0.0, 0.0, 0.0, 0.0};
};

/// Component by 8-D index: 0..3 are a's (s, i, j, k), 4..7 are b's.
inline double component(const DualQuat& z, int index) {
    return index < 4 ? component(z.a, index) : component(z.b, index - 4);
}
inline double& component(DualQuat& z, int index) {
    return index < 4 ? component(z.a, index) : component(z.b, index - 4);
}

using Vec8 = std::array<double, 8>;

inline DualQuat toDualQuat(const Vec8& v) {
    return {makeQuat(v[0], v[1], v[2], v[3]), makeQuat(v[4], v[5], v[6], v[7])};
}
inline Vec8 toVec8(const DualQuat& z) {
    Vec8 v{};
    for (int index = 0; index < 8; ++index) v[index] = component(z, index);
    return v;
}

/// The three iteration rules the toolkit offers (math.md, "The three algebras").
enum class Variant {
    Paper,         ///< the paper's literal rule: a and b iterate independently, DE = max(DE_a, DE_b)
    PaperCoupled,  ///< the paper's rule with one 8-D norm for escape and DE
    Dual,          ///< the true dual-quaternion square a^2 + (ab + ba) eps; escape on |a|
};

}  // namespace dqj
