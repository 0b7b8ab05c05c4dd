// Keyframed parameters (keyframes.hpp): the value of a track at a frame, linear or monotone
// cubic between its keys.
#include "dqjulia/keyframes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "dqjulia/param_types.hpp"
#include "dqjulia/params.hpp"
#include "params/json_text.hpp"
#include "params/param_check.hpp"

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

/// The track's value at `frame`, one number per component. Between two keys every component
/// lies between the two keys' values: linear interpolation, and the cubic with these slopes
/// (Fritsch-Butland: a slope is at most 3 times either neighbouring secant, since
/// (w0 + w1) / (w0 / d0 + w1 / d1) <= (1 + w1 / w0) d0 and w1 / w0 <= 2, and likewise for d1;
/// Fritsch and Carlson's condition for a monotone cubic). The clamp keeps it so in floating
/// point too, where the sums below may round past a key's value by an ulp; checkFrames relies on it.
std::vector<double> trackValue(const Track& track, double frame) {
    const std::vector<Keyframe>& keys = track.keys;
    if (frame <= keys.front().frame) return keys.front().value;
    if (frame >= keys.back().frame) return keys.back().value;
    const std::size_t index =
        std::size_t(std::upper_bound(keys.begin(), keys.end(), frame,
                                     [](double at, const Keyframe& key) { return at < key.frame; }) -
                    keys.begin()) -
        1;
    const Keyframe& from = keys[index];
    const Keyframe& to = keys[index + 1];
    const double span = to.frame - from.frame;
    const double t = (frame - from.frame) / span;
    std::vector<double> value(from.value.size());
    for (std::size_t component = 0; component < value.size(); ++component) {
        const double v0 = from.value[component], v1 = to.value[component];
        double v;
        if (from.interpolation == Interpolation::Linear) {
            v = v0 + t * (v1 - v0);
        } else {
            // Cubic Hermite between the keys with the slopes above.
            const double m0 = smoothSlope(keys, index, component) * span;
            const double m1 = smoothSlope(keys, index + 1, component) * span;
            const double t2 = t * t, t3 = t2 * t;
            v = (2 * t3 - 3 * t2 + 1) * v0 + (t3 - 2 * t2 + t) * m0 + (-2 * t3 + 3 * t2) * v1 + (t3 - t2) * m1;
        }
        // Not std::clamp: a NaN (slopes that overflow for keys a hair apart) becomes a key's value too.
        const double low = std::min(v0, v1), high = std::max(v0, v1);
        value[component] = v >= low ? (v <= high ? v : high) : low;
    }
    return value;
}

/// Sets the values `tracks` animate in `params` to theirs at `frame`.
void applyTracks(Params& params, const std::vector<Track>& tracks, double frame) {
    for (const Track& track : tracks) {
        const std::vector<double> value = trackValue(track, frame);
        switch (track.target) {
            case AnimatedValue::Constant: {
                Vec8 c;
                std::copy(value.begin(), value.end(), c.begin());
                params.fractal.c = toDualQuat(c);
                break;
            }
            case AnimatedValue::Iterations: params.fractal.iterations = std::max(1, int(std::lround(value[0]))); break;
            case AnimatedValue::Bailout: params.fractal.bailout = value[0]; break;
            case AnimatedValue::RotationDegrees:
                if (track.rotation < int(params.slice.rotations.size()))
                    params.slice.rotations[track.rotation].degrees = value[0];
                break;
        }
    }
}

/// The tracks one rule between animated values depends on, and the whole frames of `first` to
/// `last` within their keys' span (none if `tracks` is empty).
struct RuleTracks {
    std::vector<Track> tracks;
    double from = 1, to = 0;

    void span(int first, int last) {
        double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
        for (const Track& track : tracks) {
            lowest = std::min(lowest, track.keys.front().frame);
            highest = std::max(highest, track.keys.back().frame);
        }
        from = std::max(double(first), std::ceil(lowest));
        to = std::min(double(last), std::floor(highest));
    }
    bool covers(double frame) const { return frame >= from && frame <= to; }
};

}  // namespace

Params atFrame(const Params& params, double frame) {
    Params result = params;
    applyTracks(result, params.animation, frame);
    return result;
}

Params stillAtFrame(const Params& params, double frame) {
    Params still = params;
    still.animation.clear();
    applyTracks(still, params.animation, frame);
    return still;
}

Params validAtFrame(const Params& params, double frame) {
    if (params.animation.empty()) return params;
    Params result = atFrame(params, frame);
    try {
        validate(result);
    } catch (const ParamError& error) {
        throw ParamError(error.key(), "at frame " + json::formatNumber(frame) + ": " + error.what());
    }
    return result;
}

// Why checking the keys and the rules between values frame by frame is checking every frame.
// validate(params) has checked the whole parameter set at every key of every track. Between
// keys, each animated number lies between the values of its track's two keys around it
// (trackValue's clamp, exact in floating point too), so every rule on a single number holds at
// every frame: they are ranges (fractal.c's components, the bailout, the rotation angles, and
// the iterations, which round to whole numbers between the keys'). That is everything the costly
// check of the whole document (detail::checkDocument, through JSON) enforces on animated values.
// What is left are the two rules that relate values, each depending on some tracks only:
// - the bailout against r_K of the constant (detail::checkBailoutRule): |c| between keys may
//   exceed every key's (two components, each monotone, peaking together). It depends on the
//   tracks of c and the bailout; without a track of c it holds (r_K fixed, the bailout between
//   keys' values that pass).
// - the slice's axes after its rotations (detail::checkSliceRule): rotations keep the axes'
//   rules in exact arithmetic only. It depends on the rotations' tracks.
// Each is checked at every whole frame of its tracks' span, with only those tracks applied;
// outside that span its values are those at the span's first or last key, where validate
// checked them. Frame by frame, the bailout rule before the slice's, as validate() orders them,
// so the first failure is the one validAtFrame gives. Cost: about 0.2 microseconds a frame for
// the bailout rule, and 0.06 microseconds a rotation a frame for the slice's.
void checkFrames(const Params& params, int first, int last) {
    RuleTracks bailout, slice;
    const bool constantAnimated = std::any_of(params.animation.begin(), params.animation.end(), [](const Track& track) {
        return track.target == AnimatedValue::Constant;
    });
    for (const Track& track : params.animation) {
        if (track.target == AnimatedValue::RotationDegrees) slice.tracks.push_back(track);
        if (constantAnimated && (track.target == AnimatedValue::Constant || track.target == AnimatedValue::Bailout))
            bailout.tracks.push_back(track);
    }
    bailout.span(first, last);
    slice.span(first, last);
    Params still = params;
    still.animation.clear();
    for (double frame = std::min(bailout.from, slice.from); frame <= std::max(bailout.to, slice.to); ++frame) {
        try {
            if (bailout.covers(frame)) {
                applyTracks(still, bailout.tracks, frame);  // sets all the rule's values: none of the last frame stays
                detail::checkBailoutRule(still);
            }
            if (slice.covers(frame)) {
                applyTracks(still, slice.tracks, frame);
                detail::checkSliceRule(still);
            }
        } catch (const ParamError& error) {
            throw ParamError(error.key(), "at frame " + json::formatNumber(frame) + ": " + error.what());
        }
    }
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
