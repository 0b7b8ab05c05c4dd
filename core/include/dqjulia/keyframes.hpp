// dqjulia/keyframes.hpp - keyframed parameters: the parameter file's "animation" section
// (docs/baking.md, "Animation") and the parameters at a frame.
#pragma once

#include <string>
#include <vector>

#include "dqjulia/export.h"

namespace dqj {

struct Params;

/// Keyframes: the parameter file's "animation" section (docs/baking.md, "Animation").
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
/// the first key the first value holds, after the last the last; between two keys a value lies
/// between theirs); iterations round to the nearest whole number. Not validated: call validate()
/// on the result, or use validAtFrame. Without tracks, a copy.
DQJ_API Params atFrame(const Params& params, double frame);
/// atFrame without the animation: the still parameters of one frame. Not validated.
DQJ_API Params stillAtFrame(const Params& params, double frame);
/// atFrame, validated: a ParamError names the frame ("at frame 12: fractal.bailout: ...").
/// Without tracks, `params` as it is (not validated again).
DQJ_API Params validAtFrame(const Params& params, double frame);
/// Checks that validAtFrame(params, f) passes for every whole frame f from `first` to `last`, given
/// that validate(params) has passed; throws the ParamError validAtFrame would for the first
/// frame that fails. Cost: the keys were checked by validate; here, for the frames within the
/// keys' span, about 0.2 microseconds a frame where the constant is animated and 0.06 a frame for
/// each rotation of the slice where a rotation is (a million frames: 0.2 s, 2 s with 28 animated
/// rotations); nothing for the frames outside the span or without keys.
DQJ_API void checkFrames(const Params& params, int first, int last);
/// "fractal.c", "fractal.iterations", "fractal.bailout" or "slice.rotations[i].degrees".
DQJ_API std::string trackKey(const Track& track);
}  // namespace dqj
