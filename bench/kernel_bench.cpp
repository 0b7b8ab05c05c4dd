// dqjulia_bench - distance-estimate evaluations per second: the scalar reference evaluate()
// against the SIMD batch kernel (batch.hpp) in double and float, on the dispatched instruction
// set and the portable fallback, for the three variants; then the same-run ratios and the
// fraction of this core's peak floating-point rate. Single thread.
//
// Workload: 16384 points uniform in the bounding sphere of the default slice (a.s, a.i, a.j) of
// the default constant c = (-0.39054, -0.58679, 0, 0)(0, 0.5632, 0, 0.05), N = 12, R = 4: what
// the renderer and the bake ask for (one point in seven is inside; 4.6 iterations a point).
// The loop workload (simd_*_loop) keeps every lane busy: the bench points whose orbits stay
// bounded for kLoopIterations = 48, repeated to 16384, at N = 48, so nearly all of the time is
// the iteration loop and the share of peak is the loop's own.
//
// Flops: counted per iteration from batch.cpp's Iterate (a multiply, an add and a min count 1,
// a multiply-add 2 whether fused (float) or not (double), a comparison or a blend 0): a
// quaternion square plus c is 15, the symmetric product plus c 24, a squared norm 7, a
// derivative update 2, so paper 49 (2 squares, 2 norms, 2 updates, the min), paper-coupled 48
// (2 squares, 2 norms, 1 update, the 8-D sum, the min) and dual 49 (a square, a symmetric
// product, 1 norm, 1 update, the min) (kFlopsPerIteration; bench/README.md's table), times the
// iterations each point needs (its escape count, or N). The work once a point (its square
// roots, a logarithm and a division) is not counted; nor are lanes that idle while their
// vector's slowest point iterates.
//
// Peak: fused multiply-adds a second measured on this core (measuredFmaRate: independent FMAs
// of the dispatched width, so the clock it runs at, turbo included, and the FMA units it has
// are both in the figure) x lanes x 2 flops. Where that cannot be measured (not x86-64),
// lanes x 2 FMA units x 2 flops x the first "cpu MHz" of /proc/cpuinfo.
//
// Run: build-bench/bin/dqjulia_bench (bench/run.sh builds it)  (Google Benchmark flags work, e.g. --benchmark_filter=dual)
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

#include "dqjulia/batch.hpp"
#include "dqjulia/estimate.hpp"
#include "dqjulia/render.hpp"
#include "dqjulia/slice.hpp"
#include "variations_bench.hpp"

using namespace dqj;

namespace {

constexpr Variant kVariants[] = {Variant::Paper, Variant::PaperCoupled, Variant::Dual};
constexpr double kFlopsPerIteration[] = {49.0, 48.0, 49.0};  // paper, paper-coupled, dual
constexpr std::size_t kPoints = 16384;

constexpr int kLoopIterations = 48;

/// The two workloads: the bench points (uniform in the ball) at N = 12, and the loop's.
enum class Workload { Ball, Loop };

Fractal benchFractal(Variant variant, Workload workload = Workload::Ball) {
    Fractal fractal;  // the default constant
    fractal.variant = variant;
    fractal.iterations = workload == Workload::Loop ? kLoopIterations : 12;
    fractal.bailout = 4.0;
    return fractal;
}

std::vector<DualQuat> benchPoints() {
    const Fractal fractal = benchFractal(Variant::Paper);
    const Slice slice = sliceFromAxisNames("a.s,a.i,a.j");
    const Bounds bounds = containingBounds(fractal, slice).value_or(Bounds{});
    std::vector<DualQuat> points;
    if (std::getenv("DQJ_BENCH_GRID")) {
        const int side = 26;  // 26^3 > 16384
        for (int z = 0; z < side && points.size() < kPoints; ++z)
            for (int y = 0; y < side && points.size() < kPoints; ++y)
                for (int x = 0; x < side && points.size() < kPoints; ++x) {
                    const glm::dvec3 p = (glm::dvec3(x, y, z) + 0.5) / double(side) * 2.0 - 1.0;
                    points.push_back(slice.map(bounds.center + bounds.radius * p));
                }
        return points;
    }
    std::mt19937_64 random(7);
    std::uniform_real_distribution<double> uniform(-1.0, 1.0);
    while (points.size() < kPoints) {
        const glm::dvec3 p(uniform(random), uniform(random), uniform(random));
        if (p.x * p.x + p.y * p.y + p.z * p.z <= 1.0) points.push_back(slice.map(bounds.center + bounds.radius * p));
    }
    return points;
}

/// The bench points that stay bounded for kLoopIterations in every variant, repeated to kPoints.
std::vector<DualQuat> loopPoints(const std::vector<DualQuat>& ball) {
    std::vector<DualQuat> bounded;
    for (const DualQuat& z : ball) {
        bool inside = true;
        for (const Variant variant : kVariants)
            inside = inside && evaluate(benchFractal(variant, Workload::Loop), z).n == 0;
        if (inside) bounded.push_back(z);
    }
    if (bounded.empty()) throw std::runtime_error("dqjulia_bench: no bench point stays bounded");
    std::vector<DualQuat> points;
    while (points.size() < kPoints) points.push_back(bounded[points.size() % bounded.size()]);
    return points;
}

const std::vector<DualQuat>& points(Workload workload = Workload::Ball) {
    static const std::vector<DualQuat> ball = benchPoints();
    static const std::vector<DualQuat> loop = loopPoints(ball);
    return workload == Workload::Loop ? loop : ball;
}

/// Useful iterations over the workload (escape count, or N for points inside), by evaluate().
double iterationsOf(const Fractal& fractal, Workload workload) {
    double total = 0.0;
    for (const DualQuat& z : points(workload)) {
        const int n = evaluate(fractal, z).n;
        total += n ? n : fractal.iterations;
    }
    return total;
}

/// Points a second, and flops a second from the useful iterations of one pass over the points.
void setCounters(benchmark::State& state, Variant variant, double iterationsPerPass) {
    const double evaluations = static_cast<double>(state.iterations()) * kPoints;
    state.SetItemsProcessed(static_cast<std::int64_t>(evaluations));
    state.counters["flops"] = benchmark::Counter(static_cast<double>(state.iterations()) * iterationsPerPass *
                                                     kFlopsPerIteration[static_cast<int>(variant)],
                                                 benchmark::Counter::kIsRate);
}

void scalarReference(benchmark::State& state, Variant variant) {
    const Fractal fractal = benchFractal(variant);
    for (auto _ : state) {
        for (const DualQuat& z : points()) benchmark::DoNotOptimize(evaluate(fractal, z).de);
    }
    static std::map<Variant, double> iterations;
    if (!iterations.count(variant)) iterations[variant] = iterationsOf(fractal, Workload::Ball);
    setCounters(state, variant, iterations[variant]);
}

template <typename T>
void simdBatch(benchmark::State& state, Variant variant, std::int64_t target, Workload workload) {
    const Fractal fractal = benchFractal(variant, workload);
    std::vector<T> coords[8];
    for (int k = 0; k < 8; ++k)
        for (const DualQuat& z : points(workload)) coords[k].push_back(static_cast<T>(component(z, k)));
    std::vector<std::int32_t> n(kPoints);
    std::vector<T> r(kPoints), ra(kPoints), rb(kPoints), de(kPoints), trap(kPoints);
    PointBatch<T> batch;
    for (int k = 0; k < 8; ++k) batch.coords[k] = coords[k].data();
    batch.count = kPoints;
    const EscapeBatch<T> out{n.data(), r.data(), ra.data(), rb.data(), de.data(), trap.data()};
    for (auto _ : state) {
        evaluateBatch(fractal, batch, out, target);
        benchmark::DoNotOptimize(de.data());
        benchmark::ClobberMemory();
    }
    // The kernel's own escape counts (float's can differ from evaluate()'s near the boundary).
    double iterations = 0.0;
    for (const std::int32_t count : n) iterations += count ? count : fractal.iterations;
    setCounters(state, variant, iterations);
}

/// The renderer on the comparison scene of bench/compare.py (640x480, one ray a pixel, the
/// quaternion Julia set c = (-0.39054, -0.58679, 0, 0), N = 12): packet engine against scalar.
void renderScene(benchmark::State& state, RenderEngine engine) {
    Params params;
    params.fractal.c = DualQuat{makeQuat(-0.39054, -0.58679, 0.0, 0.0), makeQuat(0.0, 0.0, 0.0, 0.0)};
    params.fractal.variant = Variant::Dual;
    params.fractal.iterations = 12;
    params.fractal.bailout = 1.0 + norm(params.fractal.c.a);  // POV-Ray's julia_fractal bailout
    params.camera.position = glm::dvec3(2.2, 1.8, 4.0);
    params.camera.target = glm::dvec3(0.0);
    params.render.samples = 1;
    for (auto _ : state) benchmark::DoNotOptimize(render(params, {}, engine).stats.steps);
    state.SetItemsProcessed(state.iterations());  // images
}

/// Keeps every run's rates for the summary, and prints as usual.
class SummaryReporter : public benchmark::ConsoleReporter {
public:
    void ReportRuns(const std::vector<Run>& runs) override {
        for (const Run& run : runs) {
            if (run.run_type != Run::RT_Iteration) continue;
            const auto items = run.counters.find("items_per_second");
            const auto flops = run.counters.find("flops");
            if (items != run.counters.end()) evaluations[run.benchmark_name()] = items->second;
            if (flops != run.counters.end()) flopRate[run.benchmark_name()] = flops->second;
            const auto first = run.counters.find("first_ms"), last = run.counters.find("last_ms");
            if (first != run.counters.end() && last != run.counters.end())
                counters[run.benchmark_name()] = {first->second, last->second};
        }
        ConsoleReporter::ReportRuns(runs);
    }
    std::map<std::string, double> evaluations;
    std::map<std::string, double> flopRate;
    std::map<std::string, std::pair<double, double>> counters;  ///< first_ms, last_ms
};

double clockGHz() {
    std::ifstream cpuinfo("/proc/cpuinfo");
    for (std::string line; std::getline(cpuinfo, line);) {
        if (line.rfind("cpu MHz", 0) == 0) {
            const auto colon = line.find(':');
            if (colon != std::string::npos) return std::stod(line.substr(colon + 1)) / 1000.0;
        }
    }
    return 0.0;
}

constexpr int kFmaChains = 16;  // independent: two FMA units of latency 4 need 8 in flight

#if defined(__x86_64__)
/// `rounds` x kFmaChains independent FMAs on 512-bit vectors; the chains' values to `out`
/// (kFmaChains x 8 doubles), so that the work is not optimised away.
__attribute__((target("avx512f"))) void fmaChains512(long rounds, double* out) {
    __m512d acc[kFmaChains];
    for (int k = 0; k < kFmaChains; ++k) acc[k] = _mm512_set1_pd(1.0 + k);
    const __m512d scale = _mm512_set1_pd(0.999999), shift = _mm512_set1_pd(1e-6);
    for (long round = 0; round < rounds; ++round)
        for (__m512d& a : acc) a = _mm512_fmadd_pd(a, scale, shift);
    for (int k = 0; k < kFmaChains; ++k) _mm512_storeu_pd(out + 8 * k, acc[k]);
}

/// The same on 256-bit vectors (AVX2 and FMA; kFmaChains x 4 doubles to `out`).
__attribute__((target("avx2,fma"))) void fmaChains256(long rounds, double* out) {
    __m256d acc[kFmaChains];
    for (int k = 0; k < kFmaChains; ++k) acc[k] = _mm256_set1_pd(1.0 + k);
    const __m256d scale = _mm256_set1_pd(0.999999), shift = _mm256_set1_pd(1e-6);
    for (long round = 0; round < rounds; ++round)
        for (__m256d& a : acc) a = _mm256_fmadd_pd(a, scale, shift);
    for (int k = 0; k < kFmaChains; ++k) _mm256_storeu_pd(out + 4 * k, acc[k]);
}

/// FMAs a second through `chains`: the best of 5 runs of about 50 ms.
double fmaRateOf(void (*chains)(long, double*)) {
    using Clock = std::chrono::steady_clock;
    constexpr long kRounds = 20'000'000;
    double values[kFmaChains * 8];
    double best = 0.0;
    for (int run = 0; run < 5; ++run) {
        const auto start = Clock::now();
        chains(kRounds, values);
        benchmark::DoNotOptimize(values);
        benchmark::ClobberMemory();
        const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
        best = std::max(best, kFmaChains * static_cast<double>(kRounds) / seconds);
    }
    return best;
}
#endif

/// FMA instructions a second one core sustains at the dispatched width (`doubleLanes` doubles
/// a vector); 0 where it is not measured (not x86-64, or a width without FMA: SSE).
double measuredFmaRate(std::size_t doubleLanes) {
#if defined(__x86_64__)
    if (doubleLanes == 8) return fmaRateOf(fmaChains512);
    if (doubleLanes == 4) return fmaRateOf(fmaChains256);
#else
    (void)doubleLanes;
#endif
    return 0.0;
}

std::string name(const char* kind, Variant variant, const std::string& target = "") {
    return std::string(kind) + "/" + std::string(variantName(variant)) + (target.empty() ? "" : "/" + target);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc > 1 && std::string(argv[1]) == "--variation-figures") return printVariationFigures();
    const std::vector<BatchTarget> targets = batchTargets();
    const BatchTarget best = targets.front();
    const BatchTarget fallback = targets.back();
    for (const Variant variant : kVariants) {
        benchmark::RegisterBenchmark(name("scalar", variant).c_str(), scalarReference, variant);
        for (const BatchTarget& target : {best, fallback}) {
            benchmark::RegisterBenchmark(name("simd_double", variant, target.name).c_str(), simdBatch<double>, variant,
                                         target.id, Workload::Ball);
            benchmark::RegisterBenchmark(name("simd_float", variant, target.name).c_str(), simdBatch<float>, variant,
                                         target.id, Workload::Ball);
        }
        benchmark::RegisterBenchmark(name("simd_double_loop", variant, best.name).c_str(), simdBatch<double>, variant,
                                     best.id, Workload::Loop);
        benchmark::RegisterBenchmark(name("simd_float_loop", variant, best.name).c_str(), simdBatch<float>, variant,
                                     best.id, Workload::Loop);
    }
    // Wall-clock time: the renderer runs on every core.
    benchmark::RegisterBenchmark("render/packet", renderScene, RenderEngine::Packet)
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark("render/scalar", renderScene, RenderEngine::Scalar)
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond);
    registerVariationBenchmarks();
    benchmark::Initialize(&argc, argv);
    SummaryReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();

    const double ghz = clockGHz();
    const double doubleLanes = static_cast<double>(batchLanes(false));
    const double floatLanes = static_cast<double>(batchLanes(true));
    const double fmaRate = measuredFmaRate(batchLanes(false));
    // A float FMA of the same width has the throughput of a double one on every x86 core.
    const double fmasPerSecond = fmaRate > 0.0 ? fmaRate : 2.0 * ghz * 1e9;
    const double peakDouble = doubleLanes * 2.0 * fmasPerSecond;
    const double peakFloat = floatLanes * 2.0 * fmasPerSecond;
    std::printf("\nSummary (same run, one thread; %s dispatched, %s fallback)\n", best.name.c_str(),
                fallback.name.c_str());
    if (fmaRate > 0.0) {
        std::printf(
            "peak of one core, measured: %.2f G FMA/s of %.0f doubles (%.2f a cycle at cpuinfo's %.3f GHz) x 2 flops = "
            "%.1f GFLOP/s double, %.1f float (%.0f lanes)\n",
            fmaRate / 1e9, doubleLanes, ghz > 0.0 ? fmaRate / (ghz * 1e9) : 0.0, ghz, peakDouble / 1e9, peakFloat / 1e9,
            floatLanes);
    } else {
        std::printf(
            "peak of one core, nominal: %.0f lanes (double) / %.0f (float) x 2 FMA units x 2 flops x %.3f GHz "
            "(cpuinfo) = %.1f GFLOP/s double, %.1f float\n",
            doubleLanes, floatLanes, ghz, peakDouble / 1e9, peakFloat / 1e9);
    }
    std::printf("%-14s %14s %14s %8s %14s %8s %14s %9s %9s %9s %9s %9s\n", "variant", "scalar Meval/s",
                "double Meval/s", "x scalar", "float Meval/s", "x scalar", "fallback dbl", "scal %pk", "dbl %pk",
                "flt %pk", "dbl loop", "flt loop");
    for (const Variant variant : kVariants) {
        auto rate = [&](const std::string& key) {
            const auto found = reporter.evaluations.find(key);
            return found == reporter.evaluations.end() ? 0.0 : found->second;
        };
        auto flops = [&](const std::string& key) {
            const auto found = reporter.flopRate.find(key);
            return found == reporter.flopRate.end() ? 0.0 : found->second;
        };
        const double scalar = rate(name("scalar", variant));
        if (scalar == 0.0) continue;  // filtered out
        const std::string doubleKey = name("simd_double", variant, best.name);
        const std::string floatKey = name("simd_float", variant, best.name);
        std::printf("%-14s %14.2f %14.2f %8.2f %14.2f %8.2f %14.2f %8.1f%% %8.1f%% %8.1f%% %8.1f%% %8.1f%%\n",
                    std::string(variantName(variant)).c_str(), scalar / 1e6, rate(doubleKey) / 1e6,
                    rate(doubleKey) / scalar, rate(floatKey) / 1e6, rate(floatKey) / scalar,
                    rate(name("simd_double", variant, fallback.name)) / 1e6,
                    100.0 * flops(name("scalar", variant)) / peakDouble, 100.0 * flops(doubleKey) / peakDouble,
                    100.0 * flops(floatKey) / peakFloat,
                    100.0 * flops(name("simd_double_loop", variant, best.name)) / peakDouble,
                    100.0 * flops(name("simd_float_loop", variant, best.name)) / peakFloat);
    }
    const auto packet = reporter.evaluations.find("render/packet/real_time");
    const auto scalar = reporter.evaluations.find("render/scalar/real_time");
    if (packet != reporter.evaluations.end() && scalar != reporter.evaluations.end() && scalar->second > 0.0)
        std::printf(
            "renderer, 640x480 quaternion Julia (bench/compare.py's scene): packet %.1f ms, scalar %.1f ms, %.2fx\n",
            1e3 / packet->second, 1e3 / scalar->second, packet->second / scalar->second);
    const auto variations = reporter.counters.find("variations/grid9_128px/real_time");
    if (variations != reporter.counters.end())
        std::printf(
            "variations, the first grid of nine 128x128 thumbnails: first %.0f ms, last %.0f ms (target: last <= 1000 ms)\n",
            variations->second.first, variations->second.second);
    return 0;
}
