// dqjulia/keyframes.hpp - keyframed parameters: the parameter file's "animation" section
// (README "Animation") and the parameters at a frame.
#pragma once

#include <string>
#include <vector>

#include "dqjulia/export.h"

namespace dqj {

struct Params;

/// Keyframes: the parameter file's "animation" section (README "Animation").
enum class Interpolation {
    Linear,  ///< straight line to the next key
    Smooth   ///< monotone cubic: smooth through the keys, never overshooting them
};
struct Keyframe {
    double frame = 1.0;
    std::vector<double> value;                            ///< 8 numbers for fractal.c, 1 otherwise
    Interpolation interpolation = Interpolation::Linear;  ///< from this key to the next
};
/// What a track animates.
enum class AnimatedValue { Constant, Iterations, Bailout, RotationDegrees };
struct Track {
    AnimatedValue target = AnimatedValue::Constant;
    int rotation = 0;            ///< for RotationDegrees: the index into slice.rotations
    std::vector<Keyframe> keys;  ///< at least one, frames strictly increasing
};

/// The parameters at `frame`: every animated value replaced by its track's value there (before
/// the first key the first value holds, after the last the last); iterations round to the
/// nearest whole number. Not validated: call validate() on the result. Without tracks, a copy.
DQJ_API Params atFrame(const Params& params, double frame);
/// "fractal.c", "fractal.iterations", "fractal.bailout" or "slice.rotations[i].degrees".
DQJ_API std::string trackKey(const Track& track);
}  // namespace dqj
