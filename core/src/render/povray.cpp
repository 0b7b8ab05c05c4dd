// POV-Ray scenes and DF3 grids (povray.hpp). The scene mirrors the renderer (render.cpp): the same
// bounds, camera frame, hit threshold, lights, Phong terms, colouring and background, with z
// negated because POV-Ray is left-handed.
#include "dqjulia/povray.hpp"
#include "dqjulia/version.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "files/atomic_file.hpp"
#include "dqjulia/coloring.hpp"
#include "dqjulia/inspect.hpp"
#include "dqjulia/render.hpp"
#include "platform/platform.hpp"
#include "platform/parallel_progress.hpp"
#include "files/text_input.hpp"

namespace dqj {

// Generated at build time from povray/dqjulia.inc (core/CMakeLists.txt).
extern const char* const kPovrayIncludeText;

namespace {

/// dqjulia.inc limits N to this (DQJ_Max_Iterations): one nested function call per iteration,
/// and POV-Ray's function machine allows a call depth of 1024.
constexpr int kPovrayMaxIterations = 1000;

/// The largest 3-D distance a DF3 sample holds, in grid spacings: enough for the interpolated
/// field to be distance-like around the surface, small enough to keep 16-bit resolution there.
constexpr double kDensityRangeSpacings = 4.0;

/// A number as POV-Ray reads it back exactly (17 significant digits), without "-0".
std::string number(double value) {
    if (value == 0.0) return "0";
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", value);
    return text;
}

/// The same, shortened for comments and colours where exactness does not matter.
std::string shortNumber(double value) {
    if (value == 0.0 || std::abs(value) < 1e-12) return "0";
    char text[40];
    std::snprintf(text, sizeof text, "%.6g", value);
    return text;
}

std::string vector3(const glm::dvec3& v, bool exact = true) {
    auto format = exact ? number : shortNumber;
    std::string text = "<";  // appended, not operator+: GCC 12 warns falsely (-Wrestrict) on the latter
    text += format(v.x);
    text += ", ";
    text += format(v.y);
    text += ", ";
    text += format(v.z);
    text += ">";
    return text;
}

/// Slice coordinates to POV-Ray coordinates (and back): z is negated.
glm::dvec3 toPov(const glm::dvec3& v) { return {v.x, v.y, -v.z}; }

std::string array8(const Vec8& values) {
    std::string text = "{";
    for (int index = 0; index < 8; ++index) text += (index ? ", " : "") + number(values[index]);
    return text + "}";
}

/// POV-Ray string literal contents: quotes and backslashes escaped, no line breaks.
std::string povString(std::string_view text) {
    std::string out;
    for (char c : text) {
        if (c == '"' || c == '\\') out += '\\';
        out += (c == '\n' || c == '\r') ? ' ' : c;
    }
    return out;
}

/// Text as "// " comment lines of at most about 92 columns.
std::string commentBlock(std::string_view text) {
    std::string out;
    std::istringstream words{std::string(text)};
    words.exceptions(std::ios::badbit);  // memory running out ends the loop with bad_alloc, not as the text's end
    std::string word;
    std::string line = "//";
    while (words >> word) {
        if (line.size() + 1 + word.size() > 92 && line != "//") {
            out += line + "\n";
            line = "//";
        }
        line += " " + word;
    }
    if (line != "//") out += line + "\n";
    return out;
}

/// Within a cell, the trilinear interpolant's derivative along x is a bilinear blend of the
/// differences along the cell's four x edges, so it is at most the largest of them (per
/// spacing); likewise for y and z. The bound is the largest root sum of squares over the cells.
double interpolationGradientBound(const DensityGrid& grid) {
    const std::size_t n = static_cast<std::size_t>(grid.resolution);
    auto at = [&](std::size_t i, std::size_t j, std::size_t k) { return double(grid.values[(k * n + j) * n + i]); };
    double largest = 0.0;
    for (std::size_t k = 0; k + 1 < n; ++k)
        for (std::size_t j = 0; j + 1 < n; ++j)
            for (std::size_t i = 0; i + 1 < n; ++i) {
                double gx = 0.0, gy = 0.0, gz = 0.0;
                for (std::size_t a = 0; a < 2; ++a)
                    for (std::size_t b = 0; b < 2; ++b) {
                        gx = std::max(gx, std::abs(at(i + 1, j + a, k + b) - at(i, j + a, k + b)));
                        gy = std::max(gy, std::abs(at(i + a, j + 1, k + b) - at(i + a, j, k + b)));
                        gz = std::max(gz, std::abs(at(i + a, j + b, k + 1) - at(i + a, j + b, k)));
                    }
                largest = std::max(largest, gx * gx + gy * gy + gz * gz);
            }
    return std::sqrt(largest) / grid.spacing;
}

ParamError iterationLimitError(int iterations) {
    return ParamError("fractal.iterations",
                      "fractal.iterations: a POV-Ray scene evaluates the distance estimate as a chain of one function "
                      "call per iteration, and POV-Ray allows a call depth of 1024, so N is at most " +
                          std::to_string(kPovrayMaxIterations) + " (N is " + std::to_string(iterations) +
                          "); bake a density grid instead (--df3)");
}

/// Everything the scene text needs, resolved once.
struct SceneFacts {
    Fractal fractal;
    Slice slice;
    Bounds bounds;
    CameraFrame camera;
    double stretch = 1.0;
    std::string emptyReason;
};

SceneFacts resolve(const Params& params) {
    validate(params);
    SceneFacts facts;
    facts.fractal = params.fractal;
    facts.slice = params.slice.effective();
    facts.emptyReason = provenEmptyReason(params);
    // As the renderer: a proven-empty slice may have no bounds; it draws the background only.
    facts.bounds = facts.emptyReason.empty() ? renderBounds(params) : params.bounds.value_or(Bounds{});
    facts.camera = frameCamera(params, facts.bounds);
    facts.stretch = stretchOf(facts.slice).max;
    return facts;
}


void writeHeader(std::ostringstream& out, const Params& params, const PovraySceneOptions& options,
                 const std::string& kind) {
    out << "// dqjulia scene for POV-Ray 3.7, written by `dqjulia povray` (dqjulia " << povString(DQJ_VERSION_STRING)
        << ")" << (options.sourceName.empty() ? "" : " from " + povString(options.sourceName)) << ".\n";
    if (!params.description.empty()) out << commentBlock(params.description);
    out << "//\n" << commentBlock(kind);
    out << "//\n// Render (" << options.includeName
        << " must be beside this file, in the folder povray runs in, or on the library path +L<dir>):\n//   "
        << povrayCommand(params, "<this file>") << " +O<image>.png\n"
        << "// (+A0.3 instead of +A0.0 +AM1 is much faster: it anti-aliases only where neighbours differ.)\n"
        << "// Other sizes work too (+W/+H): the view is framed for " << params.render.width << "x"
        << params.render.height << ", and the hit threshold follows the image height.\n"
        << "// Coordinates: the slice point (x, y, z) is POV-Ray <x, y, -z> (POV-Ray is left-handed).\n\n"
        << "#version 3.7;\n"
        << "global_settings { assumed_gamma 1.0 }  // linear colours, as the core renderer's\n\n"
        << "#include \"" << povString(options.includeName) << "\"\n\n";
}

void writeFractalDeclarations(std::ostringstream& out, const SceneFacts& facts) {
    const Fractal& fractal = facts.fractal;
    out << "// ---- The fractal: constant, variant, iterations, bailout and the slice (rotations applied)\n"
        << "#declare Fractal_C = array[8] " << array8(toVec8(fractal.c)) << ";\n"
        << "#declare Fractal_Variant = \"" << variantName(fractal.variant) << "\";\n"
        << "#declare Fractal_N = " << fractal.iterations << ";\n"
        << "#declare Fractal_R = " << number(fractal.bailout) << ";\n"
        << "#declare Fractal_Slice = array[4][8] {\n"
        << "  " << array8(facts.slice.origin) << ",  // origin\n"
        << "  " << array8(facts.slice.axes[0]) << ",  // x axis\n"
        << "  " << array8(facts.slice.axes[1]) << ",  // y axis\n"
        << "  " << array8(facts.slice.axes[2]) << "   // z axis\n"
        << "};\n"
        << "// The sphere rays start on (the core's render bounds), in POV-Ray coordinates.\n"
        << "#declare Fractal_Center = " << vector3(toPov(facts.bounds.center)) << ";\n"
        << "#declare Fractal_Radius = " << number(facts.bounds.radius) << ";\n\n";
}

void writeCamera(std::ostringstream& out, const SceneFacts& facts) {
    const CameraFrame& camera = facts.camera;
    out << "// ---- Camera: the core's frame (eye, forward, right, up; vertical field of view)\n"
        << "#declare Camera_Location = " << vector3(toPov(camera.eye)) << ";\n"
        << "#declare Camera_Tan_Half_Fov = " << number(camera.tanHalfFov) << ";\n"
        << "camera {\n"
        << "  perspective\n"
        << "  location Camera_Location\n"
        << "  direction " << vector3(toPov(camera.forward)) << "\n"
        << "  right " << vector3(toPov(camera.right)) << " * 2 * Camera_Tan_Half_Fov * image_width / image_height\n"
        << "  up " << vector3(toPov(camera.up)) << " * 2 * Camera_Tan_Half_Fov\n"
        << "}\n\n";
}

void writeLights(std::ostringstream& out, const Params& params) {
    out << "// ---- Lights: directional (parallel), as the core's; POV-Ray's shadows are hard where the\n"
        << "// core's are soft, and the core's ambient occlusion has no counterpart here.\n";
    for (const Light& light : params.lights) {
        const double length = glm::length(light.direction);
        const glm::dvec3 radiance = light.color * light.intensity;
        if (!(length > 0.0) || !(radiance.x > 0.0 || radiance.y > 0.0 || radiance.z > 0.0)) continue;
        out << "light_source {\n"
            << "  Fractal_Center + 1000 * Fractal_Radius * " << vector3(toPov(light.direction / length)) << "\n"
            << "  color rgb " << vector3(radiance, false) << "\n"
            << "  parallel point_at Fractal_Center\n"
            << (params.material.shadows ? "" : "  shadowless\n") << "}\n";
    }
    out << "\n";
}

void writeBackground(std::ostringstream& out, const Params& params, const CameraFrame& camera) {
    const RenderSettings& render = params.render;
    out << "// ---- Background: the core's vertical gradient over the image (bottom to top)\n";
    if (render.backgroundTop == render.backgroundBottom) {
        out << "background { rgb " << vector3(render.backgroundTop, false) << " }\n\n";
        return;
    }
    const glm::dvec3 up = toPov(camera.up);
    const glm::dvec3 forward = toPov(camera.forward);
    out << "#declare Background_Mix = function {\n"
        << "  max(0, min(1, 0.5 + 0.5 * (x * " << number(up.x) << " + y * " << number(up.y) << " + z * " << number(up.z)
        << ")\n    / max(1e-9, x * " << number(forward.x) << " + y * " << number(forward.y) << " + z * "
        << number(forward.z) << ") / Camera_Tan_Half_Fov))\n"
        << "}\n"
        << "sky_sphere {\n"
        << "  pigment {\n"
        << "    function { Background_Mix(x, y, z) }\n"
        << "    color_map { [0 rgb " << vector3(render.backgroundBottom, false) << "] [1 rgb "
        << vector3(render.backgroundTop, false) << "] }\n"
        << "  }\n"
        << "}\n\n";
}

void writeTexture(std::ostringstream& out, const Params& params, bool chainAvailable) {
    const Material& material = params.material;
    out << "// ---- Material: the core's Phong terms (the paper's equation) and colouring (coloring.hpp)\n";
    const bool palette = material.coloring != Coloring::Solid && material.palette.size() > 1 && chainAvailable;
    if (palette) {
        out << "#declare Fractal_Palette = array[" << material.palette.size() << "] {";
        for (std::size_t index = 0; index < material.palette.size(); ++index)
            out << (index ? ", " : "") << vector3(material.palette[index]);
        out << "};\n";
    }
    // The surface's colour: the core's orbitColour (coloring.hpp) through the include's port of it.
    if (palette) {
        const char* name = material.coloring == Coloring::Trap ? "trap" : "iterations";
        out << "#declare Fractal_Pigment = DQJ_Orbit_Pigment(Fractal_C, Fractal_Variant, Fractal_N, Fractal_R, "
               "Fractal_Slice, \""
            << name << "\", Fractal_Palette);\n";
    } else {
        // Solid, or a palette of one colour: the colour every point gets. Beyond the include's N,
        // the palette's first colour stands in for the orbit colouring.
        const glm::dvec3 colour = material.coloring == Coloring::Solid ? material.color : paletteColour(material, 0.0);
        if (material.coloring != Coloring::Solid && material.palette.size() > 1 && !chainAvailable)
            out << "// N is beyond dqjulia.inc's limit: the orbit colouring is replaced by the palette's first "
                   "colour\n";
        out << "#declare Fractal_Pigment = pigment { rgb " << vector3(colour, false) << " };\n";
    }
    out << "#declare Fractal_Texture = texture {\n  pigment { Fractal_Pigment }\n";
    out << "  finish { ambient " << shortNumber(material.ambient) << " diffuse " << shortNumber(material.diffuse)
        << " phong " << shortNumber(material.specular) << " phong_size " << shortNumber(material.shininess) << " }\n"
        << "}\n\n";
}

std::string buildScene(const Params& params, const PovraySceneOptions& options) {
    const SceneFacts facts = resolve(params);
    const bool chainAvailable = facts.fractal.iterations <= kPovrayMaxIterations;
    const bool density = options.grid != nullptr;
    if (!density && !chainAvailable) throw iterationLimitError(facts.fractal.iterations);

    std::ostringstream out;
    writeHeader(out, params, options,
                density ? "The fractal is drawn from the density grid \"" + options.df3Name +
                              "\" (the core's distance estimate sampled on a cube): fast, at the grid's resolution."
                        : "The fractal is an isosurface of the core's distance estimate, evaluated by dqjulia.inc: "
                          "the surface `dqjulia render` draws for the same parameters.");
    writeFractalDeclarations(out, facts);
    writeCamera(out, facts);
    writeLights(out, params);
    writeBackground(out, params, facts.camera);
    if (!facts.emptyReason.empty()) {
        out << "// ---- No fractal: the slice is empty, as `dqjulia render` reports:\n"
            << commentBlock(facts.emptyReason);
        return out.str();
    }
    writeTexture(out, params, chainAvailable);

    const RenderSettings& render = params.render;
    // The core stops a ray where DE / stretch < detail * t * footprint, t the distance from the
    // eye and footprint = 2 tan(fov / 2) / height the pixel's size per unit distance.
    out << "// ---- The fractal\n"
        << "// Hit threshold per unit distance from the eye: `detail` pixel footprints, as the core's.\n"
        << "#declare Fractal_Pixel = " << number(render.detail) << " * 2 * Camera_Tan_Half_Fov / image_height;\n"
        << "#declare Fractal_View_Distance = vlength(Camera_Location - Fractal_Center);\n";
    const glm::dvec3 eye = toPov(facts.camera.eye);
    const std::string distanceFromEye = "sqrt((x - " + number(eye.x) + ") * (x - " + number(eye.x) + ") + (y - " +
                                        number(eye.y) + ") * (y - " + number(eye.y) + ") + (z - " + number(eye.z) +
                                        ") * (z - " + number(eye.z) + "))";
    if (!density) {
        out << "// The 3-D distance estimate (DE / stretch, capped at the core's max_step), minus the hit\n"
            << "// threshold at the point's distance from the eye: the surface is where it crosses 0.\n"
            << "#declare Fractal_Distance = DQJ_Scene_Function(Fractal_C, Fractal_Variant, Fractal_N, Fractal_R, "
               "Fractal_Slice, "
            << number(render.maxStep) << ");\n"
            << "#declare Fractal_Surface = function { Fractal_Distance(x, y, z) - Fractal_Pixel * " << distanceFromEye
            << " }\n"
            << "// max_gradient: the DE is a lower bound on the distance (gradient 1 for a true distance);\n"
            << "// 1 / step_factor is the core's safety margin, plus the threshold term's gradient.\n"
            << "// accuracy: one pixel footprint at the object, the core's step for central-difference normals.\n"
            << "object {\n"
            << "  DQJ_Isosurface_Custom(Fractal_Surface, Fractal_Center, Fractal_Radius, 0,\n"
            << "                        " << number(1.0 / render.stepFactor)
            << " + Fractal_Pixel, Fractal_Pixel * Fractal_View_Distance)\n"
            << "  texture { Fractal_Texture }\n"
            << "}\n";
    } else {
        const DensityGrid& grid = *options.grid;
        const double extent = grid.spacing * grid.resolution;  // the pattern's unit cube, in scene units
        // The grid smooths the surface to its spacing: draw where the sampled distance is about
        // half a spacing (or the image's hit threshold, if larger).
        out << "// The density pattern maps the unit cube to the grid: sample i sits at i / resolution.\n"
            << "#declare Fractal_Density = function { pattern { density_file df3 \"" << povString(options.df3Name)
            << "\" interpolate 1 } }\n"
            << "#declare Fractal_Grid_Lower = " << vector3(grid.lower) << ";\n"
            << "#declare Fractal_Grid_Extent = " << number(extent) << ";  // " << grid.resolution
            << " samples, spacing " << shortNumber(grid.spacing) << "\n"
            << "#declare Fractal_Grid_Range = " << number(grid.maxDistance)
            << ";  // the 3-D distance a stored 1 stands for\n"
            << "#declare Fractal_Grid_Surface = function {\n"
            << "  Fractal_Density((x - " << number(grid.lower.x) << ") / Fractal_Grid_Extent, (y - "
            << number(grid.lower.y) << ") / Fractal_Grid_Extent,\n"
            << "                  (z - " << number(grid.lower.z) << ") / Fractal_Grid_Extent)\n"
            << "}\n"
            << "#declare Fractal_Grid_Threshold = max(0.5 * " << number(grid.spacing)
            << ", Fractal_Pixel * Fractal_View_Distance) / Fractal_Grid_Range;\n"
            << "// max_gradient: a bound on the slope of the grid's trilinear interpolation over every cell,\n"
            << "// plus a margin for the samples' rounding to 8 bits. POV-Ray may advise a smaller value at the\n"
            << "// end of a render: it reports the steepest slope along the rays it traced, not over the grid.\n"
            << "object {\n"
            << "  DQJ_Isosurface_Custom(Fractal_Grid_Surface, Fractal_Center, Fractal_Radius, Fractal_Grid_Threshold,\n"
            << "                        " << number(grid.maxGradient + std::sqrt(3.0) / 255.0 / grid.spacing) << ", "
            << number(grid.spacing / 8.0) << ")\n"
            << "  texture { Fractal_Texture }\n"
            << "}\n";
    }
    return out.str();
}

}  // namespace

std::string_view povrayInclude() { return kPovrayIncludeText; }

std::string povrayCommand(const Params& params, const std::string& scene) {
    std::string command =
        "povray +W" + std::to_string(params.render.width) + " +H" + std::to_string(params.render.height);
    command += params.render.samples > 1 ? " +A0.0 +AM1 +R" + std::to_string(params.render.samples) : " -A";
    return command + " File_Gamma=sRGB +I" + scene;
}

std::string povrayScene(const Params& params, const PovraySceneOptions& options) { return buildScene(params, options); }

DensityGrid bakeDensityGrid(const Params& params, int resolution, const ProgressCallback& progress) {
    if (resolution < kMinDf3Resolution || resolution > kMaxDf3Resolution)
        throw ParamError("df3.resolution",
                         "the density grid's resolution must be from 2 to 512 samples per axis, got " +
                             std::to_string(resolution));
    const SceneFacts facts = resolve(params);
    DensityGrid grid;
    grid.resolution = resolution;
    const glm::dvec3 center = toPov(facts.bounds.center);
    grid.lower = center - glm::dvec3(facts.bounds.radius);
    grid.spacing = 2.0 * facts.bounds.radius / (resolution - 1);
    grid.maxDistance = kDensityRangeSpacings * grid.spacing;
    const std::size_t n = static_cast<std::size_t>(resolution);
    grid.values.assign(n * n * n, 1.0f);
    if (!facts.emptyReason.empty()) {
        if (progress && !progress(1.0)) throw Cancelled();
        return grid;  // nothing inside: every sample is far
    }
    const Fractal fractal = facts.fractal;
    const Slice slice = facts.slice;
    const double stretch = facts.stretch;
    parallelForWithProgress(n, progress, [&](std::size_t k, const std::atomic<bool>& stop) {
        for (std::size_t j = 0; j < n && !stop.load(std::memory_order_relaxed); ++j) {
            for (std::size_t i = 0; i < n; ++i) {
                const glm::dvec3 pov = grid.lower + grid.spacing * glm::dvec3(double(i), double(j), double(k));
                const Escape escape = evaluate(fractal, slice.map(toPov(pov)));
                double value = 0.0;
                if (escape.n != 0) {
                    const double distance = escape.de / stretch;  // +inf for a zero derivative
                    value = std::isfinite(distance) ? std::min(distance / grid.maxDistance, 1.0) : 1.0;
                }
                grid.values[(k * n + j) * n + i] = static_cast<float>(value);
            }
        }
    });
    grid.maxGradient = interpolationGradientBound(grid);
    return grid;
}

namespace {

/// The DF3 file's bytes into `file` (see writeDf3).
void writeDf3To(const DensityGrid& grid, AtomicFile& file, int bits) {
    if (bits != 8 && bits != 16 && bits != 32)
        throw std::invalid_argument("DF3 samples are 8, 16 or 32 bits, got " + std::to_string(bits));
    if (grid.resolution < 1 || grid.resolution > 65535 ||
        grid.values.size() != std::size_t(grid.resolution) * grid.resolution * grid.resolution)
        throw std::invalid_argument("DF3: the grid's size does not match its resolution");
    const int bytes = bits / 8;
    const double maximum = bits == 32 ? 4294967295.0 : double((1u << bits) - 1u);
    std::vector<unsigned char> data;
    data.reserve(6 + grid.values.size() * bytes);
    for (int axis = 0; axis < 3; ++axis) {
        data.push_back(static_cast<unsigned char>(grid.resolution >> 8));
        data.push_back(static_cast<unsigned char>(grid.resolution & 0xff));
    }
    for (float value : grid.values) {
        const double clamped = std::clamp(double(value), 0.0, 1.0);
        const auto code = static_cast<std::uint32_t>(std::lround(clamped * maximum));
        for (int byte = bytes - 1; byte >= 0; --byte) data.push_back(static_cast<unsigned char>(code >> (8 * byte)));
    }
    file.stream().write(reinterpret_cast<const char*>(data.data()), static_cast<std::streamsize>(data.size()));
}

}  // namespace

void writeDf3(const DensityGrid& grid, const std::string& path, int bits, Existing existing) {
    AtomicFile file(path, existing);
    writeDf3To(grid, file, bits);
    file.commit();
}

PovrayFiles povrayFiles(const Params& params, const std::string& scenePath, const PovrayWriteOptions& options) {
    namespace fs = std::filesystem;
    const fs::path scene = platform::pathFromUtf8(scenePath);
    if (scenePath.empty() || !scene.has_filename())
        throw std::runtime_error(AtomicFile::failureMessage(scenePath, "not a file name"));
    const fs::path folder = scene.parent_path();
    const std::string stem = platform::utf8FromPath(folder / scene.stem());
    if (params.fractal.iterations > kPovrayMaxIterations && !options.df3)
        throw iterationLimitError(params.fractal.iterations);
    PovrayFiles files;
    if (params.fractal.iterations <= kPovrayMaxIterations) files.scene = scenePath;
    if (options.df3) {
        files.df3 = stem + ".df3";
        files.df3Scene = stem + "_df3.pov";
        // The DF3 scene names the grid file in a POV-Ray string, which carries printable
        // ASCII only (POV-Ray 3.7 reads strings as ASCII; quotes and backslashes are escapes).
        const std::string df3Name = platform::utf8FromPath(platform::pathFromUtf8(files.df3).filename());
        for (const char ch : df3Name)
            if (ch < 0x20 || ch > 0x7e || ch == '"' || ch == '\\')
                throw ParamError("output.path", "'" + inputExcerpt(scenePath) +
                                                    "': with --df3 the scene names the grid file '" +
                                                    inputExcerpt(df3Name) +
                                                    "' in a POV-Ray string, which carries only printable ASCII "
                                                    "characters without \" and \\; rename the scene");
    }
    if (options.copyInclude) files.include = platform::utf8FromPath(folder / "dqjulia.inc");
    return files;
}

std::vector<std::string> writePovray(const Params& params, const std::string& scenePath,
                                     const PovrayWriteOptions& options, const ProgressCallback& progress) {
    if (options.df3 && std::find(kDf3Bits.begin(), kDf3Bits.end(), options.df3Bits) == kDf3Bits.end())
        throw ParamError("df3.bits", "DF3 samples are 8, 16 or 32 bits, got " + std::to_string(options.df3Bits));
    const PovrayFiles files = povrayFiles(params, scenePath, options);

    PovraySceneOptions sceneOptions;
    sceneOptions.includeName = "dqjulia.inc";
    sceneOptions.sourceName = options.sourceName;
    // Build every text first, so bad parameters fail before anything is written.
    std::string sceneText;
    if (!files.scene.empty()) sceneText = povrayScene(params, sceneOptions);
    DensityGrid grid;
    std::string df3SceneText;
    if (options.df3) {
        grid = bakeDensityGrid(params, options.df3Resolution, progress);
        PovraySceneOptions df3Options = sceneOptions;
        df3Options.df3Name = platform::utf8FromPath(platform::pathFromUtf8(files.df3).filename());
        df3Options.grid = &grid;
        df3SceneText = povrayScene(params, df3Options);
    }

    // Every file written before the first gets its name: all of them or none (AtomicFileSet).
    AtomicFileSet set(options.existing);
    if (!files.scene.empty()) set.add(files.scene).stream() << sceneText;
    if (options.df3) {
        writeDf3To(grid, set.add(files.df3), options.df3Bits);
        set.add(files.df3Scene).stream() << df3SceneText;
    }
    if (!files.include.empty()) {
        if (fileHolds(files.include, povrayInclude()) != true) set.add(files.include).stream() << povrayInclude();
    }
    set.commit();
    return set.paths();
}

}  // namespace dqj
