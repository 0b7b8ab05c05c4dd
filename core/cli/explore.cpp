// Exploration (explore.hpp): reproducible random constants with non-empty slices.
#include "explore.hpp"

#include <cmath>
#include <complex>
#include <numbers>
#include <random>
#include <sstream>

#include "dqjulia/inspect.hpp"

namespace dqj {
namespace {

/// Uniform in [0, 1) from the top 53 bits: identical on every standard library.
double uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }
double uniform(std::mt19937_64& rng, double low, double high) { return low + (high - low) * uniform(rng); }

double rounded(double value, int decimals) {
    const double scale = std::pow(10.0, decimals);
    return std::round(value * scale) / scale + 0.0;  // + 0.0: no "-0"
}

bool staysBounded(std::complex<double> c) {
    std::complex<double> z = 0.0;
    for (int k = 0; k < 100; ++k) {
        z = z * z + c;
        if (std::norm(z) > 4.0) return false;
    }
    return true;
}

/// A complex constant within 0.03 of the Mandelbrot set's edge, on either side: deep inside
/// the Julia sets are plain blobs, far outside they are dust; near the edge they are detailed.
std::complex<double> nearMandelbrotEdge(std::mt19937_64& rng) {
    constexpr double kReach = 0.03;
    while (true) {
        const std::complex<double> c(uniform(rng, -1.6, 0.45), uniform(rng, 0.0, 1.1));
        const bool inside = staysBounded(c);
        for (const std::complex<double> step : {std::complex<double>(kReach, 0), std::complex<double>(-kReach, 0),
                                                std::complex<double>(0, kReach), std::complex<double>(0, -kReach)})
            if (staysBounded(c + step) != inside) return c;
    }
}

/// c0 + |c_v| i turned into a quaternion by a random unit direction of (i, j, k).
Quat randomQuaternion(std::mt19937_64& rng) {
    const std::complex<double> c = nearMandelbrotEdge(rng);
    const double z = uniform(rng, -1.0, 1.0);
    const double angle = uniform(rng, 0.0, 2.0 * std::numbers::pi);
    const double ring = std::sqrt(1.0 - z * z);
    const int decimals = 3;
    return makeQuat(rounded(c.real(), decimals), rounded(c.imag() * ring * std::cos(angle), decimals),
                    rounded(c.imag() * ring * std::sin(angle), decimals), rounded(c.imag() * z, decimals));
}

std::string number(double value, int decimals) {
    std::ostringstream out;
    out << rounded(value, decimals);
    return out.str();
}

}  // namespace

std::string constantText(const DualQuat& c, int decimals) {
    std::string text;
    for (int part = 0; part < 2; ++part) {
        text += "(";
        for (int index = 0; index < 4; ++index)
            text += (index ? ", " : "") + number(component(c, 4 * part + index), decimals);
        text += ")";
    }
    return text;
}

ExploreResult explore(const Params& base, const ExploreOptions& options) {
    ExploreResult result;
    std::mt19937_64 rng(options.seed);
    while (static_cast<int>(result.tiles.size()) < options.count && result.attempts < options.maxAttempts) {
        ++result.attempts;
        Params candidate = base;
        candidate.fractal.c = {randomQuaternion(rng), randomQuaternion(rng)};
        candidate.fractal.bailout = std::max(base.fractal.bailout, minimumBailout(candidate.fractal));
        candidate.bounds.reset();
        const InspectReport report = inspect(candidate, 16);
        if (!report.emptyReason.empty() || report.insideFraction < options.minInsideFraction) {
            ++result.skippedEmpty;
            continue;
        }
        candidate.description = "dqjulia explore, seed " + std::to_string(options.seed) + ", tile " +
                                std::to_string(result.tiles.size() + 1) + ": c = " + constantText(candidate.fractal.c) +
                                ", variant " + std::string(variantName(candidate.fractal.variant)) +
                                ", N = " + std::to_string(candidate.fractal.iterations);
        result.tiles.push_back(std::move(candidate));
    }
    return result;
}

}  // namespace dqj
