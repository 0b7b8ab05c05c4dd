// Keyframed parameters (keyframes.hpp): the value of a track at a frame, linear or monotone
// cubic between its keys.
#include "dqjulia/keyframes.hpp"

#include <algorithm>
#include <cmath>

#include "dqjulia/param_types.hpp"

namespace dqj {

namespace {

/// The slope at key `index` of one component for smooth interpolation: 0 at the first and last
/// key and where the values turn (a local extremum), else the weighted harmonic mean of the two
/// neighbouring secant slopes (Fritsch-Butland), which keeps the cubic monotone between keys.
double smoothSlope(const std::vector<Keyframe>& keys, std::size_t index, std::size_t component) {
    if (index == 0 || index + 1 >= keys.size()) return 0.0;
    const double h0 = keys[index].frame - keys[index - 1].frame;
    const double h1 = keys[index + 1].frame - keys[index].frame;
    const double d0 = (keys[index].value[component] - keys[index - 1].value[component]) / h0;
    const double d1 = (keys[index + 1].value[component] - keys[index].value[component]) / h1;
    if (d0 * d1 <= 0.0) return 0.0;
    const double w0 = 2.0 * h1 + h0, w1 = h1 + 2.0 * h0;
    return (w0 + w1) / (w0 / d0 + w1 / d1);
}

/// The track's value at `frame`, one number per component.
std::vector<double> trackValue(const Track& track, double frame) {
    const std::vector<Keyframe>& keys = track.keys;
    if (frame <= keys.front().frame) return keys.front().value;
    if (frame >= keys.back().frame) return keys.back().value;
    std::size_t index = 0;
    while (!(frame < keys[index + 1].frame)) ++index;
    const Keyframe& from = keys[index];
    const Keyframe& to = keys[index + 1];
    const double span = to.frame - from.frame;
    const double t = (frame - from.frame) / span;
    std::vector<double> value(from.value.size());
    for (std::size_t component = 0; component < value.size(); ++component) {
        const double v0 = from.value[component], v1 = to.value[component];
        if (from.interpolation == Interpolation::Linear) {
            value[component] = v0 + t * (v1 - v0);
            continue;
        }
        // Cubic Hermite between the keys with the slopes above.
        const double m0 = smoothSlope(keys, index, component) * span;
        const double m1 = smoothSlope(keys, index + 1, component) * span;
        const double t2 = t * t, t3 = t2 * t;
        value[component] =
            (2 * t3 - 3 * t2 + 1) * v0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * v1 + (t3 - t2) * m1;
    }
    return value;
}

}  // namespace

Params atFrame(const Params& params, double frame) {
    Params result = params;
    for (const Track& track : params.animation) {
        const std::vector<double> value = trackValue(track, frame);
        switch (track.target) {
            case AnimatedValue::Constant: {
                Vec8 c;
                std::copy(value.begin(), value.end(), c.begin());
                result.fractal.c = toDualQuat(c);
                break;
            }
            case AnimatedValue::Iterations: result.fractal.iterations = std::max(1, int(std::lround(value[0]))); break;
            case AnimatedValue::Bailout: result.fractal.bailout = value[0]; break;
            case AnimatedValue::RotationDegrees:
                if (track.rotation < int(result.slice.rotations.size()))
                    result.slice.rotations[track.rotation].degrees = value[0];
                break;
        }
    }
    return result;
}

std::string trackKey(const Track& track) {
    switch (track.target) {
        case AnimatedValue::Constant: return "fractal.c";
        case AnimatedValue::Iterations: return "fractal.iterations";
        case AnimatedValue::Bailout: return "fractal.bailout";
        case AnimatedValue::RotationDegrees: return "slice.rotations[" + std::to_string(track.rotation) + "].degrees";
    }
    return "unknown";
}

}  // namespace dqj
