// The SIMD escape iteration (batch.hpp), compiled once per instruction set by Highway's
// foreach_target.h: this file includes itself once per target, each time inside that target's
// namespace (N_AVX3, N_AVX2, ..., N_EMU128), and HWY_EXPORT builds the table that
// HWY_DYNAMIC_DISPATCH picks from at run time.
//
// Every lane of a vector runs one point. A lane that escapes either stops (AVX-512: its updates
// are masked away) or keeps iterating with the others (its values may overflow to inf or NaN,
// which is harmless) while its outputs are frozen at the iteration it escaped (kOrbitStops).
// A vector runs a segment of a few iterations; the orbits still running after it are packed
// together, so a lane idles behind its vector's slowest point for at most a segment
// (IterateChunk). In double precision the arithmetic repeats estimate.cpp's
// operations in the same order without fused multiply-add (this file is compiled with
// -ffp-contract=off), so results are bit-identical to evaluate() apart from the logarithm in
// the DE. In float, multiply-adds are fused for speed.

// clang-format off
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "kernel/batch.cpp"
#include <hwy/foreach_target.h>  // must come before highway.h
#include <hwy/highway.h>
#include <hwy/contrib/math/math-inl.h>
// clang-format on

#include <algorithm>
#include <bit>
#include <cstring>
#include <limits>
#include <stdexcept>
#include <type_traits>

#include "dqjulia/batch.hpp"

// This pass of the file compiles for AVX-512 (mask registers, compress, scatter): the raw
// intrinsics below are used only then. Redefined, identically, on every pass.
#undef DQJ_AVX512
#define DQJ_AVX512 (HWY_TARGET == HWY_AVX3 || HWY_TARGET == HWY_AVX3_DL)

HWY_BEFORE_NAMESPACE();
namespace dqj {
namespace HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

/// The fractal in the kernel's precision.
template <typename T>
struct Constants {
    T ca[4];
    T cb[4];
    T escapeAbove;  // squaredBailout(R): a squared norm above it has escaped
    int iterations;
};

/// Lanes of the widest vector of T on any target: the size of per-vector local arrays.
template <typename T>
constexpr std::size_t kMaxLanes = HWY_MAX_BYTES / sizeof(T);

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

/// |q|^2 = ((s^2 + i^2) + j^2) + k^2, dot4's order.
template <class V>
HWY_INLINE V SquaredNorm(const QuatV<V>& q) {
    return MulAddT(q.k, q.k, MulAddT(q.j, q.j, MulAddT(q.i, q.i, hn::Mul(q.s, q.s))));
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

/// 1 / sqrt(x) to a few ulps for x in T's normal range (other lanes: unspecified): a first
/// guess within 3.5 % from the exponent halved in integer arithmetic, then Newton steps
/// y (1.5 - x y^2 / 2), each doubling the correct bits (4 in double, 3 in float). Costs a
/// few multiply-adds instead of a square root and a division, the slowest instructions.
template <class D, class V>
HWY_INLINE V ReciprocalSqrt(D d, V x) {
    using T = hn::TFromD<D>;
    const hn::RebindToUnsigned<D> du;
    using U = hn::TFromD<decltype(du)>;
    const U magic = sizeof(T) == 8 ? static_cast<U>(0x5FE6EB50C7B537A9ull) : static_cast<U>(0x5F3759DFu);
    V y = hn::BitCast(d, hn::Sub(hn::Set(du, magic), hn::ShiftRight<1>(hn::BitCast(du, x))));
    const V halfX = hn::Mul(hn::Set(d, 0.5), x);
    const V threeHalves = hn::Set(d, 1.5);
    for (int step = 0; step < (sizeof(T) == 8 ? 4 : 3); ++step)
        y = hn::Mul(y, hn::NegMulAdd(halfX, hn::Mul(y, y), threeHalves));
    return y;
}

/// 0.5 |x| ln|x| / d from the squared derivative d^2; +inf for a zero derivative (estimate.cpp's
/// partEstimate). 1/d by ReciprocalSqrt; lanes whose d^2 is not a normal number (0, inf, NaN,
/// subnormal) take the exact route, a square root and a division, as evaluate() does.
template <class D, class V>
HWY_INLINE V PartEstimate(D d, V norm, V squaredDerivative) {
    using T = hn::TFromD<D>;
    const V numerator = hn::Mul(hn::Mul(hn::Set(d, 0.5), norm), hn::Log(d, norm));
    const V estimate = hn::Mul(numerator, ReciprocalSqrt(d, squaredDerivative));
    const auto normal = hn::And(hn::Ge(squaredDerivative, hn::Set(d, std::numeric_limits<T>::min())),
                                hn::Le(squaredDerivative, hn::Set(d, std::numeric_limits<T>::max())));
    if (HWY_LIKELY(hn::AllTrue(d, normal))) return estimate;
    const V exact =
        hn::IfThenElse(hn::Eq(squaredDerivative, hn::Zero(d)), hn::Set(d, std::numeric_limits<T>::infinity()),
                       hn::Div(numerator, hn::Sqrt(squaredDerivative)));
    return hn::IfThenElse(normal, estimate, exact);
}

/// One vector of orbits between iterations, norms and derivatives squared as in estimate.cpp.
/// Which fields carry over from one iteration to the next depends on the variant (Carried);
/// the others are recomputed every iteration.
template <class V>
struct Orbit {
    QuatV<V> a, b;
    V sa, sb, s8, da, db, trap;
};

template <Variant Var>
struct Carried {
    static constexpr bool sa = Var != Variant::PaperCoupled;  // da's factor (paper, dual)
    static constexpr bool sb = Var == Variant::Paper;         // db's factor
    static constexpr bool s8 = Var == Variant::PaperCoupled;  // the 8-D dr's factor
    static constexpr bool db = Var == Variant::Paper;
};

/// The outputs of a vector's lanes, frozen at the iteration each escaped (squared).
template <class V>
struct Frozen {
    V n, sa, sb, s8, da, db, trap;
    QuatV<V> b;  // dual: b at escape (its norm is taken once, at the end)
};

template <Variant Var, class D, typename T = hn::TFromD<D>>
HWY_INLINE Orbit<hn::Vec<D>> StartOrbit(D d, const T* const* in, std::size_t at) {
    using V = hn::Vec<D>;
    Orbit<V> o;
    o.a = {hn::LoadU(d, in[0] + at), hn::LoadU(d, in[1] + at), hn::LoadU(d, in[2] + at), hn::LoadU(d, in[3] + at)};
    o.b = {hn::LoadU(d, in[4] + at), hn::LoadU(d, in[5] + at), hn::LoadU(d, in[6] + at), hn::LoadU(d, in[7] + at)};
    o.sa = SquaredNorm(o.a);
    o.sb = SquaredNorm(o.b);
    o.s8 = Var == Variant::PaperCoupled ? hn::Add(o.sa, o.sb) : hn::Zero(d);  // the 8-D norm squared
    o.da = hn::Set(d, 1);  // paper, dual: |da|^2; paper-coupled: the 8-D dr^2
    o.db = hn::Set(d, 1);
    o.trap = o.sa;
    return o;
}

/// Where an escaped lane's outputs are kept. With AVX-512's mask registers its orbit stops: its
/// updates are merge-masked away (the mask folds into the instruction that computes the value),
/// so the orbit holds the outputs and only the escape count needs a blend. The mask is then on
/// the chain from one iteration to the next, so two vectors step together, each filling the
/// other's latency (kStepped). Without mask registers a blend is an instruction of its own: the
/// orbit runs on (into inf or NaN, harmlessly), its outputs copied into `Frozen` as it escapes
/// (fewer blends), one vector at a time. On AVX-512 the orbits stop where dqjulia_bench measured
/// it faster: dual, and paper-coupled in float. Paper's orbit carries two vectors more (db and
/// |b|^2), two of them spill out of the 32 registers; paper-coupled in double lost 10 % on the
/// bench's points (bench/README.md, "Stopped orbits").
constexpr bool kMaskRegisters = DQJ_AVX512;
template <Variant Var, typename T>
constexpr bool kOrbitStops = kMaskRegisters &&
                             (Var == Variant::Dual || (Var == Variant::PaperCoupled && sizeof(T) == 4));
/// Vectors of orbits stepped together (Iterate).
template <Variant Var, typename T>
constexpr int kStepped = kOrbitStops<Var, T> ? 2 : 1;

/// `updated` in the lanes still running, `old` in the others when the orbit stops (kOrbitStops).
template <Variant Var, class M, class V>
HWY_INLINE V IfRunning(M running, V updated, V old) {
    if constexpr (kOrbitStops<Var, hn::TFromV<V>>) {
        return hn::IfThenElse(running, updated, old);
    } else {
        return updated;
    }
}
template <Variant Var, class M, class V>
HWY_INLINE QuatV<V> IfRunning(M running, const QuatV<V>& updated, const QuatV<V>& old) {
    return {IfRunning<Var>(running, updated.s, old.s), IfRunning<Var>(running, updated.i, old.i),
            IfRunning<Var>(running, updated.j, old.j), IfRunning<Var>(running, updated.k, old.k)};
}

/// The fractal's constants as vectors.
template <class V>
struct ConstantsV {
    V ca[4], cb[4], escapeAbove, four;
};

/// Iteration k of one vector of orbits. Lanes that escape join `escaped`, with k in `frozen.n`;
/// lanes already in it (escaped, or holding no orbit) are left alone. Their other outputs are in
/// the orbit (kOrbitStops: it stopped) or in `frozen` (the orbit runs on).
template <Variant Var, class D, typename T = hn::TFromD<D>>
HWY_INLINE void Step(D d, const ConstantsV<hn::Vec<D>>& c, int k, Orbit<hn::Vec<D>>& o, hn::Mask<D>& escaped,
                     Frozen<hn::Vec<D>>& frozen) {
    using V = hn::Vec<D>;
    const auto running = hn::Not(escaped);
    // Norms, the 8-D sum and the trap need no mask: from a stopped orbit they come out unchanged
    // (the same operations on the same values; trap <= |a|^2 already).
    if constexpr (Var == Variant::Paper) {
        o.da = IfRunning<Var>(running, hn::Mul(o.da, hn::Mul(c.four, o.sa)), o.da);
        o.db = IfRunning<Var>(running, hn::Mul(o.db, hn::Mul(c.four, o.sb)), o.db);
        o.a = IfRunning<Var>(running, SquarePlus(d, o.a, c.ca), o.a);
        o.b = IfRunning<Var>(running, SquarePlus(d, o.b, c.cb), o.b);
    } else if constexpr (Var == Variant::PaperCoupled) {
        o.da = IfRunning<Var>(running, hn::Mul(o.da, hn::Mul(c.four, o.s8)), o.da);
        o.a = IfRunning<Var>(running, SquarePlus(d, o.a, c.ca), o.a);
        o.b = IfRunning<Var>(running, SquarePlus(d, o.b, c.cb), o.b);
    } else {
        o.da = IfRunning<Var>(running, hn::Mul(o.da, hn::Mul(c.four, o.sa)), o.da);
        const QuatV<V> previous = o.a;  // b must use the old a
        o.a = IfRunning<Var>(running, SquarePlus(d, o.a, c.ca), o.a);
        o.b = IfRunning<Var>(running, SymmetricPlus(d, previous, o.b, c.cb), o.b);
    }
    o.sa = SquaredNorm(o.a);
    if constexpr (Var != Variant::Dual) o.sb = SquaredNorm(o.b);  // dual: only needed at exit
    o.trap = StdMin(o.trap, o.sa);
    hn::Mask<D> escapes;
    if constexpr (Var == Variant::Paper) {
        escapes = hn::Or(hn::Gt(o.sa, c.escapeAbove), hn::Gt(o.sb, c.escapeAbove));
    } else if constexpr (Var == Variant::PaperCoupled) {
        o.s8 = hn::Add(o.sa, o.sb);
        escapes = hn::Gt(o.s8, c.escapeAbove);
    } else {
        escapes = hn::Gt(o.sa, c.escapeAbove);
    }
    const auto now = hn::AndNot(escaped, escapes);  // escaping at this iteration
    // Branch-free: which lanes escape is data-dependent, so a branch here would mispredict.
    frozen.n = hn::IfThenElse(now, hn::Set(d, static_cast<T>(k)), frozen.n);
    if constexpr (!kOrbitStops<Var, T>) {
        frozen.sa = hn::IfThenElse(now, o.sa, frozen.sa);
        if constexpr (Var == Variant::Dual) {  // |b| is only needed at exit: keep b itself
            frozen.b = {hn::IfThenElse(now, o.b.s, frozen.b.s), hn::IfThenElse(now, o.b.i, frozen.b.i),
                        hn::IfThenElse(now, o.b.j, frozen.b.j), hn::IfThenElse(now, o.b.k, frozen.b.k)};
        } else {
            frozen.sb = hn::IfThenElse(now, o.sb, frozen.sb);
        }
        if constexpr (Var == Variant::PaperCoupled) frozen.s8 = hn::IfThenElse(now, o.s8, frozen.s8);
        frozen.da = hn::IfThenElse(now, o.da, frozen.da);
        if constexpr (Var == Variant::Paper) frozen.db = hn::IfThenElse(now, o.db, frozen.db);
        frozen.trap = hn::IfThenElse(now, o.trap, frozen.trap);
    }
    escaped = hn::Or(escaped, now);
}

/// Iterations from + 1 .. to of K vectors of orbits, stepped together so that one's chain of
/// dependent operations fills the other's latency. Stops early once every lane has escaped.
template <int K, Variant Var, class D, typename T = hn::TFromD<D>>
HWY_INLINE void Iterate(D d, const Constants<T>& constants, Orbit<hn::Vec<D>> (&o)[K], int from, int to,
                        hn::Mask<D> (&escaped)[K], Frozen<hn::Vec<D>> (&frozen)[K]) {
    ConstantsV<hn::Vec<D>> c;
    for (int k = 0; k < 4; ++k) {
        c.ca[k] = hn::Set(d, constants.ca[k]);
        c.cb[k] = hn::Set(d, constants.cb[k]);
    }
    c.escapeAbove = hn::Set(d, constants.escapeAbove);
    c.four = hn::Set(d, 4);
    for (int k = from + 1; k <= to; ++k) {
        bool done = true;
        for (int v = 0; v < K; ++v) {
            Step<Var>(d, c, k, o[v], escaped[v], frozen[v]);
            done = done && hn::AllTrue(d, escaped[v]);
        }
        if (done) break;
    }
}

/// Lanes that never escaped after N iterations: their outputs are the final state (DE 0).
template <Variant Var, class D>
HWY_INLINE void FreezeUnescaped(D /* tag */, hn::Mask<D> unescaped, const Orbit<hn::Vec<D>>& o,
                                Frozen<hn::Vec<D>>& frozen) {
    frozen.sa = hn::IfThenElse(unescaped, o.sa, frozen.sa);
    frozen.sb = hn::IfThenElse(unescaped, Var == Variant::Dual ? SquaredNorm(o.b) : o.sb, frozen.sb);
    frozen.s8 = hn::IfThenElse(unescaped, o.s8, frozen.s8);
    frozen.trap = hn::IfThenElse(unescaped, o.trap, frozen.trap);
}

/// Orbits between segments: the carried fields of the live orbits, packed from index 0, and
/// each orbit's point index within the chunk (exact in T: a chunk is at most kChunk points).
template <typename T>
struct OrbitStore {
    enum Field { kA = 0, kB = 4, kSa = 8, kSb, kS8, kDa, kDb, kTrap, kIndex, kFields };
    T* field[kFields];
};

/// Points a chunk of the batch holds. Its store (about 36 KB in double) lives on the stack: a
/// buffer kept per thread would be freed too early by MinGW's emulated TLS (thread_scratch.hpp).
constexpr std::size_t kChunk = 256;
/// Iterations a segment runs before the orbits still running are packed together.
constexpr int kSegment = 4;
/// Orbits below which packing stops (the rest run to N): vectors' worth.
constexpr std::size_t kPackMinimum = 2;

/// Zeroes the vector after the `kept` packed orbits, so that the lanes past them in the last
/// vector the next segment loads are defined (they hold no orbit and count as escaped).
template <class D, typename T = hn::TFromD<D>>
HWY_INLINE void ClearAfter(D d, const OrbitStore<T>& store, std::size_t kept) {
    for (T* field : store.field) hn::StoreU(hn::Zero(d), d, field + kept);
}

template <Variant Var, class D, typename T = hn::TFromD<D>>
HWY_INLINE Orbit<hn::Vec<D>> LoadOrbit(D d, const OrbitStore<T>& store, std::size_t at) {
    using S = OrbitStore<T>;
    T* const* f = store.field;
    Orbit<hn::Vec<D>> o;
    o.a = {hn::LoadU(d, f[S::kA] + at), hn::LoadU(d, f[S::kA + 1] + at), hn::LoadU(d, f[S::kA + 2] + at),
           hn::LoadU(d, f[S::kA + 3] + at)};
    o.b = {hn::LoadU(d, f[S::kB] + at), hn::LoadU(d, f[S::kB + 1] + at), hn::LoadU(d, f[S::kB + 2] + at),
           hn::LoadU(d, f[S::kB + 3] + at)};
    const auto zero = hn::Zero(d);
    o.sa = Carried<Var>::sa ? hn::LoadU(d, f[S::kSa] + at) : zero;
    o.sb = Carried<Var>::sb ? hn::LoadU(d, f[S::kSb] + at) : zero;
    o.s8 = Carried<Var>::s8 ? hn::LoadU(d, f[S::kS8] + at) : zero;
    o.db = Carried<Var>::db ? hn::LoadU(d, f[S::kDb] + at) : zero;
    o.da = hn::LoadU(d, f[S::kDa] + at);
    o.trap = hn::LoadU(d, f[S::kTrap] + at);
    return o;
}

/// CompressStore through a register and a full store (the store has a vector's room past the
/// packed lanes): the memory form of vcompressps/pd is slow on AMD Zen 4 (it made the packing
/// kernel 2-3 times slower than none), and Highway 1.0.3's Compress of 64-bit lanes on AVX-512
/// goes through a lookup table instead of vcompresspd.
template <class D, typename T = hn::TFromD<D>>
HWY_INLINE void PackStore(D d, hn::Vec<D> v, hn::Mask<D> mask, T* to) {
#if DQJ_AVX512
    if constexpr (sizeof(T) == 8 && hn::MaxLanes(d) == 8) {
        hn::StoreU(hn::Vec<D>{_mm512_maskz_compress_pd(mask.raw, v.raw)}, d, to);
    } else {
        hn::StoreU(hn::Compress(v, mask), d, to);
    }
#else
    hn::CompressStore(v, mask, d, to);
#endif
}

/// Packs the `running` lanes' orbits and indices into the store from `to` on; returns how many.
/// `to` is at most the index the vector was loaded from, so packing in place is safe.
template <Variant Var, class D, typename T = hn::TFromD<D>>
HWY_INLINE std::size_t KeepOrbits(D d, const Orbit<hn::Vec<D>>& o, hn::Vec<D> index, hn::Mask<D> running,
                                  const OrbitStore<T>& store, std::size_t to) {
    using S = OrbitStore<T>;
    T* const* f = store.field;
    const hn::Vec<D> parts[8] = {o.a.s, o.a.i, o.a.j, o.a.k, o.b.s, o.b.i, o.b.j, o.b.k};
    for (int k = 0; k < 8; ++k) PackStore(d, parts[k], running, f[S::kA + k] + to);
    if constexpr (Carried<Var>::sa) PackStore(d, o.sa, running, f[S::kSa] + to);
    if constexpr (Carried<Var>::sb) PackStore(d, o.sb, running, f[S::kSb] + to);
    if constexpr (Carried<Var>::s8) PackStore(d, o.s8, running, f[S::kS8] + to);
    if constexpr (Carried<Var>::db) PackStore(d, o.db, running, f[S::kDb] + to);
    PackStore(d, o.da, running, f[S::kDa] + to);
    PackStore(d, o.trap, running, f[S::kTrap] + to);
    PackStore(d, index, running, f[S::kIndex] + to);
    return hn::CountTrue(d, running);
}

/// What a finished lane leaves in the result arrays until FinishEstimates: n final; ra, rb and
/// trap squared; r holds the paper's db or paper-coupled's 8-D norm squared, de the derivative
/// squared.
template <Variant Var, class V>
HWY_INLINE V PendingR(const Frozen<V>& f) {
    return Var == Variant::Paper ? f.db : f.s8;
}

/// Every lane's outputs to entries at .. at + lanes - 1 (a full vector of the chunk's first
/// segment; lanes still running are written again when they finish).
template <Variant Var, class D, typename T = hn::TFromD<D>>
HWY_INLINE void WriteAll(D d, const Frozen<hn::Vec<D>>& f, const EscapeBatch<T>& out, std::size_t at) {
    if constexpr (sizeof(T) == 4) {
        const hn::RebindToSigned<D> di;
        hn::StoreU(hn::ConvertTo(di, f.n), di, out.n + at);
    } else {
        const hn::Rebind<std::int32_t, D> di;
        hn::StoreU(hn::DemoteTo(di, f.n), di, out.n + at);
    }
    hn::StoreU(PendingR<Var>(f), d, out.r + at);
    hn::StoreU(f.sa, d, out.ra + at);
    hn::StoreU(f.sb, d, out.rb + at);
    hn::StoreU(f.da, d, out.de + at);
    hn::StoreU(f.trap, d, out.trap + at);
}

#if DQJ_AVX512
// AVX-512's masked scatters by element type: base[at[i]] = v[i] in the lanes of m.
HWY_INLINE __m512i Int32(__m512 v) { return _mm512_cvttps_epi32(v); }
HWY_INLINE __m256i Int32(__m512d v) { return _mm512_cvttpd_epi32(v); }
HWY_INLINE void Scatter(std::int32_t* base, __mmask16 m, __m512i at, __m512i v) {
    _mm512_mask_i32scatter_epi32(base, m, at, v, 4);
}
HWY_INLINE void Scatter(std::int32_t* base, __mmask8 m, __m256i at, __m256i v) {
    _mm256_mask_i32scatter_epi32(base, m, at, v, 4);
}
HWY_INLINE void Scatter(float* base, __mmask16 m, __m512i at, __m512 v) {
    _mm512_mask_i32scatter_ps(base, m, at, v, 4);
}
HWY_INLINE void Scatter(double* base, __mmask8 m, __m256i at, __m512d v) {
    _mm512_mask_i32scatter_pd(base, m, at, v, 8);
}
#endif

/// The `finished` lanes' outputs to the entries their indices name.
template <Variant Var, class D, typename T = hn::TFromD<D>>
HWY_INLINE void WriteFinished(D d, const Frozen<hn::Vec<D>>& f, hn::Mask<D> finished, hn::Vec<D> index,
                              const EscapeBatch<T>& out) {
#if DQJ_AVX512
    if constexpr (hn::MaxLanes(d) * sizeof(T) == 64) {  // masked scatters: no branch a lane
        const auto at = Int32(index.raw);
        Scatter(out.n, finished.raw, at, Int32(f.n.raw));
        Scatter(out.r, finished.raw, at, PendingR<Var>(f).raw);
        Scatter(out.ra, finished.raw, at, f.sa.raw);
        Scatter(out.rb, finished.raw, at, f.sb.raw);
        Scatter(out.de, finished.raw, at, f.da.raw);
        Scatter(out.trap, finished.raw, at, f.trap.raw);
        return;
    }
#endif
    HWY_ALIGN T values[7][kMaxLanes<T>];
    const hn::Vec<D> fields[7] = {index, f.n, PendingR<Var>(f), f.sa, f.sb, f.da, f.trap};
    for (int k = 0; k < 7; ++k) hn::Store(fields[k], d, values[k]);
    static_assert(kMaxLanes<T> <= 64, "a vector's mask bits fit 64 bits");
    std::uint8_t bytes[8] = {};
    hn::StoreMaskBits(d, finished, bytes);
    std::uint64_t bits;
    std::memcpy(&bits, bytes, sizeof(bits));
    for (; bits != 0; bits &= bits - 1) {  // the finished lanes only: no branch a lane
        const auto lane = static_cast<std::size_t>(std::countr_zero(bits));
        const auto i = static_cast<std::size_t>(values[0][lane]);
        out.n[i] = static_cast<std::int32_t>(values[1][lane]);
        out.r[i] = values[2][lane];
        out.ra[i] = values[3][lane];
        out.rb[i] = values[4][lane];
        out.de[i] = values[5][lane];
        out.trap[i] = values[6][lane];
    }
}

/// The square roots, r and the DE of one vector from the pending results (PendingR): n, r, ra,
/// rb, de and trap at index 0.
template <Variant Var, class D, typename T = hn::TFromD<D>>
HWY_INLINE void FinishVector(D d, const Constants<T>& constants, const std::int32_t* n, T* r, T* ra, T* rb, T* de,
                             T* trap) {
    using V = hn::Vec<D>;
    V count;
    if constexpr (sizeof(T) == 4) {
        count = hn::ConvertTo(d, hn::LoadU(hn::RebindToSigned<D>(), n));
    } else {
        count = hn::PromoteTo(d, hn::LoadU(hn::Rebind<std::int32_t, D>(), n));
    }
    const auto escaped = hn::Gt(count, hn::Zero(d));
    const V escapeAbove = hn::Set(d, constants.escapeAbove);
    const V one = hn::Set(d, 1);
    const V two = hn::Set(d, 2);
    const V saOut = hn::LoadU(d, ra);
    const V raOut = hn::Sqrt(saOut);
    const V sbOut = hn::LoadU(d, rb);
    const V rbOut = hn::Sqrt(sbOut);
    const V pending = hn::LoadU(d, r);
    const V daOut = hn::LoadU(d, de);  // squared
    // Non-escaped lanes get a harmless argument for the log.
    V radius, estimate;
    if constexpr (Var == Variant::Paper) {
        radius = StdMax(raOut, rbOut);
        // max, not min: min is 0 wherever one part never escapes and the marcher stalls.
        const auto aOut = hn::And(escaped, hn::Gt(saOut, escapeAbove));
        const auto bOut = hn::And(escaped, hn::Gt(sbOut, escapeAbove));
        // max(deA, deB) with deX = 0 for a part that did not escape, in one logarithm where a
        // lane's parts did not both escape (nearly all): that part's estimate, the a part's
        // as it is and the b part's as max(0, deB), StdMax's value for a NaN too. Lanes where
        // both escaped take the second logarithm.
        const V single = PartEstimate(d, hn::IfThenElse(aOut, raOut, hn::IfThenElse(bOut, rbOut, two)),
                                      hn::IfThenElse(aOut, daOut, hn::IfThenElse(bOut, pending, one)));
        estimate = hn::IfThenElse(aOut, single, hn::IfThenElseZero(bOut, StdMax(hn::Zero(d), single)));
        const auto both = hn::And(aOut, bOut);
        if (HWY_UNLIKELY(!hn::AllFalse(d, both))) {
            const V deB = PartEstimate(d, hn::IfThenElse(both, rbOut, two), hn::IfThenElse(both, pending, one));
            estimate = hn::IfThenElse(both, StdMax(estimate, deB), estimate);
        }
    } else {
        radius = Var == Variant::PaperCoupled ? hn::Sqrt(pending) : raOut;
        estimate = hn::IfThenElseZero(escaped, PartEstimate(d, hn::IfThenElse(escaped, radius, two),
                                                            hn::IfThenElse(escaped, daOut, one)));
    }
    hn::StoreU(radius, d, r);
    hn::StoreU(raOut, d, ra);
    hn::StoreU(rbOut, d, rb);
    hn::StoreU(estimate, d, de);
    hn::StoreU(hn::Sqrt(hn::LoadU(d, trap)), d, trap);
}

/// r, the DE and the square roots of every point of a chunk, once all have finished.
template <Variant Var, class D, typename T = hn::TFromD<D>>
HWY_INLINE void FinishEstimates(D d, const Constants<T>& constants, const EscapeBatch<T>& out, std::size_t count) {
    const std::size_t lanes = hn::Lanes(d);
    std::size_t at = 0;
    for (; at + lanes <= count; at += lanes)
        FinishVector<Var>(d, constants, out.n + at, out.r + at, out.ra + at, out.rb + at, out.de + at, out.trap + at);
    if (at == count) return;
    const std::size_t rest = count - at;
    std::int32_t n[kMaxLanes<T>] = {};
    std::memcpy(n, out.n + at, rest * sizeof(std::int32_t));
    HWY_ALIGN T tail[5][kMaxLanes<T>] = {};
    T* const fields[5] = {out.r + at, out.ra + at, out.rb + at, out.de + at, out.trap + at};
    for (int k = 0; k < 5; ++k) std::memcpy(tail[k], fields[k], rest * sizeof(T));
    FinishVector<Var>(d, constants, n, tail[0], tail[1], tail[2], tail[3], tail[4]);
    for (int k = 0; k < 5; ++k) std::memcpy(fields[k], tail[k], rest * sizeof(T));
}

/// One chunk of at most kChunk points. Every vector runs a segment of kSegment iterations
/// from its start points; the orbits still running then are packed into the store, whose
/// vectors run the next segment, and so on until N, so lanes do not idle behind a vector's
/// slowest point for more than a segment. A vector whose lanes are mostly still running goes on
/// to N instead, and below kPackMinimum vectors' worth of orbits (or with fewer than 4 lanes)
/// the rest run to N in one segment. Each point's operations are those of evaluate(), in its
/// order, so packing changes no result.
template <Variant Var, class D, typename T = hn::TFromD<D>>
HWY_INLINE void IterateChunk(D d, const Constants<T>& constants, const T* const* in, const EscapeBatch<T>& out,
                             std::size_t count, const OrbitStore<T>& store) {
    using V = hn::Vec<D>;
    const std::size_t lanes = hn::Lanes(d);
    const int iterations = constants.iterations;
    auto segmentEnd = [&](int from, std::size_t orbits) {
        return orbits > kPackMinimum * lanes && lanes >= 4 ? std::min(iterations, from + kSegment) : iterations;
    };
    // Runs K vectors (vector v at point `at` + v lanes, `live[v]` lanes holding orbits) to `to`,
    // or on to N if most of their lanes are still running then (packing them would cost more
    // than their idle neighbours); returns the orbits packed. Inlined: as a call, the orbit went
    // through memory and the kernel was slower than without packing.
    auto run = [&]<int K>(Orbit<V>(&o)[K], const V(&index)[K], const std::size_t(&live)[K], int from, int to,
                          std::size_t kept, bool direct, std::size_t at) __attribute__((always_inline)) {
        hn::Mask<D> liveLanes[K], escaped[K];
        Frozen<V> frozen[K];
        std::size_t running = 0;
        for (int v = 0; v < K; ++v) {
            liveLanes[v] = hn::FirstN(d, live[v]);
            escaped[v] = hn::Not(liveLanes[v]);
            const V zero = hn::Zero(d);
            frozen[v] = {zero, zero, zero, zero, zero, zero, zero, {zero, zero, zero, zero}};
        }
        Iterate<K, Var>(d, constants, o, from, to, escaped, frozen);
        for (int v = 0; v < K; ++v) running += hn::CountTrue(d, hn::Not(escaped[v]));
        if (to < iterations && 2 * running > K * lanes) {
            Iterate<K, Var>(d, constants, o, to, iterations, escaped, frozen);
            to = iterations;
        }
        std::size_t packed = 0;
        for (int v = 0; v < K; ++v) {
            auto stillRunning = hn::AndNot(escaped[v], liveLanes[v]);
            auto finished = hn::And(escaped[v], liveLanes[v]);
            if constexpr (kOrbitStops<Var, T>) {  // the outputs are the orbit's, escaped or not
                frozen[v].sa = o[v].sa;
                frozen[v].sb = Var == Variant::Dual ? SquaredNorm(o[v].b) : o[v].sb;
                frozen[v].s8 = o[v].s8;
                frozen[v].da = o[v].da;
                frozen[v].db = o[v].db;
                frozen[v].trap = o[v].trap;
            } else if constexpr (Var == Variant::Dual) {
                frozen[v].sb = SquaredNorm(frozen[v].b);
            }
            if (to == iterations) {
                if constexpr (!kOrbitStops<Var, T>) FreezeUnescaped<Var>(d, stillRunning, o[v], frozen[v]);
                finished = liveLanes[v];
                stillRunning = hn::AndNot(liveLanes[v], liveLanes[v]);
            }
            if (direct) {
                WriteAll<Var>(d, frozen[v], out, at + v * lanes);
            } else {
                WriteFinished<Var>(d, frozen[v], finished, index[v], out);
            }
            if (!hn::AllFalse(d, stillRunning))
                packed += KeepOrbits<Var>(d, o[v], index[v], stillRunning, store, kept + packed);
        }
        return packed;
    };

    int to = segmentEnd(0, count);
    std::size_t kept = 0;
    std::size_t at = 0;
    for (; at + kStepped<Var, T> * lanes <= count; at += kStepped<Var, T> * lanes) {
        Orbit<V> o[kStepped<Var, T>];
        V index[kStepped<Var, T>];
        std::size_t live[kStepped<Var, T>];
        for (int v = 0; v < kStepped<Var, T>; ++v) {
            o[v] = StartOrbit<Var>(d, in, at + v * lanes);
            index[v] = hn::Iota(d, static_cast<T>(at + v * lanes));
            live[v] = lanes;
        }
        kept += run(o, index, live, 0, to, kept, true, at);
    }
    for (; at < count; at += lanes) {
        Orbit<V> o[1];
        const V index[1] = {hn::Iota(d, static_cast<T>(at))};
        if (at + lanes <= count) {
            o[0] = StartOrbit<Var>(d, in, at);
            kept += run(o, index, {lanes}, 0, to, kept, true, at);
        } else {  // the tail, through zero-padded copies
            HWY_ALIGN T padded[8][kMaxLanes<T>] = {};
            const T* start[8];
            for (int k = 0; k < 8; ++k) {
                std::memcpy(padded[k], in[k] + at, (count - at) * sizeof(T));
                start[k] = padded[k];
            }
            o[0] = StartOrbit<Var>(d, start, 0);
            kept += run(o, index, {count - at}, 0, to, kept, false, at);
        }
    }
    for (int from = to; kept > 0; from = to) {
        ClearAfter(d, store, kept);
        const std::size_t orbits = kept;
        to = segmentEnd(from, orbits);
        kept = 0;
        std::size_t next = 0;
        for (; next + kStepped<Var, T> * lanes <= orbits; next += kStepped<Var, T> * lanes) {
            Orbit<V> o[kStepped<Var, T>];
            V index[kStepped<Var, T>];
            std::size_t live[kStepped<Var, T>];
            for (int v = 0; v < kStepped<Var, T>; ++v) {
                o[v] = LoadOrbit<Var>(d, store, next + v * lanes);
                index[v] = hn::LoadU(d, store.field[OrbitStore<T>::kIndex] + next + v * lanes);
                live[v] = lanes;
            }
            kept += run(o, index, live, from, to, kept, false, next);
        }
        for (; next < orbits; next += lanes) {
            Orbit<V> o[1] = {LoadOrbit<Var>(d, store, next)};
            const V index[1] = {hn::LoadU(d, store.field[OrbitStore<T>::kIndex] + next)};
            kept += run(o, index, {std::min(lanes, orbits - next)}, from, to, kept, false, next);
        }
    }
    FinishEstimates<Var>(d, constants, out, count);
}

template <Variant Var, typename T>
void IterateAll(const Constants<T>& constants, const PointBatch<T>& points, const EscapeBatch<T>& results) {
    const hn::ScalableTag<T> d;
    HWY_ALIGN T storage[OrbitStore<T>::kFields][kChunk + kMaxLanes<T>];  // a vector's room past the packed orbits
    OrbitStore<T> store;
    for (int f = 0; f < OrbitStore<T>::kFields; ++f) store.field[f] = storage[f];
    for (std::size_t base = 0; base < points.count; base += kChunk) {
        const T* in[8];
        for (int k = 0; k < 8; ++k) in[k] = points.coords[k] + base;
        const EscapeBatch<T> out{results.n + base,  results.r + base,  results.ra + base,
                                 results.rb + base, results.de + base, results.trap + base};
        IterateChunk<Var>(d, constants, in, out, std::min(kChunk, points.count - base), store);
    }
}

template <typename T>
void EvaluateT(const Fractal& fractal, const PointBatch<T>& points, const EscapeBatch<T>& results) {
    Constants<T> constants;
    for (int k = 0; k < 4; ++k) {
        constants.ca[k] = static_cast<T>(component(fractal.c.a, k));
        constants.cb[k] = static_cast<T>(component(fractal.c.b, k));
    }
    constants.escapeAbove = squaredBailout<T>(fractal.bailout);
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
