// scene.hpp - what a render resolves once and every ray reads: the fractal, the slice, the
// camera framing the bounds, the material, the lights, the hit threshold and the background
// (internal to the renderer: included by render.cpp alone, in an anonymous namespace as when it
// was part of that file, so the compiler inlines it into the tile loop as before). Cost: built
// once per render.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include <glm/geometric.hpp>

#include "dqjulia/coloring.hpp"
#include "dqjulia/render.hpp"
#include "render/camera.hpp"

namespace dqj {
namespace {

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();
inline constexpr double kFootprintFloor = 1e-7;

/// What the renderer reads of an evaluation: Escape without the exit state, small enough to pass
/// around by the million.
struct Probe {
    int n = 0;
    double r = 0.0;
    double ra = 0.0;
    double rb = 0.0;
    double de = 0.0;
    double trap = 0.0;

    static Probe of(const Escape& escape) { return {escape.n, escape.r, escape.ra, escape.rb, escape.de, escape.trap}; }
    Escape escape() const {
        Escape escape;
        escape.n = n;
        escape.r = r;
        escape.ra = ra;
        escape.rb = rb;
        escape.de = de;
        escape.trap = trap;
        return escape;
    }
};

/// Everything a ray needs, resolved once per render.
class Scene {
public:
    /// `empty`: the slice is proven empty (inspect.hpp), so no ray hits; its DE could still stop
    /// rays near the other part's set, and its bounds may not exist.
    Scene(const Params& params, bool empty)
        : fractal_(params.fractal),
          slice_(params.slice.effective()),
          material_(params.material),
          settings_(params.render),
          bounds_(empty ? params.bounds.value_or(Bounds{}) : renderBounds(params)),
          empty_(empty) {
        camera_ = frameCamera(params, bounds_);
        stretch_ = stretchOf(slice_).max;
        footprint_ = 2.0 * camera_.tanHalfFov / camera_.height;
        samples_ = std::max(1, settings_.samples);
        // The derivative before escape is at most (2 R)^N (each factor 2 |a_k| with |a_k| <= R),
        // and the kernel carries it squared, (2 R)^2N: the float kernel only where that stays
        // below float's largest value, 2^128, with room to spare (2^120), and
        // where the start points, c and their squares do too (an infinite square gives NaNs,
        // which never escape: a false hit).
        const double reach = stretch_ * (glm::length(bounds_.center) + bounds_.radius);  // of any point, in 8-D
        double largest = 0.0;
        for (int k = 0; k < 8; ++k)
            largest = std::max({largest, std::abs(slice_.origin[k]) + reach, std::abs(component(fractal_.c, k))});
        floatKernel_ =
            2.0 * fractal_.iterations * std::log2(2.0 * std::max(fractal_.bailout, 1.0)) < 120.0 && largest < 1e15;
        analytic_ = settings_.normals == NormalMethod::Analytic ||
                    (settings_.normals == NormalMethod::Auto && fractal_.variant == Variant::Dual);
        for (int axis = 0; axis < 3; ++axis) {
            const Vec8& a = slice_.axes[axis];
            realAxes_[axis] = makeQuat(a[0], a[1], a[2], a[3]);
        }
        for (const Light& light : params.lights) {
            const double length = glm::length(light.direction);
            const glm::dvec3 radiance = light.color * light.intensity;
            if (length > 0.0 && (radiance.x > 0.0 || radiance.y > 0.0 || radiance.z > 0.0))
                lights_.push_back({light.direction / length, radiance});
        }
        // Occlusion probes reach 5 * 2% of the bounds' radius: about the size of the bulbs of a
        // typical set, so creases darken while flat parts stay lit.
        occlusionDelta_ = 0.02 * bounds_.radius;
    }

    const CameraFrame& camera() const { return camera_; }
    const Bounds& bounds() const { return bounds_; }
    int samples() const { return samples_; }
    std::size_t lightCount() const { return lights_.size(); }

    /// Hit threshold at distance t from the eye: `detail` pixel footprints.
    double epsilon(double t) const { return std::max(settings_.detail * t * footprint_, kFootprintFloor); }

    Escape evaluateAt(const glm::dvec3& p) const { return evaluate(fractal_, slice_.map(p)); }

    /// The DE as a 3-D distance; 0 inside, +inf for a zero derivative.
    double distance3(int n, double de) const { return n == 0 ? 0.0 : de / stretch_; }
    double distance3(const Probe& escape) const { return distance3(escape.n, escape.de); }

    const Slice& slice() const { return slice_; }
    const Fractal& fractal() const { return fractal_; }
    /// Whether the packet engine may evaluate in float (the derivative cannot overflow).
    bool floatKernel() const { return floatKernel_; }

    glm::dvec3 baseColour(const Escape& escape) const { return orbitColour(material_, fractal_, escape); }

    /// Vertical gradient over the image: bottom colour at the bottom edge, top at the top.
    glm::dvec3 background(const glm::dvec3& direction) const {
        return backgroundAt(glm::dot(direction, camera_.up) / glm::dot(direction, camera_.forward));
    }
    /// The same for the rays through the image plane's row at `y` (screenY()): the gradient
    /// depends on the row only (equal to background() up to rounding), so a tile's pixels that
    /// trace no ray take it per row, without a direction each.
    glm::dvec3 backgroundAt(double y) const {
        const double mix = std::clamp(0.5 + 0.5 * (y / camera_.tanHalfFov), 0.0, 1.0);
        return settings_.backgroundBottom * (1.0 - mix) + settings_.backgroundTop * mix;
    }

private:
    friend class RayJob;

    struct ResolvedLight {
        glm::dvec3 direction;
        glm::dvec3 radiance;
    };

    Fractal fractal_;
    Slice slice_;
    Material material_;
    RenderSettings settings_;
    Bounds bounds_;
    bool empty_ = false;
    CameraFrame camera_;
    double stretch_ = 1.0;
    double footprint_ = 1e-3;
    int samples_ = 1;
    bool floatKernel_ = false;
    bool analytic_ = false;
    Quat realAxes_[3];
    std::vector<ResolvedLight> lights_;
    double occlusionDelta_ = 0.02;
};

}  // namespace
}  // namespace dqj
