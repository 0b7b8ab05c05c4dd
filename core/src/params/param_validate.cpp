// validate(): the parameter set's rules. Types and ranges come from the schema (the same check
// as the file's reader); the rules between fields are here: bailout against r_K, a 3-D slice,
// a camera that looks somewhere, normals the variant can give, an image path, keyframes.
#include <algorithm>
#include <cctype>
#include <cmath>

#include <glm/geometric.hpp>

#include "dqjulia/param_file.hpp"
#include "params/json_text.hpp"
#include "files/message_text.hpp"
#include "params/param_check.hpp"

namespace dqj {

namespace {

using json::formatNumber;

bool parallel(const glm::dvec3& a, const glm::dvec3& b) {
    return glm::length(glm::cross(glm::normalize(a), glm::normalize(b))) < 1e-6;
}

}  // namespace

namespace detail {

void checkBailoutRule(const Params& params) {
    const Fractal& fractal = params.fractal;
    const double needed = minimumBailout(fractal);
    if (!(fractal.bailout >= needed))
        throw ParamError("fractal.bailout",
                         "fractal.bailout: is " + formatNumber(fractal.bailout) +
                             " but must be at least the containment radius r_K = " + formatNumber(needed) +
                             " of this constant and variant (points inside r_K may still be in "
                             "the set)");
}

void checkSliceRule(const Params& params) {
    auto fail = [](const std::string& key, const std::string& message) { throw ParamError(key, key + ": " + message); };
    const Slice slice = params.slice.effective();
    const Stretch stretch = stretchOf(slice);
    if (stretch.min < 1e-9 * std::max(1.0, stretch.max))
        fail("slice.axes", "the three axes are zero or parallel, so the slice is not 3-D; give three independent axes");
    // Linearly dependent axes (z = x + y) span a plane: the Gram determinant vanishes against
    // the product of the squared lengths (Hadamard's bound; 1 for orthogonal axes).
    double gram[3][3] = {};
    for (int row = 0; row < 3; ++row)
        for (int column = 0; column < 3; ++column)
            for (int index = 0; index < 8; ++index)
                gram[row][column] += slice.axes[row][index] * slice.axes[column][index];
    const double determinant = gram[0][0] * (gram[1][1] * gram[2][2] - gram[1][2] * gram[2][1]) -
                               gram[0][1] * (gram[1][0] * gram[2][2] - gram[1][2] * gram[2][0]) +
                               gram[0][2] * (gram[1][0] * gram[2][1] - gram[1][1] * gram[2][0]);
    if (!(determinant > 1e-10 * gram[0][0] * gram[1][1] * gram[2][2]))
        fail("slice.axes",
             "the three axes are linearly dependent (one is a combination of the others), so the slice "
             "is a plane, not 3-D; give three independent axes");
}

}  // namespace detail

void validate(const Params& params) {
    auto fail = [](const std::string& key, const std::string& message) { throw ParamError(key, key + ": " + message); };
    // What passes (from flags or the C ABI) is written by --save-params as a file that reads back.
    for (const PlaneRotation& rotation : params.slice.rotations)
        if (rotation.first == rotation.second || rotation.first < 0 || rotation.first > 7 || rotation.second < 0 ||
            rotation.second > 7)
            fail("slice.rotations", "a rotation plane must name two different axes");
    // Types and ranges: every key against its schema field, as the file's reader checks them.
    detail::checkDocument(json::Json::parse(toJson(params)));
    detail::checkBailoutRule(params);
    detail::checkSliceRule(params);
    const Fractal& fractal = params.fractal;

    const Camera& camera = params.camera;
    if (glm::length(camera.up) == 0.0) fail("camera.up", "must not be the zero vector");
    glm::dvec3 forward;
    if (camera.position) {
        const glm::dvec3 target = camera.target.value_or(glm::dvec3(0.0));
        forward = target - *camera.position;
        if (camera.target && glm::length(forward) == 0.0)
            fail("camera.position", "equals camera.target; the camera must look somewhere");
    } else {
        if (glm::length(camera.direction) == 0.0) fail("camera.direction", "must not be the zero vector");
        forward = -camera.direction;
    }
    if (glm::length(forward) > 0.0 && parallel(forward, camera.up))
        fail("camera.up", "is parallel to the viewing direction; choose an up vector across it");

    for (std::size_t index = 0; index < params.lights.size(); ++index)
        if (glm::length(params.lights[index].direction) == 0.0)
            fail("lights[" + std::to_string(index) + "].direction", "must not be the zero vector");

    if (params.render.normals == NormalMethod::Analytic && fractal.variant != Variant::Dual)
        fail("render.normals",
             "\"analytic\" normals come from the dual part of the true algebra and need variant \"dual\"; "
             "use \"central\" or \"auto\" with variant \"" +
                 std::string(variantName(fractal.variant)) + "\"");
    if (params.output.path.empty()) fail("output.path", "must not be empty");
    if (!params.output.format) {
        std::string extension =
            params.output.path.substr(std::min(params.output.path.size(), params.output.path.rfind('.')));
        std::transform(extension.begin(), extension.end(), extension.begin(),
                       [](unsigned char ch) { return std::tolower(ch); });
        if (extension != ".png" && extension != ".exr")
            fail("output.path", "\"" + inputExcerpt(params.output.path) +
                                    "\" must end in .png or .exr (or set output.format to png8, png16 or exr)");
    }

    const BakeSettings& bake = params.bake;
    if (bake.bounds)
        for (int axis = 0; axis < 3; ++axis)
            if (!(bake.bounds->min[axis] < bake.bounds->max[axis]))
                fail("bake.bounds", "min must be below max on every axis (x, y, z)");
    if (bake.maxFaces > 0 && bake.adaptivity > 0.0)
        fail("bake.max_faces", "chooses the adaptivity itself: give bake.max_faces or bake.adaptivity, not both");

    // Keyframes: a rotation track needs its rotation, and the parameters at every key must pass
    // the rules above (checkFrames, keyframes.cpp, checks the frames between keys).
    for (const Track& track : params.animation) {
        if (track.target == AnimatedValue::RotationDegrees && track.rotation >= int(params.slice.rotations.size()))
            fail("animation." + trackKey(track),
                 "animates rotation " + std::to_string(track.rotation) + " but slice.rotations has " +
                     std::to_string(params.slice.rotations.size()) + " (they count from 0)");
        for (const Keyframe& key : track.keys) {
            const Params still = stillAtFrame(params, key.frame);
            try {
                validate(still);
            } catch (const ParamError& error) {
                throw ParamError(error.key(), "animation: at frame " + formatNumber(key.frame) + " (a key of " +
                                                  trackKey(track) + "): " + error.what());
            }
        }
    }
}

}  // namespace dqj
