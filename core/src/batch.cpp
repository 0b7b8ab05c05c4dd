// The SIMD escape iteration (batch.hpp), compiled once per instruction set by Highway's
// foreach_target.h: this file includes itself once per target, each time inside that target's
// namespace (N_AVX3, N_AVX2, ..., N_EMU128), and HWY_EXPORT builds the table that
// HWY_DYNAMIC_DISPATCH picks from at run time.
//
// Every lane of a vector runs one point. Lanes that escape keep iterating with the others
// (their values may overflow to inf or NaN, which is harmless) while their outputs are frozen
// at the iteration they escaped; the vector stops when every lane has escaped or after N
// iterations. In double precision the arithmetic repeats estimate.cpp's operations in the same
// order without fused multiply-add (this file is compiled with -ffp-contract=off), so results
// are bit-identical to evaluate() apart from the logarithm in the DE. In float, multiply-adds
// are fused for speed.

// clang-format off
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "batch.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>
#include <hwy/contrib/math/math-inl.h>
// clang-format on

#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "dqjulia/batch.hpp"

HWY_BEFORE_NAMESPACE();
namespace dqj {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

/// The fractal in the kernel's precision.
template <typename T>
struct Constants {
    T ca[4];
    T cb[4];
    T bailout;
    int iterations;
};

template <class V>
struct QuatV {
    V s, i, j, k;
};

// a * b + c and c - a * b: fused in float; in double a separate multiply and add, so that the
// rounding is exactly estimate.cpp's.
template <class V>
HWY_INLINE V MulAddT(V a, V b, V c) {
    if constexpr (std::is_same_v<hn::TFromV<V>, float>) {
        return hn::MulAdd(a, b, c);
    } else {
        return hn::Add(hn::Mul(a, b), c);
    }
}
template <class V>
HWY_INLINE V SubMulT(V c, V a, V b) {
    if constexpr (std::is_same_v<hn::TFromV<V>, float>) {
        return hn::NegMulAdd(a, b, c);
    } else {
        return hn::Sub(c, hn::Mul(a, b));
    }
}

// std::min(a, b) and std::max(a, b) exactly, NaN included ((b < a) ? b : a and (a < b) ? b : a):
// Highway's Min and Max may treat a NaN differently, and orbits from infinite starts give NaNs.
template <class V>
HWY_INLINE V StdMin(V a, V b) {
    return hn::IfThenElse(hn::Lt(b, a), b, a);
}
template <class V>
HWY_INLINE V StdMax(V a, V b) {
    return hn::IfThenElse(hn::Lt(a, b), b, a);
}

/// |q| = sqrt(((s^2 + i^2) + j^2) + k^2), dot4's order.
template <class V>
HWY_INLINE V Norm(const QuatV<V>& q) {
    return hn::Sqrt(MulAddT(q.k, q.k, MulAddT(q.j, q.j, MulAddT(q.i, q.i, hn::Mul(q.s, q.s)))));
}

/// square(q) + c: (s^2 - i^2 - j^2 - k^2, 2 s i, 2 s j, 2 s k) + c.
template <class D, class V>
HWY_INLINE QuatV<V> SquarePlus(D d, const QuatV<V>& q, const V* c) {
    const V twoS = hn::Mul(hn::Set(d, 2), q.s);
    const V real = SubMulT(SubMulT(SubMulT(hn::Mul(q.s, q.s), q.i, q.i), q.j, q.j), q.k, q.k);
    return {hn::Add(real, c[0]), MulAddT(twoS, q.i, c[1]), MulAddT(twoS, q.j, c[2]), MulAddT(twoS, q.k, c[3])};
}

/// sym(a, b) + c = (2 (a0 b0 - a_v.b_v), 2 (a0 b_v + b0 a_v)) + c.
template <class D, class V>
HWY_INLINE QuatV<V> SymmetricPlus(D d, const QuatV<V>& a, const QuatV<V>& b, const V* c) {
    const V two = hn::Set(d, 2);
    const V real = SubMulT(SubMulT(SubMulT(hn::Mul(a.s, b.s), a.i, b.i), a.j, b.j), a.k, b.k);
    return {MulAddT(two, real, c[0]), MulAddT(two, MulAddT(b.s, a.i, hn::Mul(a.s, b.i)), c[1]),
            MulAddT(two, MulAddT(b.s, a.j, hn::Mul(a.s, b.j)), c[2]),
            MulAddT(two, MulAddT(b.s, a.k, hn::Mul(a.s, b.k)), c[3])};
}

/// 0.5 |x| ln|x| / d; +inf for a zero derivative (estimate.cpp's partEstimate).
template <class D, class V>
HWY_INLINE V PartEstimate(D d, V norm, V derivative) {
    const V estimate = hn::Div(hn::Mul(hn::Mul(hn::Set(d, 0.5), norm), hn::Log(d, norm)), derivative);
    return hn::IfThenElse(hn::Eq(derivative, hn::Zero(d)), hn::Set(d, std::numeric_limits<hn::TFromD<D>>::infinity()),
                          estimate);
}

/// One vector of points: loads lanes from `in` (8 arrays), stores the results to `out`
/// (n as T, then r, ra, rb, de, trap), all at index 0 of the given pointers.
template <Variant Var, class D, typename T = hn::TFromD<D>>
HWY_INLINE void IterateVector(D d, const Constants<T>& constants, const T* const* in, T* const* out) {
    using V = hn::Vec<D>;
    V ca[4], cb[4];
    for (int k = 0; k < 4; ++k) {
        ca[k] = hn::Set(d, constants.ca[k]);
        cb[k] = hn::Set(d, constants.cb[k]);
    }
    const V bailout = hn::Set(d, constants.bailout);
    const V two = hn::Set(d, 2);

    QuatV<V> a{hn::LoadU(d, in[0]), hn::LoadU(d, in[1]), hn::LoadU(d, in[2]), hn::LoadU(d, in[3])};
    QuatV<V> b{hn::LoadU(d, in[4]), hn::LoadU(d, in[5]), hn::LoadU(d, in[6]), hn::LoadU(d, in[7])};
    V ra = Norm(a);
    V rb = Norm(b);
    // paper-coupled: the 8-D norm sqrt(ra^2 + rb^2), from the rounded ra and rb as estimate.cpp.
    V r8 = Var == Variant::PaperCoupled ? hn::Sqrt(MulAddT(rb, rb, hn::Mul(ra, ra))) : hn::Zero(d);
    V da = hn::Set(d, 1);  // paper, dual: |da|; paper-coupled: the 8-D dr
    V db = hn::Set(d, 1);
    V trap = ra;

    // Outputs of the lanes that escaped, frozen at their escape iteration.
    auto escaped = hn::Lt(bailout, bailout);  // all false
    V nOut = hn::Zero(d), raOut = nOut, rbOut = nOut, r8Out = nOut, daOut = nOut, dbOut = nOut, trapOut = nOut;
    QuatV<V> bOut{nOut, nOut, nOut, nOut};  // dual: b at escape

    for (int k = 1; k <= constants.iterations; ++k) {
        if constexpr (Var == Variant::Paper) {
            da = hn::Mul(da, hn::Mul(two, ra));
            db = hn::Mul(db, hn::Mul(two, rb));
            a = SquarePlus(d, a, ca);
            b = SquarePlus(d, b, cb);
        } else if constexpr (Var == Variant::PaperCoupled) {
            da = hn::Mul(da, hn::Mul(two, r8));
            a = SquarePlus(d, a, ca);
            b = SquarePlus(d, b, cb);
        } else {
            da = hn::Mul(da, hn::Mul(two, ra));
            const QuatV<V> previous = a;  // b must use the old a
            a = SquarePlus(d, a, ca);
            b = SymmetricPlus(d, previous, b, cb);
        }
        ra = Norm(a);
        if constexpr (Var != Variant::Dual) rb = Norm(b);  // dual: only needed at exit
        trap = StdMin(trap, ra);
        hn::Mask<D> escapes;
        if constexpr (Var == Variant::Paper) {
            escapes = hn::Or(hn::Gt(ra, bailout), hn::Gt(rb, bailout));
        } else if constexpr (Var == Variant::PaperCoupled) {
            r8 = hn::Sqrt(MulAddT(rb, rb, hn::Mul(ra, ra)));
            escapes = hn::Gt(r8, bailout);
        } else {
            escapes = hn::Gt(ra, bailout);
        }
        const auto now = hn::AndNot(escaped, escapes);  // escaping at this iteration
        // Branch-free: which lanes escape is data-dependent, so a branch here would mispredict.
        nOut = hn::IfThenElse(now, hn::Set(d, static_cast<T>(k)), nOut);
        raOut = hn::IfThenElse(now, ra, raOut);
        if constexpr (Var == Variant::Dual) {  // |b| is only needed at exit: keep b itself
            bOut = {hn::IfThenElse(now, b.s, bOut.s), hn::IfThenElse(now, b.i, bOut.i),
                    hn::IfThenElse(now, b.j, bOut.j), hn::IfThenElse(now, b.k, bOut.k)};
        } else {
            rbOut = hn::IfThenElse(now, rb, rbOut);
        }
        r8Out = hn::IfThenElse(now, r8, r8Out);
        daOut = hn::IfThenElse(now, da, daOut);
        dbOut = hn::IfThenElse(now, db, dbOut);
        trapOut = hn::IfThenElse(now, trap, trapOut);
        escaped = hn::Or(escaped, now);
        if (hn::AllTrue(d, escaped)) break;
    }
    if constexpr (Var == Variant::Dual) rbOut = Norm(bOut);
    // Lanes that never escaped report the state after N iterations and DE 0.
    if (!hn::AllTrue(d, escaped)) {
        if constexpr (Var == Variant::Dual) rb = Norm(b);
        raOut = hn::IfThenElse(escaped, raOut, ra);
        rbOut = hn::IfThenElse(escaped, rbOut, rb);
        r8Out = hn::IfThenElse(escaped, r8Out, r8);
        trapOut = hn::IfThenElse(escaped, trapOut, trap);
    }
    // The DE from the frozen values; non-escaped lanes get a harmless argument for the log.
    const V one = hn::Set(d, 1);
    V r, de;
    if constexpr (Var == Variant::Paper) {
        r = StdMax(raOut, rbOut);
        // max, not min: min is 0 wherever one part never escapes and the marcher stalls.
        const auto aOut = hn::And(escaped, hn::Gt(raOut, bailout));
        const auto bOut = hn::And(escaped, hn::Gt(rbOut, bailout));
        const V deA = hn::IfThenElseZero(aOut, PartEstimate(d, hn::IfThenElse(aOut, raOut, two), daOut));
        const V deB = hn::IfThenElseZero(bOut, PartEstimate(d, hn::IfThenElse(bOut, rbOut, two), dbOut));
        de = StdMax(deA, deB);
    } else if constexpr (Var == Variant::PaperCoupled) {
        r = r8Out;
        de = hn::IfThenElseZero(escaped, PartEstimate(d, hn::IfThenElse(escaped, r8Out, two),
                                                      hn::IfThenElse(escaped, daOut, one)));
    } else {
        r = raOut;
        de = hn::IfThenElseZero(escaped, PartEstimate(d, hn::IfThenElse(escaped, raOut, two),
                                                      hn::IfThenElse(escaped, daOut, one)));
    }
    hn::StoreU(nOut, d, out[0]);
    hn::StoreU(r, d, out[1]);
    hn::StoreU(raOut, d, out[2]);
    hn::StoreU(rbOut, d, out[3]);
    hn::StoreU(de, d, out[4]);
    hn::StoreU(trapOut, d, out[5]);
}

/// Runs every full vector in place and the tail through zero-padded local arrays.
template <Variant Var, typename T>
void IterateAll(const Constants<T>& constants, const PointBatch<T>& points, const EscapeBatch<T>& results) {
    const hn::ScalableTag<T> d;
    const std::size_t lanes = hn::Lanes(d);
    constexpr std::size_t kMaxLanes = HWY_MAX_BYTES / sizeof(T);
    // Per vector: the results in T (escape count included), converted to the caller's arrays.
    HWY_ALIGN T buffer[6][kMaxLanes] = {};
    T* out[6] = {buffer[0], buffer[1], buffer[2], buffer[3], buffer[4], buffer[5]};
    const T* in[8];
    HWY_ALIGN T padded[8][kMaxLanes];

    std::size_t first = 0;
    for (; first + lanes <= points.count; first += lanes) {
        // Full vectors: the T results go straight to the caller's arrays, n through the buffer.
        for (int k = 0; k < 8; ++k) in[k] = points.coords[k] + first;
        T* direct[6] = {buffer[0],          results.r + first,  results.ra + first,
                        results.rb + first, results.de + first, results.trap + first};
        IterateVector<Var>(d, constants, in, direct);
        for (std::size_t lane = 0; lane < lanes; ++lane)
            results.n[first + lane] = static_cast<std::int32_t>(buffer[0][lane]);
    }
    if (first < points.count) {
        const std::size_t rest = points.count - first;
        for (int k = 0; k < 8; ++k) {
            std::memset(padded[k], 0, sizeof(padded[k]));
            std::memcpy(padded[k], points.coords[k] + first, rest * sizeof(T));
            in[k] = padded[k];
        }
        IterateVector<Var>(d, constants, in, out);
        for (std::size_t lane = 0; lane < rest; ++lane) {
            results.n[first + lane] = static_cast<std::int32_t>(buffer[0][lane]);
            results.r[first + lane] = buffer[1][lane];
            results.ra[first + lane] = buffer[2][lane];
            results.rb[first + lane] = buffer[3][lane];
            results.de[first + lane] = buffer[4][lane];
            results.trap[first + lane] = buffer[5][lane];
        }
    }
}

template <typename T>
void EvaluateT(const Fractal& fractal, const PointBatch<T>& points, const EscapeBatch<T>& results) {
    Constants<T> constants;
    for (int k = 0; k < 4; ++k) {
        constants.ca[k] = static_cast<T>(component(fractal.c.a, k));
        constants.cb[k] = static_cast<T>(component(fractal.c.b, k));
    }
    constants.bailout = static_cast<T>(fractal.bailout);
    constants.iterations = fractal.iterations;
    switch (fractal.variant) {
        case Variant::Paper: return IterateAll<Variant::Paper>(constants, points, results);
        case Variant::PaperCoupled: return IterateAll<Variant::PaperCoupled>(constants, points, results);
        case Variant::Dual: return IterateAll<Variant::Dual>(constants, points, results);
    }
}

void EvaluateDouble(const Fractal& fractal, const PointBatch<double>& points, const EscapeBatch<double>& results) {
    EvaluateT(fractal, points, results);
}
void EvaluateFloat(const Fractal& fractal, const PointBatch<float>& points, const EscapeBatch<float>& results) {
    EvaluateT(fractal, points, results);
}
std::size_t LanesDouble() { return hn::Lanes(hn::ScalableTag<double>()); }
std::size_t LanesFloat() { return hn::Lanes(hn::ScalableTag<float>()); }

}  // namespace HWY_NAMESPACE
}  // namespace dqj
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace dqj {

HWY_EXPORT(EvaluateDouble);
HWY_EXPORT(EvaluateFloat);
HWY_EXPORT(LanesDouble);
HWY_EXPORT(LanesFloat);

namespace {

/// The index into the HWY_EXPORT tables of one target: the entry HWY_DYNAMIC_DISPATCH would
/// take on a CPU that supported only that target.
std::size_t tableIndex(std::int64_t target) {
    hwy::ChosenTarget chosen;
    chosen.Update(target);
    return chosen.GetIndex();
}

/// The table index for `target` (0 = best), after checking this CPU can run it. The supported
/// set is read once: hwy::SupportedTargets() runs CPUID, which a virtual machine traps (it was
/// 5 % of a 16,384-point call naming its target).
std::size_t checkedIndex(std::int64_t target) {
    static const std::int64_t supported = hwy::SupportedTargets() & HWY_TARGETS;
    if (target == 0) {
        static const std::size_t best = tableIndex(supported);
        return best;
    }
    if ((target & (target - 1)) != 0 || (target & supported) == 0)
        throw std::invalid_argument("evaluateBatch: instruction set " + std::to_string(target) +
                                    " is not compiled in or not supported by this CPU");
    return tableIndex(target);
}

template <typename T>
void checkArrays(const PointBatch<T>& points, const EscapeBatch<T>& out) {
    if (points.count == 0) return;
    for (const T* coordinate : points.coords)
        if (coordinate == nullptr) throw std::invalid_argument("evaluateBatch: a coordinate array is null");
    if (!out.n || !out.r || !out.ra || !out.rb || !out.de || !out.trap)
        throw std::invalid_argument("evaluateBatch: a result array is null");
}

}  // namespace

std::vector<BatchTarget> batchTargets() {
    std::vector<BatchTarget> targets;
    // Highway's target bits are ordered best first from the lowest bit.
    for (std::int64_t remaining = hwy::SupportedTargets() & HWY_TARGETS; remaining != 0; remaining &= remaining - 1) {
        const std::int64_t target = remaining & -remaining;
        targets.push_back({target, hwy::TargetName(target)});
    }
    return targets;
}

BatchTarget bestBatchTarget() { return batchTargets().front(); }

std::size_t batchLanes(bool singlePrecision) {
    const std::size_t index = checkedIndex(0);
    return singlePrecision ? HWY_DISPATCH_TABLE(LanesFloat)[index]() : HWY_DISPATCH_TABLE(LanesDouble)[index]();
}

void evaluateBatch(const Fractal& fractal, const PointBatch<double>& points, const EscapeBatch<double>& out,
                   std::int64_t target) {
    checkArrays(points, out);
    if (points.count == 0) return;
    HWY_DISPATCH_TABLE(EvaluateDouble)[checkedIndex(target)](fractal, points, out);
}

void evaluateBatch(const Fractal& fractal, const PointBatch<float>& points, const EscapeBatch<float>& out,
                   std::int64_t target) {
    checkArrays(points, out);
    if (points.count == 0) return;
    HWY_DISPATCH_TABLE(EvaluateFloat)[checkedIndex(target)](fractal, points, out);
}

}  // namespace dqj
#endif  // HWY_ONCE
