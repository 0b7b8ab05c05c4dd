// dqjulia/params.hpp - the parameter set shared by the whole toolkit, and its JSON file format.
//
// One format for the CLI, the Blender add-on and the POV-Ray writer. Loading validates
// every value and throws ParamError naming the key, what was wrong and what is allowed.
// The schema is documented in README.md ("Parameter file").
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "dqjulia/estimate.hpp"
#include "dqjulia/export.h"
#include "dqjulia/slice.hpp"

namespace dqj {

/// The slice as the user wrote it: origin, axes and the rotations applied to the axes.
struct SliceSpec {
    Slice base;
    std::vector<PlaneRotation> rotations;
    Slice effective() const { return rotated(base, rotations); }
};

/// A pinhole camera. When `position` is unset the camera frames the bounds from `direction`.
struct Camera {
    std::optional<glm::dvec3> position;
    std::optional<glm::dvec3> target;          ///< default: the centre of the bounds
    glm::dvec3 direction{0.55, 0.45, 1.0};     ///< from target towards the camera, for auto framing
    glm::dvec3 up{0.0, 1.0, 0.0};
    double fovDegrees = 40.0;                  ///< vertical field of view
};

/// A directional light: `direction` points from the surface towards the light.
struct Light {
    glm::dvec3 direction{1.0, 1.0, 1.0};
    glm::dvec3 color{1.0, 1.0, 1.0};
    double intensity = 1.0;
};

enum class Coloring { Solid, Iterations, Trap };

/// Phong material (the paper's equation) plus occlusion, shadows and orbit colouring.
struct Material {
    glm::dvec3 color{0.85, 0.62, 0.35};  ///< base colour (linear RGB) for solid colouring
    Coloring coloring = Coloring::Trap;
    std::vector<glm::dvec3> palette{{0.95, 0.75, 0.40}, {0.80, 0.30, 0.20}, {0.20, 0.25, 0.55}};
    double ambient = 0.15;    ///< k_a
    double diffuse = 0.8;     ///< k_d
    double specular = 0.35;   ///< k_s
    double shininess = 24.0;  ///< specular exponent s
    double occlusion = 0.8;   ///< strength of ambient occlusion from the DE, 0 = off
    bool shadows = true;
    double shadowSoftness = 12.0;  ///< penumbra factor k: larger = harder shadows
};

enum class NormalMethod { Auto, CentralDifferences, Analytic };

struct RenderSettings {
    int width = 640;
    int height = 480;
    int samples = 2;           ///< anti-aliasing: samples x samples rays per pixel
    double stepFactor = 0.9;   ///< fraction of the distance estimate taken per step
    double maxStep = 0.25;     ///< largest step, in slice units
    int maxSteps = 400;
    double detail = 1.0;       ///< hit threshold in pixel footprints (smaller = finer)
    NormalMethod normals = NormalMethod::Auto;  ///< auto: analytic for dual, central differences otherwise
    glm::dvec3 backgroundTop{0.30, 0.36, 0.45};
    glm::dvec3 backgroundBottom{0.06, 0.06, 0.08};
};

enum class ImageFormat { Png8, Png16, Exr };

struct OutputSettings {
    std::string path = "out/dqjulia.png";
    std::optional<ImageFormat> format;  ///< default: from the file extension
};

/// A box in slice coordinates (bake.bounds).
struct Box {
    glm::dvec3 min{-1.0};
    glm::dvec3 max{1.0};
};

/// The grids a bake can write (bake.grids). README "Baking" says what each holds.
enum class BakeGrid { Surface, Density, Color, Trap, Iterations };

/// The "bake" section: OpenVDB volumes and meshes (bake.hpp, mesh.hpp).
struct BakeSettings {
    int resolution = 256;       ///< voxels across the largest side of the bounds
    std::optional<Box> bounds;  ///< default: the cube around the render bounds' sphere, clipped to the sphere
    double bandWidth = 3.0;     ///< half width of the level set's narrow band, in voxels
    std::vector<BakeGrid> grids{BakeGrid::Surface, BakeGrid::Density};
    double adaptivity = 0.0;    ///< mesh adaptivity 0..1 (OpenVDB volumeToMesh): 0 = uniform quads
    bool meshColors = true;     ///< vertex colours from the material's colouring
};

/// Keyframes: the parameter file's "animation" section (README "Animation").
enum class Interpolation {
    Linear,  ///< straight line to the next key
    Smooth   ///< monotone cubic: smooth through the keys, never overshooting them
};
struct Keyframe {
    double frame = 1.0;
    std::vector<double> value;  ///< 8 numbers for fractal.c, 1 otherwise
    Interpolation interpolation = Interpolation::Linear;  ///< from this key to the next
};
/// What a track animates.
enum class AnimatedValue { Constant, Iterations, Bailout, RotationDegrees };
struct Track {
    AnimatedValue target = AnimatedValue::Constant;
    int rotation = 0;             ///< for RotationDegrees: the index into slice.rotations
    std::vector<Keyframe> keys;   ///< at least one, frames strictly increasing
};

struct Params {
    std::string description;  ///< free text, kept on round trips (examples say what they show)
    Fractal fractal;
    SliceSpec slice;
    std::optional<Bounds> bounds;  ///< default: containingBounds(fractal, slice)
    Camera camera;
    std::vector<Light> lights{Light{{0.6, 0.8, 0.7}, {1.0, 0.96, 0.9}, 1.0},
                              Light{{-0.7, 0.2, -0.5}, {0.55, 0.65, 0.9}, 0.35}};
    Material material;
    RenderSettings render;
    OutputSettings output;
    BakeSettings bake;
    std::vector<Track> animation;  ///< empty: nothing is animated
};

/// A bad parameter: `key` is the dotted path ("fractal.iterations"), `what()` the full message.
class DQJ_API ParamError : public std::runtime_error {
public:
    ParamError(std::string key, const std::string& message);
    const std::string& key() const { return key_; }

private:
    std::string key_;
};

enum class Validation { Full, TypesOnly };

/// What a writer does with an existing file at its path: replace it atomically, or keep it
/// and fail (also when the file appears while the work runs; the CLI without --force).
enum class Existing { Replace, Keep };

/// Checks, before long work, that `path` can be written: a new or regular file (not a folder,
/// device, FIFO or socket), not existing when `existing` is Keep, in a folder where a file can
/// really be created (tried, so read-only and special file systems fail now). Throws
/// std::runtime_error ("cannot write 'path': reason").
DQJ_API void checkWritable(const std::string& path, Existing existing = Existing::Replace);

/// The largest parameter document read (16 MiB) and the deepest nesting of arrays and objects
/// in it (64 levels; the format needs 4).
inline constexpr std::size_t kMaxParamsBytes = 16u << 20;
inline constexpr int kMaxParamsDepth = 64;

/// Parses a parameter document: types, ranges and key names always; the cross-field rules of
/// validate() too unless `validation` is TypesOnly (for callers that override values first,
/// such as the CLI's flags, and validate afterwards). `source` names the document in messages.
/// Missing keys keep their defaults. Throws ParamError.
DQJ_API Params parseParams(const std::string& jsonText, const std::string& source = "parameters",
                           Validation validation = Validation::Full);
/// Reads and parses a file. Throws ParamError (also for a missing or unreadable file).
DQJ_API Params loadParams(const std::string& path, Validation validation = Validation::Full);
/// The complete document for `params` (every key written), which parseParams reads back.
DQJ_API std::string toJson(const Params& params);
/// Writes toJson(params) to `path` through a temporary file in the same folder, so a failure
/// never leaves a partial file. Throws std::runtime_error naming the path.
DQJ_API void saveParams(const Params& params, const std::string& path, Existing existing = Existing::Replace);
/// Checks the cross-field rules (bailout >= r_K, non-degenerate slice, camera, ...). Throws ParamError.
DQJ_API void validate(const Params& params);

DQJ_API std::string_view coloringName(Coloring coloring);
DQJ_API std::string_view normalMethodName(NormalMethod method);
DQJ_API std::string_view imageFormatName(ImageFormat format);
/// The format for a path: from `output.format` if set, else from its extension (.png, .exr).
DQJ_API ImageFormat formatFor(const OutputSettings& output);

/// The parameters at `frame`: every animated value replaced by its track's value there (before
/// the first key the first value holds, after the last the last); iterations round to the
/// nearest whole number. Not validated: call validate() on the result. Without tracks, a copy.
DQJ_API Params atFrame(const Params& params, double frame);
/// "fractal.c", "fractal.iterations", "fractal.bailout" or "slice.rotations[i].degrees".
DQJ_API std::string trackKey(const Track& track);
DQJ_API std::string_view bakeGridName(BakeGrid grid);
DQJ_API bool hasGrid(const BakeSettings& bake, BakeGrid grid);

}  // namespace dqj
