// The variations' benchmark (issue 38): the first grid of nine 128x128 thumbnails around the
// default document, as `dqjulia explore --around` and the Blender add-on make it: vary() (medium
// strength, the variant locked) and then nine renders at one ray a pixel, on every core. Counters:
// the wall time to the first thumbnail (the variations and the first render) and to the last.
// Target: the last within 1 s on 2 cores.
//
// `dqjulia_bench --variation-figures` prints, instead of benchmarking, the figures of
// docs/variations.md: per strength, what each measure rejected in a sample of 1,000 candidates
// and the image distances of the variations that passed, around the default document and around
// the paper's test2 tile 2 (beyond the Mandelbrot set's edge).
#include "variations_bench.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "dqjulia/render.hpp"
#include "dqjulia/variations.hpp"

namespace dqj {
namespace {

void variationGrid(benchmark::State& state) {
    using Clock = std::chrono::steady_clock;
    double first = 0.0, last = 0.0;
    std::uint64_t seed = 1;
    for (auto _ : state) {
        const auto start = Clock::now();
        VariationOptions options;
        options.seed = seed++;  // a new grid each time, as Refresh makes
        options.strength = 0.3;
        options.count = 9;
        const VariationResult found = vary(Params(), options);
        for (std::size_t index = 0; index < found.variations.size(); ++index) {
            Params thumbnail = found.variations[index].params;
            thumbnail.render.width = thumbnail.render.height = 128;
            thumbnail.render.samples = 1;
            benchmark::DoNotOptimize(render(thumbnail).stats.hitPixels);
            const double seconds = std::chrono::duration<double>(Clock::now() - start).count();
            if (index == 0) first += seconds;
            last = index + 1 == found.variations.size() ? last + seconds : last;
        }
    }
    state.counters["first_ms"] = benchmark::Counter(1e3 * first, benchmark::Counter::kAvgIterations);
    state.counters["last_ms"] = benchmark::Counter(1e3 * last, benchmark::Counter::kAvgIterations);
}

}  // namespace

void registerVariationBenchmarks() {
    benchmark::RegisterBenchmark("variations/grid9_128px", variationGrid)->UseRealTime()->Unit(benchmark::kMillisecond);
}

int printVariationFigures() {
    // The default document (its constant inside the Mandelbrot set, near the edge), and the
    // paper's test2 tile 2 (examples/paper-test2-2.json: the real part just outside, N = 8).
    Params beyond;
    beyond.fractal.c = {makeQuat(-0.67, -0.54, -0.07, 0.02), makeQuat(0.06, -0.53, 0.15, -0.27)};
    beyond.fractal.iterations = 8;
    for (const auto& [label, base] : {std::pair<const char*, Params>{"the default document", Params()},
                                      std::pair<const char*, Params>{"paper-test2-2", beyond}}) {
        std::printf("\nvariations of %s, seed 1, the variant locked; 1,000 candidates a strength\n", label);
        std::printf("%-7s %8s %8s %6s %6s %6s %6s %8s %8s  %s\n", "", "accepted", "invalid", "empty", "dust", "tiny",
                    "ball", "similar", "bound", "distance from the original: min / mean / max; closest pair");
        for (const StrengthName& name : strengthNames()) {
            VariationOptions options;
            options.seed = 1;
            options.strength = name.value;
            const VariationResult result = sampleVariations(base, options, 1000);
            double low = 1.0, high = 0.0, sum = 0.0;
            for (const Variation& variation : result.variations) {
                low = std::min(low, variation.measures.distance);
                high = std::max(high, variation.measures.distance);
                sum += variation.measures.distance;
            }
            // The closest pair among the first nine (one grid).
            double closest = 1.0;
            std::vector<std::vector<std::uint16_t>> grid;
            for (std::size_t i = 0; i < std::min<std::size_t>(9, result.variations.size()); ++i)
                grid.push_back(thumbnailOf(result.variations[i].params));
            for (std::size_t i = 0; i < grid.size(); ++i)
                for (std::size_t j = 0; j < i; ++j) closest = std::min(closest, thumbnailDistance(grid[i], grid[j]));
            std::printf("%-7s %8zu", std::string(name.name).c_str(), result.variations.size());
            for (int r = 0; r < kRejectionCount; ++r)
                std::printf(" %*d", r == 0 || r == kRejectionCount - 1 ? 8 : 6, result.rejected[r]);
            std::printf(" %8.3f  %.3f / %.3f / %.3f; first grid's closest pair %.3f\n", result.minimumDistance, low,
                        result.variations.empty() ? 0.0 : sum / double(result.variations.size()), high, closest);
        }
    }
    return 0;
}

}  // namespace dqj
