// The sphere-tracing renderer (render.hpp): camera, marching, normals, shading, tiles.
//
// All geometry is in slice (3-D) coordinates. The distance estimate is in 8-D units; a 3-D
// step of length s moves at most stretch.max * s in 8-D, so DE / stretch.max is a safe 3-D step.
#include "dqjulia/render.hpp"
#include "dqjulia/inspect.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <limits>
#include <numbers>
#include <sstream>
#include <vector>

#include <glm/geometric.hpp>

#include "parallel_progress.hpp"

namespace dqj {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr int kTileSize = 16;
constexpr int kOcclusionSamples = 5;
constexpr int kShadowSteps = 64;     // soft shadows are a look, not a measurement: cap their cost
constexpr int kBisectionSteps = 8;   // refines a step that landed inside to 1/256 of the step
constexpr double kFootprintFloor = 1e-7;

/// Where a ray meets a sphere: [near, far] along the ray, or nothing.
struct Interval {
    bool valid = false;
    double near = 0.0;
    double far = 0.0;
};

Interval intersectSphere(const glm::dvec3& origin, const glm::dvec3& direction, const Bounds& bounds) {
    const glm::dvec3 offset = origin - bounds.center;
    const double b = glm::dot(offset, direction);
    const double c = glm::dot(offset, offset) - bounds.radius * bounds.radius;
    const double discriminant = b * b - c;
    if (discriminant < 0.0) return {};
    const double root = std::sqrt(discriminant);
    if (-b + root < 0.0) return {};  // the sphere is behind the origin
    return {true, std::max(0.0, -b - root), -b + root};
}

/// Result of marching one ray.
struct Trace {
    bool hit = false;
    double t = kInfinity;
    Escape escape;          ///< at the hit point (outside the finite-N set when refined)
    bool cutFace = false;   ///< started inside the set on the bounding sphere (a clipped set)
    int steps = 0;
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
        // Trap colouring: the orbit's closest approach to 0 ranges over [0, r_K(c_a)] and is
        // mostly below half of it on the surface; scaling by r_K/2 spreads the default set's
        // values over the whole palette.
        trapScale_ = 0.65 * containmentRadius(fractal_.c.a);
    }

    const CameraFrame& camera() const { return camera_; }
    int samples() const { return samples_; }

    /// Hit threshold at distance t from the eye: `detail` pixel footprints.
    double epsilon(double t) const { return std::max(settings_.detail * t * footprint_, kFootprintFloor); }

    Escape evaluateAt(const glm::dvec3& p) const { return evaluate(fractal_, slice_.map(p)); }

    /// The DE as a 3-D distance; 0 inside, +inf for a zero derivative.
    double distance3(const Escape& escape) const { return escape.n == 0 ? 0.0 : escape.de / stretch_; }

    Trace march(const glm::dvec3& origin, const glm::dvec3& direction) const {
        Trace trace;
        const Interval span = intersectSphere(origin, direction, bounds_);
        if (!span.valid || empty_) return trace;
        double t = span.near;
        double previousT = t;
        Escape previous;
        bool havePrevious = false;
        double step3 = kInfinity;
        double eps = epsilon(t);
        for (int step = 0; step < settings_.maxSteps; ++step) {
            const Escape escape = evaluateAt(origin + t * direction);
            ++trace.steps;
            eps = epsilon(t);
            if (escape.n == 0) {
                trace.hit = true;
                if (!havePrevious) {
                    trace.t = t;
                    trace.escape = escape;
                    trace.cutFace = step == 0 && bounds_.clipped && span.near > 0.0;
                    return trace;
                }
                // The step jumped over the surface of the finite-N set (the DE bounds the
                // distance to the limit set, math.md): bisect back to the last point outside.
                double outside = previousT;
                double inside = t;
                for (int k = 0; k < kBisectionSteps; ++k) {
                    const double middle = 0.5 * (outside + inside);
                    const Escape probe = evaluateAt(origin + middle * direction);
                    if (probe.n == 0) {
                        inside = middle;
                    } else {
                        outside = middle;
                        previous = probe;
                    }
                }
                trace.t = outside;
                trace.escape = previous;
                return trace;
            }
            step3 = escape.de / stretch_;
            if (!std::isfinite(step3)) step3 = settings_.maxStep;  // zero derivative: largest step
            if (step3 < eps) {
                trace.hit = true;
                trace.t = t;
                trace.escape = escape;
                return trace;
            }
            previousT = t;
            previous = escape;
            havePrevious = true;
            t += settings_.stepFactor * std::min(step3, settings_.maxStep);
            if (t > span.far) return trace;
        }
        // Out of steps: close enough to count, or give up.
        if (havePrevious && step3 < 10.0 * eps) {
            trace.hit = true;
            trace.t = previousT;
            trace.escape = previous;
        }
        return trace;
    }

    glm::dvec3 normalAt(const glm::dvec3& p, const glm::dvec3& direction, const Trace& trace, double eps) const {
        glm::dvec3 gradient(0.0);
        if (trace.cutFace) {
            gradient = p - bounds_.center;  // the sphere clips the set: its face is the surface
        } else if (analytic_) {
            gradient = realPartGradient(fractal_, slice_.map(p).a, realAxes_);
        } else {
            // Central differences of the DE; where one side is inside (DE clamped to 0, not
            // negative) a one-sided difference from the hit point avoids bending the normal.
            const double h = std::max(eps, 1e-6);
            const double here = distance3(trace.escape);
            for (int axis = 0; axis < 3; ++axis) {
                glm::dvec3 offset(0.0);
                offset[axis] = h;
                const Escape plus = evaluateAt(p + offset);
                const Escape minus = evaluateAt(p - offset);
                const double dPlus = distance3(plus);
                const double dMinus = distance3(minus);
                if (plus.n != 0 && minus.n != 0) {
                    gradient[axis] = (dPlus - dMinus) / (2.0 * h);
                } else if (plus.n != 0) {
                    gradient[axis] = (dPlus - here) / h;
                } else if (minus.n != 0) {
                    gradient[axis] = (here - dMinus) / h;
                }
            }
        }
        const double length = glm::length(gradient);
        glm::dvec3 normal = length > 0.0 && std::isfinite(length) ? gradient / length : -direction;
        if (glm::dot(normal, direction) > 0.0) normal = -normal;  // face the camera
        return normal;
    }

    glm::dvec3 palette(double value) const {
        const auto& colours = material_.palette;
        if (colours.empty()) return material_.color;
        if (colours.size() == 1 || !(value > 0.0)) return colours.front();
        if (value >= 1.0) return colours.back();
        const double position = value * static_cast<double>(colours.size() - 1);
        const auto index = static_cast<std::size_t>(position);
        const double fraction = position - static_cast<double>(index);
        return colours[index] * (1.0 - fraction) + colours[index + 1] * fraction;
    }

    glm::dvec3 baseColour(const Escape& escape) const {
        switch (material_.coloring) {
            case Coloring::Solid: return material_.color;
            case Coloring::Iterations: {
                if (escape.n == 0 || !(escape.r > 1.0)) return palette(1.0);
                // Smooth escape count: the fraction of an iteration by which r overshot R.
                const double smooth = escape.n + 1.0 - std::log2(std::log(escape.r) / std::log(fractal_.bailout));
                return palette(smooth / fractal_.iterations);
            }
            case Coloring::Trap: return palette(escape.trap / trapScale_);
        }
        return material_.color;
    }

    /// 1 = open, 0 = fully occluded. Compares the DE at probes along the normal with their
    /// height above the surface; the DE is about half the true distance (exactly half for the
    /// ball, c = 0), so 2 * DE is the estimate of the free distance.
    double occlusion(const glm::dvec3& p, const glm::dvec3& normal) const {
        if (material_.occlusion <= 0.0) return 1.0;
        double sum = 0.0;
        double weight = 0.5;
        double totalWeight = 0.0;
        for (int i = 1; i <= kOcclusionSamples; ++i, weight *= 0.5) {
            const double height = i * occlusionDelta_;
            const double free = std::min(2.0 * distance3(evaluateAt(p + normal * height)), height);
            sum += weight * (height - free) / height;
            totalWeight += weight;
        }
        return std::clamp(1.0 - material_.occlusion * sum / totalWeight, 0.0, 1.0);
    }

    /// Soft shadow towards a directional light: 0 = blocked, 1 = lit; penumbra from the
    /// closest miss along the way (k * d / t).
    double shadow(const glm::dvec3& p, const glm::dvec3& normal, const glm::dvec3& toLight, double eps) const {
        const glm::dvec3 origin = p + normal * (2.0 * eps);
        const Interval span = intersectSphere(origin, toLight, bounds_);
        if (!span.valid) return 1.0;
        double result = 1.0;
        double t = 2.0 * eps;
        for (int step = 0; step < kShadowSteps && t < span.far; ++step) {
            const Escape escape = evaluateAt(origin + t * toLight);
            if (escape.n == 0) return 0.0;
            double d = escape.de / stretch_;
            if (!std::isfinite(d)) d = settings_.maxStep;
            if (d < 0.25 * eps) return 0.0;
            result = std::min(result, material_.shadowSoftness * d / t);
            t += std::clamp(settings_.stepFactor * d, eps, settings_.maxStep);
        }
        return std::clamp(result, 0.0, 1.0);
    }

    /// Phong (the paper's equation) with occlusion on the ambient term and soft shadows.
    glm::dvec3 shade(const glm::dvec3& p, const glm::dvec3& normal, const glm::dvec3& direction,
                     const Escape& escape, double eps) const {
        const glm::dvec3 base = baseColour(escape);
        const double open = occlusion(p, normal);
        glm::dvec3 colour = material_.ambient * open * base;
        const glm::dvec3 toEye = -direction;
        const double diffuseOcclusion = 0.7 + 0.3 * open;  // creases also lose some direct light
        for (const auto& light : lights_) {
            const double facing = glm::dot(normal, light.direction);
            if (facing <= 0.0) continue;
            const double lit = material_.shadows ? shadow(p, normal, light.direction, eps) : 1.0;
            if (lit <= 0.0) continue;
            const glm::dvec3 reflected = 2.0 * facing * normal - light.direction;
            const double highlight = std::pow(std::max(0.0, glm::dot(reflected, toEye)), material_.shininess);
            colour += (material_.diffuse * facing * diffuseOcclusion * base + material_.specular * highlight) *
                      light.radiance * lit;
        }
        return colour;
    }

    /// Vertical gradient over the image: bottom colour at the bottom edge, top at the top.
    glm::dvec3 background(const glm::dvec3& direction) const {
        const double height = glm::dot(direction, camera_.up) / glm::dot(direction, camera_.forward) / camera_.tanHalfFov;
        const double mix = std::clamp(0.5 + 0.5 * height, 0.0, 1.0);
        return settings_.backgroundBottom * (1.0 - mix) + settings_.backgroundTop * mix;
    }

private:
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
    bool analytic_ = false;
    Quat realAxes_[3];
    std::vector<ResolvedLight> lights_;
    double occlusionDelta_ = 0.02;
    double trapScale_ = 1.0;
};

struct TileStats {
    std::uint64_t rays = 0;
    std::uint64_t steps = 0;
    std::uint64_t hitPixels = 0;
};

TileStats renderTile(const Scene& scene, int x0, int y0, int x1, int y1, Image& image) {
    TileStats stats;
    const CameraFrame& camera = scene.camera();
    const int samples = scene.samples();
    const double weight = 1.0 / (samples * samples);
    for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; ++x) {
            glm::dvec3 colour(0.0);
            glm::dvec3 surfaceColour(0.0);
            glm::dvec3 normalSum(0.0);
            double depth = kInfinity;
            int hits = 0;
            for (int sy = 0; sy < samples; ++sy) {
                for (int sx = 0; sx < samples; ++sx) {
                    // A regular grid of sub-pixel positions; with one sample, the pixel centre.
                    const double px = x + (sx + 0.5) / samples;
                    const double py = y + (sy + 0.5) / samples;
                    const glm::dvec3 direction = camera.rayDirection(px, py);
                    const Trace trace = scene.march(camera.eye, direction);
                    ++stats.rays;
                    stats.steps += trace.steps;
                    if (!trace.hit) {
                        colour += scene.background(direction);
                        continue;
                    }
                    const glm::dvec3 p = camera.eye + trace.t * direction;
                    const double eps = scene.epsilon(trace.t);
                    const glm::dvec3 normal = scene.normalAt(p, direction, trace, eps);
                    const glm::dvec3 shaded = scene.shade(p, normal, direction, trace.escape, eps);
                    colour += shaded;
                    surfaceColour += shaded;
                    normalSum += normal;
                    depth = std::min(depth, trace.t);
                    ++hits;
                }
            }
            const std::size_t pixel = static_cast<std::size_t>(y) * image.width + x;
            colour *= weight;
            surfaceColour *= weight;
            for (int channel = 0; channel < 3; ++channel)
                image.surface[3 * pixel + channel] = static_cast<float>(surfaceColour[channel]);
            image.rgba[4 * pixel + 0] = static_cast<float>(colour.x);
            image.rgba[4 * pixel + 1] = static_cast<float>(colour.y);
            image.rgba[4 * pixel + 2] = static_cast<float>(colour.z);
            image.rgba[4 * pixel + 3] = static_cast<float>(hits * weight);
            image.depth[pixel] = static_cast<float>(depth);
            const double length = glm::length(normalSum);
            const glm::dvec3 normal = length > 0.0 ? normalSum / length : glm::dvec3(0.0);
            for (int axis = 0; axis < 3; ++axis) image.normal[3 * pixel + axis] = static_cast<float>(normal[axis]);
            if (hits > 0) ++stats.hitPixels;
        }
    }
    return stats;
}

}  // namespace

glm::dvec3 CameraFrame::rayDirection(double px, double py) const {
    const double aspect = static_cast<double>(width) / height;
    const double x = (2.0 * px / width - 1.0) * tanHalfFov * aspect;
    const double y = (1.0 - 2.0 * py / height) * tanHalfFov;  // image rows go down, `up` goes up
    return glm::normalize(forward + x * right + y * up);
}

Bounds renderBounds(const Params& params) {
    if (params.bounds) return *params.bounds;
    const Slice slice = params.slice.effective();
    const auto bounds = containingBounds(params.fractal, slice);
    if (bounds) return *bounds;
    std::ostringstream message;
    message << std::setprecision(4) << "slice: the slice misses the containment region (every orbit with |a| > r_K = "
            << containmentRadius(params.fractal.c.a) << " escapes";
    if (params.fractal.variant != Variant::Dual)
        message << ", and every orbit with |b| > r_K = " << containmentRadius(params.fractal.c.b);
    message << "), so the set is empty in this slice whatever the iteration count; move the slice origin "
               "closer to 0 or set explicit \"bounds\"";
    throw ParamError("slice", message.str());
}

CameraFrame frameCamera(const Params& params, const Bounds& bounds) {
    const Camera& camera = params.camera;
    CameraFrame frame;
    frame.width = std::max(1, params.render.width);
    frame.height = std::max(1, params.render.height);
    const double halfFov = 0.5 * camera.fovDegrees * std::numbers::pi / 180.0;
    frame.tanHalfFov = std::tan(halfFov);
    const glm::dvec3 target = camera.target.value_or(bounds.center);
    if (camera.position) {
        frame.eye = *camera.position;
    } else {
        // Fit the bounding sphere in the narrower of the two fields of view, with 8% margin.
        const double aspect = static_cast<double>(frame.width) / frame.height;
        const double halfHorizontal = std::atan(frame.tanHalfFov * aspect);
        const double distance = bounds.radius / std::sin(std::min(halfFov, halfHorizontal)) * 1.08;
        const double length = glm::length(camera.direction);
        const glm::dvec3 away = length > 0.0 ? camera.direction / length : glm::dvec3(0.0, 0.0, 1.0);
        frame.eye = target + away * distance;
    }
    const glm::dvec3 view = target - frame.eye;
    frame.forward = glm::length(view) > 0.0 ? glm::normalize(view) : glm::dvec3(0.0, 0.0, -1.0);
    // If `up` is (nearly) along the view, any other up gives a valid frame: take the world
    // axis least aligned with the view.
    glm::dvec3 up = camera.up;
    if (!(glm::length(glm::cross(frame.forward, up)) > 1e-9 * glm::length(up))) {
        const glm::dvec3 f = glm::abs(frame.forward);
        up = f.x <= f.y && f.x <= f.z ? glm::dvec3(1, 0, 0) : (f.y <= f.z ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, 1));
    }
    frame.right = glm::normalize(glm::cross(frame.forward, up));
    frame.up = glm::cross(frame.right, frame.forward);
    return frame;
}

RenderResult render(const Params& params, const ProgressCallback& progress) {
    validate(params);
    const auto start = std::chrono::steady_clock::now();
    const Scene scene(params, !provenEmptyReason(params).empty());

    RenderResult result;
    Image& image = result.image;
    image.width = scene.camera().width;
    image.height = scene.camera().height;
    const std::size_t pixels = static_cast<std::size_t>(image.width) * image.height;
    image.rgba.assign(4 * pixels, 0.0f);
    image.surface.assign(3 * pixels, 0.0f);
    image.depth.assign(pixels, std::numeric_limits<float>::infinity());
    image.normal.assign(3 * pixels, 0.0f);

    const int tilesX = (image.width + kTileSize - 1) / kTileSize;
    const int tilesY = (image.height + kTileSize - 1) / kTileSize;
    std::atomic<std::uint64_t> rays{0};
    std::atomic<std::uint64_t> steps{0};
    std::atomic<std::uint64_t> hitPixels{0};
    parallelForWithProgress(
        static_cast<std::size_t>(tilesX) * tilesY, progress, [&](std::size_t index, const std::atomic<bool>&) {
            const int x0 = static_cast<int>(index % tilesX) * kTileSize;
            const int y0 = static_cast<int>(index / tilesX) * kTileSize;
            const TileStats tile = renderTile(scene, x0, y0, std::min(x0 + kTileSize, image.width),
                                              std::min(y0 + kTileSize, image.height), image);
            rays += tile.rays;
            steps += tile.steps;
            hitPixels += tile.hitPixels;
        });

    result.stats.rays = rays;
    result.stats.steps = steps;
    result.stats.hitPixels = hitPixels;
    result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

}  // namespace dqj
