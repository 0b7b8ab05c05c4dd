// dqjulia_bench - distance-estimate evaluations per second: the scalar reference evaluate()
// against the SIMD batch kernel (batch.hpp) in double and float, on the dispatched instruction
// set and the portable fallback, for the three variants; then the same-run ratios and the
// fraction of this core's peak floating-point rate. Single thread.
//
// Workload: 16384 points uniform in the bounding sphere of the default slice (a.s, a.i, a.j) of
// the default constant c = (-0.39054, -0.58679, 0, 0)(0, 0.5632, 0, 0.05), N = 12, R = 4: what
// the renderer and the bake ask for (about a quarter of the points are inside).
//
// Flops: counted per iteration from the kernel's operations (multiplies, adds, square roots;
// a fused multiply-add counts 2, a comparison 0): paper 51, paper-coupled 53, dual 50 (see
// kFlopsPerIteration), times the iterations each point needs (its escape count, or N). The
// final DE (a logarithm and a division per point) is not counted. Lanes that idle while their
// vector's slowest point iterates do no useful work and are not counted either.
//
// Peak: lanes of the detected instruction set x 2 FMA units x 2 flops x clock (the first
// "cpu MHz" of /proc/cpuinfo), for one core. CPUs that execute 512-bit FMAs as two 256-bit
// halves (AMD Zen 4) have half that peak for AVX-512; the summary says which it assumed.
//
// Run: build-bench/bin/dqjulia_bench (bench/run.sh builds it)  (Google Benchmark flags work, e.g. --benchmark_filter=dual)
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "dqjulia/batch.hpp"
#include "dqjulia/estimate.hpp"
#include "dqjulia/render.hpp"
#include "dqjulia/slice.hpp"

using namespace dqj;

namespace {

constexpr Variant kVariants[] = {Variant::Paper, Variant::PaperCoupled, Variant::Dual};
constexpr double kFlopsPerIteration[] = {51.0, 53.0, 50.0};  // paper, paper-coupled, dual
constexpr std::size_t kPoints = 16384;

Fractal benchFractal(Variant variant) {
    Fractal fractal;  // the default constant
    fractal.variant = variant;
    fractal.iterations = 12;
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

const std::vector<DualQuat>& points() {
    static const std::vector<DualQuat> all = benchPoints();
    return all;
}

/// Useful iterations over the workload (escape count, or N for points inside).
double iterationsOf(const Fractal& fractal) {
    double total = 0.0;
    for (const DualQuat& z : points()) {
        const int n = evaluate(fractal, z).n;
        total += n ? n : fractal.iterations;
    }
    return total;
}

void setCounters(benchmark::State& state, Variant variant) {
    const Fractal fractal = benchFractal(variant);
    static std::map<Variant, double> iterations;
    if (!iterations.count(variant)) iterations[variant] = iterationsOf(fractal);
    const double evaluations = static_cast<double>(state.iterations()) * kPoints;
    state.SetItemsProcessed(static_cast<std::int64_t>(evaluations));
    state.counters["flops"] = benchmark::Counter(static_cast<double>(state.iterations()) * iterations[variant] *
                                                     kFlopsPerIteration[static_cast<int>(variant)],
                                                 benchmark::Counter::kIsRate);
}

void scalarReference(benchmark::State& state, Variant variant) {
    const Fractal fractal = benchFractal(variant);
    for (auto _ : state) {
        for (const DualQuat& z : points()) benchmark::DoNotOptimize(evaluate(fractal, z).de);
    }
    setCounters(state, variant);
}

template <typename T>
void simdBatch(benchmark::State& state, Variant variant, std::int64_t target) {
    const Fractal fractal = benchFractal(variant);
    std::vector<T> coords[8];
    for (int k = 0; k < 8; ++k)
        for (const DualQuat& z : points()) coords[k].push_back(static_cast<T>(component(z, k)));
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
    setCounters(state, variant);
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
        }
        ConsoleReporter::ReportRuns(runs);
    }
    std::map<std::string, double> evaluations;
    std::map<std::string, double> flopRate;
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

bool splitsWideFma() {  // AMD family 25 (Zen 4) runs a 512-bit FMA as two 256-bit halves
    std::ifstream cpuinfo("/proc/cpuinfo");
    bool amd = false;
    for (std::string line; std::getline(cpuinfo, line);) {
        if (line.rfind("vendor_id", 0) == 0) amd = line.find("AuthenticAMD") != std::string::npos;
        if (line.rfind("cpu family", 0) == 0) return amd && line.find(": 25") != std::string::npos;
    }
    return false;
}

std::string name(const char* kind, Variant variant, const std::string& target = "") {
    return std::string(kind) + "/" + std::string(variantName(variant)) + (target.empty() ? "" : "/" + target);
}

}  // namespace

int main(int argc, char** argv) {
    const std::vector<BatchTarget> targets = batchTargets();
    const BatchTarget best = targets.front();
    const BatchTarget fallback = targets.back();
    for (const Variant variant : kVariants) {
        benchmark::RegisterBenchmark(name("scalar", variant).c_str(), scalarReference, variant);
        for (const BatchTarget& target : {best, fallback}) {
            benchmark::RegisterBenchmark(name("simd_double", variant, target.name).c_str(), simdBatch<double>, variant,
                                         target.id);
            benchmark::RegisterBenchmark(name("simd_float", variant, target.name).c_str(), simdBatch<float>, variant,
                                         target.id);
        }
    }
    // Wall-clock time: the renderer runs on every core.
    benchmark::RegisterBenchmark("render/packet", renderScene, RenderEngine::Packet)
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond);
    benchmark::RegisterBenchmark("render/scalar", renderScene, RenderEngine::Scalar)
        ->UseRealTime()
        ->Unit(benchmark::kMillisecond);
    benchmark::Initialize(&argc, argv);
    SummaryReporter reporter;
    benchmark::RunSpecifiedBenchmarks(&reporter);
    benchmark::Shutdown();

    const double ghz = clockGHz();
    const bool split = splitsWideFma();
    const double doubleLanes = static_cast<double>(batchLanes(false));
    const double floatLanes = static_cast<double>(batchLanes(true));
    // Lanes of the FMA units: the detected vector width, halved when 512-bit FMAs are split.
    const double fmaDoubleLanes = split && doubleLanes > 4 ? doubleLanes / 2 : doubleLanes;
    const double fmaFloatLanes = split && floatLanes > 8 ? floatLanes / 2 : floatLanes;
    const double peakDouble = fmaDoubleLanes * 2.0 * 2.0 * ghz * 1e9;
    const double peakFloat = fmaFloatLanes * 2.0 * 2.0 * ghz * 1e9;
    std::printf("\nSummary (same run, one thread; %s dispatched, %s fallback)\n", best.name.c_str(),
                fallback.name.c_str());
    std::printf(
        "peak of one core: %.0f lanes (double) / %.0f (float) per FMA x 2 FMA units x 2 flops x %.3f GHz = "
        "%.1f GFLOP/s double, %.1f float%s\n",
        fmaDoubleLanes, fmaFloatLanes, ghz, peakDouble / 1e9, peakFloat / 1e9,
        split ? " (512-bit FMAs counted as two 256-bit halves: AMD Zen 4)" : "");
    if (split)
        std::printf(
            "(at the full detected width, %.0f doubles / %.0f floats, the nominal peak would be %.1f / %.1f GFLOP/s)\n",
            doubleLanes, floatLanes, doubleLanes * 4.0 * ghz, floatLanes * 4.0 * ghz);
    std::printf("%-14s %14s %14s %8s %14s %8s %14s %9s %9s %9s\n", "variant", "scalar Meval/s", "double Meval/s",
                "x scalar", "float Meval/s", "x scalar", "fallback dbl", "scal %pk", "dbl %pk", "flt %pk");
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
        std::printf("%-14s %14.2f %14.2f %8.2f %14.2f %8.2f %14.2f %8.1f%% %8.1f%% %8.1f%%\n",
                    std::string(variantName(variant)).c_str(), scalar / 1e6, rate(doubleKey) / 1e6,
                    rate(doubleKey) / scalar, rate(floatKey) / 1e6, rate(floatKey) / scalar,
                    rate(name("simd_double", variant, fallback.name)) / 1e6,
                    100.0 * flops(name("scalar", variant)) / peakDouble, 100.0 * flops(doubleKey) / peakDouble,
                    100.0 * flops(floatKey) / peakFloat);
    }
    const auto packet = reporter.evaluations.find("render/packet/real_time");
    const auto scalar = reporter.evaluations.find("render/scalar/real_time");
    if (packet != reporter.evaluations.end() && scalar != reporter.evaluations.end() && scalar->second > 0.0)
        std::printf(
            "renderer, 640x480 quaternion Julia (bench/compare.py's scene): packet %.1f ms, scalar %.1f ms, %.2fx\n",
            1e3 / packet->second, 1e3 / scalar->second, packet->second / scalar->second);
    return 0;
}
