// dqjulia/povray.hpp - POV-Ray scenes that draw what `dqjulia render` draws, and DF3 density grids.
//
// The scenes #include "dqjulia.inc" (povray/dqjulia.inc in the source tree, embedded in the
// library so the copy written beside a scene always matches), which evaluates the core's
// distance estimate in POV-Ray's function machine as a chain of N + 2 functions. A scene holds
// the fractal as an isosurface, the core renderer's camera, lights, Phong material, colouring
// and background. Coordinates: the slice space is right-handed, POV-Ray's left-handed; scenes
// negate z (slice point (x, y, z) is POV-Ray <x, y, -z>), for the object, camera and lights alike.
//
// A DF3 grid samples the 3-D distance estimate on a cube around the bounds; a scene drawing it
// (function { pattern { density_file df3 ... } } in an isosurface) renders heavy settings
// (large N) fast, at the grid's resolution.
// Cost: a scene is text, written instantly; a grid costs resolution^3 distance estimates,
// spread over TBB threads.
#pragma once

#include <array>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "dqjulia/export.h"
#include "dqjulia/params.hpp"
#include "dqjulia/progress.hpp"

namespace dqj {

/// The text of dqjulia.inc this library was built with.
DQJ_API std::string_view povrayInclude();

/// A cube of samples of the 3-D distance estimate (DE / stretch), clamped to [0, maxDistance]
/// and stored as fractions of maxDistance: 0 inside the finite-N set, 1 at maxDistance or more
/// (and for a zero derivative). Sample (i, j, k) sits at POV-Ray point lower + spacing * (i, j, k).
struct DensityGrid {
    int resolution = 0;         ///< samples along each axis
    glm::dvec3 lower{0.0};      ///< POV-Ray coordinates of sample (0, 0, 0)
    double spacing = 0.0;       ///< distance between neighbouring samples, scene units
    double maxDistance = 0.0;   ///< the distance a stored 1 stands for, scene units
    std::vector<float> values;  ///< resolution^3 fractions in [0, 1], x fastest, then y, then z
    /// Bound on the gradient of the grid's trilinear interpolation, in stored units per scene
    /// unit (from each cell's largest edge differences along each axis): the isosurface's max_gradient.
    double maxGradient = 0.0;
};

/// The DF3 grid's limits: samples per axis (a 512^3 grid holds 134 million samples) and the
/// bits a sample may have.
inline constexpr int kMinDf3Resolution = 2, kMaxDf3Resolution = 512;
inline constexpr std::array<int, 3> kDf3Bits{8, 16, 32};

/// Samples the parameter set's distance estimate on a resolution^3 grid over the cube around
/// the render bounds. Throws ParamError for invalid parameters or a resolution outside
/// [2, 512] (a 512^3 grid holds 134 million samples), Cancelled if `progress` returned false.
DQJ_API DensityGrid bakeDensityGrid(const Params& params, int resolution, const ProgressCallback& progress = {});

/// Writes a DF3 file: three big-endian 16-bit sizes, then the samples as big-endian unsigned
/// integers of `bits` (8, 16 or 32) bits, x fastest. Written to a temporary file and renamed.
/// Throws std::invalid_argument for other bit depths, std::runtime_error if it cannot write.
DQJ_API void writeDf3(const DensityGrid& grid, const std::string& path, int bits = 16,
                      Existing existing = Existing::Replace);

struct PovraySceneOptions {
    std::string includeName = "dqjulia.inc";  ///< as written in #include
    std::string sourceName;                   ///< where the parameters came from, for the header comment
    /// When set, the scene draws this DF3 file (as named in the scene) sampled from `grid`
    /// instead of evaluating the distance estimate.
    std::string df3Name;
    const DensityGrid* grid = nullptr;
};

/// The povray command line that renders a scene as `dqjulia render` would: the image size,
/// S x S samples a pixel (+A0.0 +AM1 +R<S>) and an sRGB file, e.g.
/// "povray +W640 +H480 +A0.0 +AM1 +R2 File_Gamma=sRGB +Iscene.pov".
DQJ_API std::string povrayCommand(const Params& params, const std::string& scene);

/// A complete scene (camera, lights, material, background, the fractal) for the parameter set.
/// A slice proven empty (inspect.hpp) gives a scene without the fractal and a comment saying
/// why. Throws ParamError for invalid parameters.
DQJ_API std::string povrayScene(const Params& params, const PovraySceneOptions& options = {});

struct PovrayWriteOptions {
    bool copyInclude = true;  ///< also write dqjulia.inc beside the scene (unless an identical copy is there)
    bool df3 = false;         ///< also bake <scene>.df3 and write <scene>_df3.pov drawing it
    int df3Resolution = 128;
    int df3Bits = 16;
    std::string sourceName;                 ///< for the scenes' header comment
    Existing existing = Existing::Replace;  ///< replace existing files, or keep them and fail
};

/// The files writePovray() writes for `scenePath`; an empty path is not written. The scene is
/// skipped when N is beyond the include's limit (1000) and a DF3 grid replaces it.
struct PovrayFiles {
    std::string scene;     ///< the scene evaluating the distance estimate
    std::string df3;       ///< <scene>.df3
    std::string df3Scene;  ///< <scene>_df3.pov, drawing the grid
    std::string include;   ///< dqjulia.inc beside the scene
};
DQJ_API PovrayFiles povrayFiles(const Params& params, const std::string& scenePath,
                                const PovrayWriteOptions& options = {});

/// Writes the files of povrayFiles() (the include only if it is missing or differs from
/// povrayInclude()), all of them or none: every text is built and the grid baked first, every
/// file written to a temporary file, and only then are they renamed into place; if one cannot
/// be, those already renamed are withdrawn (and the files they replaced put back). Returns the
/// paths written.
/// Throws ParamError (bad parameters or options), Cancelled, std::runtime_error (writing).
DQJ_API std::vector<std::string> writePovray(const Params& params, const std::string& scenePath,
                                             const PovrayWriteOptions& options = {},
                                             const ProgressCallback& progress = {});

}  // namespace dqj
