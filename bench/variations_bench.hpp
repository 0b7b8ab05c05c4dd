// variations_bench.hpp - the variations' benchmark and figures (variations_bench.cpp), for
// dqjulia_bench's main (kernel_bench.cpp).
#pragma once

namespace dqj {

/// Registers "variations/grid9_128px": the first grid of nine 128x128 thumbnails.
void registerVariationBenchmarks();
/// Prints the rejections by measure in 1,000 candidates, and the diversity, per strength.
int printVariationFigures();

}  // namespace dqj
