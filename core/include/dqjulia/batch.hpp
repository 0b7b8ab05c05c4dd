// dqjulia/batch.hpp - evaluate many 8-D points at once with SIMD (the vectorised evaluate()).
//
// The escape iteration of estimate.hpp for a structure-of-arrays batch of start points, all
// three variants, on as many points per instruction as the CPU allows. One binary carries
// several instruction sets (Highway's run-time dispatch: AVX-512, AVX2, SSE4, ..., and a
// portable fallback) and picks the best the CPU supports on the first call.
//
// Two precisions:
//  - double: n, r, ra, rb and trap are bit-identical to evaluate() (same operations in the same
//    order, no fused multiply-add); de differs from evaluate() only through the logarithm
//    (Highway's vector log, within 4 ulp) and 1/d (Newton steps from the squared derivative),
//    a relative difference below 1e-14.
//  - float: about twice the points per instruction. Escape counts equal evaluate()'s except
//    where the double orbit passes within float rounding of the bailout at the deciding
//    iteration: the float orbit carries a relative error of about 2^-24 times the derivative
//    |d a_k / d a_0| (floatErrorBound() in tests/core/batch_test.cpp makes this precise), so near
//    the set's surface, where the derivative is large, |a_k| may land on the other side of R.
//    r, ra, rb, de and trap agree to about 1e-6 relative where the counts agree and the
//    derivative is small. The kernel carries the derivative squared, which overflows float
//    beyond about 3e38, a derivative of 1.8e19 (de becomes 0); use double for large N.
// The exit state (Escape::exit) is not computed.
//
// Cost: as evaluate() per point, divided by the lanes per vector (8 doubles or 16 floats with
// AVX-512), plus lanes that idle while the slowest point of their vector is still iterating
// (the orbits still running are packed together every few iterations, so at most a few
// iterations a point) and the packing itself.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "dqjulia/algebra.hpp"
#include "dqjulia/estimate.hpp"
#include "dqjulia/export.h"

namespace dqj {

/// Start points, structure of arrays: coordinate k (0..3 = a's s, i, j, k; 4..7 = b's) of point i
/// is coords[k][i]. `count` points.
template <typename T>
struct PointBatch {
    std::array<const T*, 8> coords{};
    std::size_t count = 0;
};

/// Results, structure of arrays, each array `count` long; the fields of Escape.
template <typename T>
struct EscapeBatch {
    std::int32_t* n = nullptr;
    T* r = nullptr;
    T* ra = nullptr;
    T* rb = nullptr;
    T* de = nullptr;
    T* trap = nullptr;
};

/// An instruction set compiled into the library; `id` is Highway's target bit.
struct BatchTarget {
    std::int64_t id = 0;
    std::string name;  ///< "AVX3" (AVX-512), "AVX2", "SSE4", "EMU128" (portable fallback), ...
};

/// The instruction sets compiled in that this CPU supports, best first. The last is the
/// portable fallback, which every CPU runs.
DQJ_API std::vector<BatchTarget> batchTargets();
/// The instruction set evaluateBatch() uses on this CPU (the first of batchTargets()).
DQJ_API BatchTarget bestBatchTarget();
/// Points per vector for the best target: doubles, or floats if `singlePrecision`.
DQJ_API std::size_t batchLanes(bool singlePrecision);

/// Iterates every point of `points` under `fractal` and writes the results to `out`.
/// `target` 0 = the best one; otherwise the id of one of batchTargets() (for tests and benchmarks).
/// Throws std::invalid_argument for a target this CPU cannot run or a null array.
DQJ_API void evaluateBatch(const Fractal& fractal, const PointBatch<double>& points, const EscapeBatch<double>& out,
                           std::int64_t target = 0);
DQJ_API void evaluateBatch(const Fractal& fractal, const PointBatch<float>& points, const EscapeBatch<float>& out,
                           std::int64_t target = 0);

/// A batch that owns its arrays: add() points, evaluate(), read the results back by index.
/// Reuse one per thread: clear() keeps the memory. The arrays only grow and the batch's length
/// is kept apart, so a batch that grows again after a smaller one (the renderer's rounds) zeroes
/// nothing: entries past the length hold stale values.
template <typename T>
class BatchBuffer {
public:
    std::size_t size() const { return count_; }
    void clear() { count_ = 0; }
    /// Appends a start point; returns its index.
    std::size_t add(const DualQuat& z) {
        if (count_ == start_[0].size()) grow(2 * count_ + 64);
        const Vec8 coordinates = toVec8(z);  // unrolled there: no branch on k per coordinate here
        for (int k = 0; k < 8; ++k) start_[k][count_] = static_cast<T>(coordinates[k]);
        return count_++;
    }
    /// Makes `count` start points, to be written through start(k) (faster than add()); the
    /// first min(count, size()) keep their values, the others are unspecified.
    void resize(std::size_t count) {
        if (count > start_[0].size()) grow(count);
        count_ = count;
    }
    /// Coordinate k (0..3 = a's s, i, j, k; 4..7 = b's) of every start point.
    T* start(int k) { return start_[k].data(); }
    void evaluate(const Fractal& fractal, std::int64_t target = 0) {
        const std::size_t count = size();
        if (n_.size() < count) {
            n_.resize(count);
            for (auto* field : {&r_, &ra_, &rb_, &de_, &trap_}) field->resize(count);
        }
        PointBatch<T> points;
        for (int k = 0; k < 8; ++k) points.coords[k] = start_[k].data();
        points.count = count;
        evaluateBatch(fractal, points,
                      EscapeBatch<T>{n_.data(), r_.data(), ra_.data(), rb_.data(), de_.data(), trap_.data()}, target);
    }
    /// Result `index` of the last evaluate(), as an Escape (exit state left zero).
    Escape escape(std::size_t index) const {
        Escape result;
        result.n = n_[index];
        result.r = r_[index];
        result.ra = ra_[index];
        result.rb = rb_[index];
        result.de = de_[index];
        result.trap = trap_[index];
        return result;
    }
    int n(std::size_t index) const { return n_[index]; }
    T r(std::size_t index) const { return r_[index]; }
    T ra(std::size_t index) const { return ra_[index]; }
    T rb(std::size_t index) const { return rb_[index]; }
    T de(std::size_t index) const { return de_[index]; }
    T trap(std::size_t index) const { return trap_[index]; }

private:
    void grow(std::size_t count) {
        for (auto& coordinate : start_) coordinate.resize(count);
    }

    std::array<std::vector<T>, 8> start_;
    std::vector<std::int32_t> n_;
    std::vector<T> r_, ra_, rb_, de_, trap_;
    std::size_t count_ = 0;
};

}  // namespace dqj
