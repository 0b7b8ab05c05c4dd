// explore.hpp - seeded random constants for exploring, empty slices skipped.
//
// Each part of the constant is drawn as a complex number near the edge of the Mandelbrot set
// (where Julia sets are detailed rather than blobs or dust) and turned into a quaternion by a random direction of the
// imaginary axes (math.md: c0 + |c_v| i is what matters). Candidates whose slice is empty, or
// nearly so, at the base parameters' N are skipped. The same seed gives the same constants on
// every machine (own uniform mapping, no std distributions). Cost: one inspect() per candidate.
#pragma once

#include <cstdint>
#include <vector>

#include "dqjulia/params.hpp"

namespace dqj {

struct ExploreOptions {
    std::uint64_t seed = 1;
    int count = 12;
    double minInsideFraction = 0.004;  ///< of the bounds' cube, sampled 16^3; below it counts as empty
    int maxAttempts = 5000;
};

struct ExploreResult {
    std::vector<Params> tiles;  ///< `base` with a new constant each (description says where it came from)
    int attempts = 0;
    int skippedEmpty = 0;  ///< candidates rejected because their slice was (nearly) empty
};

/// Draws constants until `count` have non-empty slices (or maxAttempts is reached).
ExploreResult explore(const Params& base, const ExploreOptions& options);

/// "(-0.12, 0.65, 0.03, 0)(0.1, -0.2, 0, 0.3)": the constant as the paper prints it.
std::string constantText(const DualQuat& c, int decimals = 3);

}  // namespace dqj
