// dqjulia/image.hpp - rendered images and their files: 8-bit sRGB PNG, 16-bit PNG, and EXR
// with depth and normal passes for compositing.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "dqjulia/export.h"
#include "dqjulia/params.hpp"

namespace dqj {

/// Row-major, top row first. Colours are linear RGB; files get the sRGB transfer (PNG) or
/// stay linear (EXR). PNG files hold `rgba`'s colour (the background included, opaque); EXR
/// files hold `surface` with alpha (premultiplied, transparent background), depth and normals.
struct Image {
    int width = 0;
    int height = 0;
    std::vector<float> rgba;  ///< 4 per pixel: the picture over the background; alpha = fraction of samples that hit
    std::vector<float>
        surface;                ///< 3 per pixel: the surface alone, premultiplied by alpha (EXR's RGB, for compositing)
    std::vector<float> depth;   ///< 1 per pixel: distance from the eye to the nearest hit, +inf if none
    std::vector<float> normal;  ///< 3 per pixel: unit surface normal in slice coordinates, 0 if none
};

/// Linear [0, 1] to an 8-bit sRGB code (clamped, rounded). The one sRGB encoder of the library.
DQJ_API std::uint8_t linearToSrgb8(float linear);

/// Writes `image` to `path` in `format`. The file is written to an unnamed temporary file in
/// the same folder, every write checked, and published only when complete, so a failure never
/// leaves a partial file or destroys an existing one. `existing`: replace an existing file or
/// keep it (and fail). Throws std::runtime_error naming the path and the cause.
DQJ_API void writeImage(const Image& image, const std::string& path, ImageFormat format,
                        Existing existing = Existing::Replace);

/// Reads an 8- or 16-bit PNG into linear RGBA floats (depth and normal stay empty).
/// Throws std::runtime_error.
DQJ_API Image readPng(const std::string& path);

}  // namespace dqj
