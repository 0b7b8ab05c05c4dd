// dqjulia/render.hpp - the sphere-tracing renderer.
// Code: core/src/render/render.cpp (render) and camera.cpp (frameCamera, rayDirection).
//
// Rays start where they enter the bounding sphere (radius r_K, math.md) and step by
// stepFactor * min(DE / stretch, maxStep) until the DE falls below the pixel footprint
// (times `detail`). Shading: Phong (the paper's equation, several lights) and orbit colouring
// from coloring.hpp, ambient occlusion and soft shadows from the DE, background gradient,
// samples x samples anti-aliasing. Work is split in tiles over TBB threads; the rays of a tile
// march together, their points evaluated many at a time by the SIMD batch kernel (batch.hpp).
// Cost: about width * height * samples^2 * (steps per ray) * N quaternion iterations.
#pragma once

#include <cstdint>
#include <string>

#include <glm/vec3.hpp>

#include "dqjulia/export.h"
#include "dqjulia/image.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/progress.hpp"

namespace dqj {

/// The camera resolved against the bounds (renderBounds, slice.hpp): eye, orthonormal frame and field of view.
struct CameraFrame {
    glm::dvec3 eye{0.0};
    glm::dvec3 forward{0.0, 0.0, -1.0};
    glm::dvec3 right{1.0, 0.0, 0.0};
    glm::dvec3 up{0.0, 1.0, 0.0};
    double tanHalfFov = 0.36;
    int width = 1;
    int height = 1;
    /// Unit direction of the ray through image position (px, py) in pixels, (0,0) = top-left corner.
    DQJ_API glm::dvec3 rayDirection(double px, double py) const;
};

DQJ_API CameraFrame frameCamera(const Params& params, const Bounds& bounds);

struct RenderStats {
    std::uint64_t rays = 0;
    std::uint64_t steps = 0;      ///< sphere-tracing steps over all rays
    std::uint64_t hitPixels = 0;  ///< pixels with at least one sample on the surface
    /// Fractal evaluations over all rays: marching (with the cone pre-pass), bisection, normals,
    /// occlusion and shadow probes
    std::uint64_t evaluations = 0;
    double seconds = 0.0;
};

struct RenderResult {
    Image image;
    RenderStats stats;
    /// Why no pixel shows the surface (stats.hitPixels == 0): the slice's proven emptiness
    /// (provenEmptyReason), else inspect()'s reason from sampling; "" when pixels were hit or no
    /// reason is known. emptyResultMessage (empty_result.hpp) words it.
    std::string emptyReason;
};

/// How the renderer evaluates the fractal. Both run the same marching and shading logic.
enum class RenderEngine {
    Packet,  ///< the rays of a tile together, through the SIMD batch kernel (batch.hpp); the default
    Scalar   ///< one point at a time with evaluate(): the reference the packet engine is tested against
};

/// Renders the parameter set. A slice proven empty (provenEmptyReason in inspect.hpp) renders
/// as background only. Throws ParamError for invalid parameters, Cancelled if
/// `progress` returned false.
DQJ_API RenderResult render(const Params& params, const ProgressCallback& progress = {},
                            RenderEngine engine = RenderEngine::Packet);

}  // namespace dqj
