// dqjulia/param_types.hpp - the parameter set shared by the whole toolkit: what the parameter
// file holds, as C++ values with their defaults. The defaults here are the only ones: the
// schema (schema.hpp), the file's writer and the Blender add-on take them from these structs.
// Code: core/src/params/param_types.cpp.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "dqjulia/estimate.hpp"
#include "dqjulia/export.h"
#include "dqjulia/keyframes.hpp"
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
    std::optional<glm::dvec3> target;       ///< default: the centre of the bounds
    glm::dvec3 direction{0.55, 0.45, 1.0};  ///< from target towards the camera, for auto framing
    glm::dvec3 up{0.0, 1.0, 0.0};
    double fovDegrees = 40.0;  ///< vertical field of view
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
    int samples = 2;          ///< anti-aliasing: samples x samples rays per pixel
    double stepFactor = 0.9;  ///< fraction of the distance estimate taken per step
    double maxStep = 0.25;    ///< largest step, in slice units
    int maxSteps = 400;
    double detail = 1.0;                        ///< hit threshold in pixel footprints (smaller = finer)
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

/// The grids a bake can write (bake.grids). docs/baking.md says what each holds.
enum class BakeGrid { Surface, Density, Color, Trap, Iterations };

/// The "bake" section: OpenVDB volumes and meshes (bake.hpp, mesh.hpp).
struct BakeSettings {
    int resolution = 256;       ///< voxels across the largest side of the bounds
    std::optional<Box> bounds;  ///< default: the cube around the render bounds' sphere, clipped to the sphere
    double bandWidth = 3.0;     ///< half width of the level set's narrow band, in voxels
    std::vector<BakeGrid> grids{BakeGrid::Surface, BakeGrid::Density, BakeGrid::Color};
    double adaptivity = 0.0;  ///< mesh adaptivity 0..1 (OpenVDB volumeToMesh): 0 = uniform quads
    bool meshColors = true;   ///< vertex colours from the material's colouring
    /// Meshes: at most this many triangles (a quad counts as two), by the least adaptivity that
    /// meets it (mesh_simplify.hpp); 0 = no limit (bake.adaptivity applies).
    int maxFaces = 0;
    /// How deep inside the attribute grids (color, trap, iterations) reach, as a fraction of the
    /// resolution (the bake's largest side): 0.02 = 5 voxels at 256, 20 at 1024; at least the band.
    double colorDepth = 0.02;
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

DQJ_API std::string_view coloringName(Coloring coloring);
DQJ_API std::string_view normalMethodName(NormalMethod method);
DQJ_API std::string_view imageFormatName(ImageFormat format);
/// The format for a path: from `output.format` if set, else from its extension (.png, .exr).
DQJ_API ImageFormat formatFor(const OutputSettings& output);

DQJ_API std::string_view bakeGridName(BakeGrid grid);
DQJ_API bool hasGrid(const BakeSettings& bake, BakeGrid grid);

}  // namespace dqj
