// The sphere-tracing renderer (render.hpp): camera, marching, normals, shading, tiles.
//
// All geometry is in slice (3-D) coordinates. The distance estimate is in 8-D units; a 3-D
// step of length s moves at most stretch.max * s in 8-D, so DE / stretch.max is a safe 3-D step.
//
// Each camera ray is a RayJob: a state machine that asks for the points it needs evaluated
// (marching, bisection, normal and occlusion probes, shadow marches) and consumes their
// escapes. The packet engine runs the rays of a tile as a wavefront: each round the queries of
// every unfinished ray go through the SIMD batch kernel together and finished rays retire. The
// scalar engine answers each query with evaluate(), the reference; both run the same logic.
// The packet engine uses the float kernel (twice the lanes) where its derivative cannot
// overflow: the points it evaluates stay about a hit threshold (a fraction of a pixel) from
// the surface or more, where the float orbit's error, 2^-24 times the derivative (batch.hpp),
// moves the DE by a small fraction of that threshold.
#include "dqjulia/render.hpp"
#include "dqjulia/batch.hpp"
#include "dqjulia/coloring.hpp"
#include "dqjulia/inspect.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>

#include "platform/parallel_progress.hpp"
#include "platform/thread_scratch.hpp"

namespace dqj {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();
constexpr int kTileSize = 16;
constexpr int kOcclusionSamples = 5;
constexpr int kShadowSteps = 64;    // soft shadows are a look, not a measurement: cap their cost
/// Shadow marches step by this many DEs (over-relaxed; the DE is about half the distance) and
/// fall back to the plain step where two consecutive free balls do not overlap.
constexpr double kShadowRelaxation = 1.6;
constexpr int kBisectionSteps = 8;  // refines a step that landed inside to 1/256 of the step
constexpr double kFootprintFloor = 1e-7;
constexpr int kRaysPerPass = 1024;  // rays traced together: whole pixels of a tile
constexpr int kConeBlock = 4;       // pixels per side of the blocks a cone pre-pass marches for
/// A cone stops where its free margin (DE minus its radius) drops below this many hit
/// thresholds: its rays then start well before any point where they could stop.
constexpr double kConeMargin = 4.0;

/// The normal turned towards the eye. A gradient that tips past perpendicular to the ray (a
/// surface seen edge on, where the differences straddle a crease) is bent back onto the
/// silhouette, its component along the ray removed, not mirrored: mirroring turned a lit grazing
/// surface into a dark speckle one pixel wide. A normal pointing straight away becomes -ray.
glm::dvec3 facingRay(const glm::dvec3& normal, const glm::dvec3& direction) {
    const double along = glm::dot(normal, direction);
    if (along <= 0.0) return normal;
    const glm::dvec3 bent = normal - along * direction;
    const double length = glm::length(bent);
    return length > 1e-6 ? bent / length : -direction;
}

/// CameraFrame::rayDirection in parts: the image plane's x of a pixel column, its y of a row,
/// and the direction through (x, y). A tile works its columns and rows out once; the same
/// expressions give the same directions, bit for bit.
double screenX(const CameraFrame& camera, double px) {
    const double aspect = static_cast<double>(camera.width) / camera.height;
    return (2.0 * px / camera.width - 1.0) * camera.tanHalfFov * aspect;
}
double screenY(const CameraFrame& camera, double py) {
    return (1.0 - 2.0 * py / camera.height) * camera.tanHalfFov;  // image rows go down, `up` goes up
}
glm::dvec3 screenDirection(const CameraFrame& camera, double x, double y) {
    return glm::normalize(camera.forward + x * camera.right + y * camera.up);
}

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

/// 3-D points to evaluate, structure of arrays: mapping them to 8-D reads each coordinate
/// contiguously (vectorised loops), not every third double.
/// One count for the three arrays, which only grow: an append is one check and three stores.
class Points3 {
public:
    std::size_t size() const { return count_; }
    void clear() { count_ = 0; }
    void push_back(const glm::dvec3& p) {
        if (count_ == coords_[0].size()) grow();
        for (int axis = 0; axis < 3; ++axis) coords_[axis][count_] = p[axis];
        ++count_;
    }
    glm::dvec3 operator[](std::size_t i) const { return {coords_[0][i], coords_[1][i], coords_[2][i]}; }
    /// Coordinate `axis` of every point (size() of them).
    const double* coordinate(int axis) const { return coords_[axis].data(); }

private:
    // Out of line and rare, so that push_back stays small enough to inline into queries().
    void grow() {
        for (auto& coordinate : coords_) coordinate.resize(std::max<std::size_t>(64, 2 * count_));
    }

    std::array<std::vector<double>, 3> coords_;
    std::size_t count_ = 0;
};

/// Result of marching one ray.
struct Trace {
    bool hit = false;
    double t = kInfinity;
    Probe escape;          ///< at the hit point (outside the finite-N set when refined)
    bool cutFace = false;  ///< started inside the set on the bounding sphere (a clipped set)
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

/// A soft-shadow march towards one directional light: 0 = blocked, 1 = lit; penumbra from
/// the closest miss along the way (k * d / t). It starts from its ray's shadow origin and goes
/// along the light's direction (both the same for every light of a ray: not stored here).
struct ShadowMarch {
    double far = 0.0;
    double t = 0.0;
    double result = 1.0;
    double lit = 1.0;
    // Over-relaxation: the last point marched from, its DE and plain step, and whether the
    // step from it was the long one (checked when its point is answered).
    double previousT = 0.0;
    double previousD = 0.0;
    double plainStep = 0.0;
    int step = 0;
    bool done = true;
    bool relaxed = false;
};

/// One camera ray, from the eye to its shaded colour, as a state machine. Each stage names the
/// 3-D points whose escape it needs next (queries()) and moves on when given their escapes
/// (answer()): sphere tracing, bisecting back to the surface, the normal's probes (central
/// differences), the occlusion probes, and one soft-shadow march per lit light, side by side.
/// The scalar engine answers each query at once with evaluate(); the packet engine gathers the
/// queries of many rays and answers them together with the SIMD batch kernel (batch.hpp). Both
/// run this same logic, so their pictures differ only where the kernel's rounding (float, or the
/// double kernel's logarithm) tips a decision.
class RayJob {
public:
    /// A camera ray; `start`: where a cone pre-pass proved the way free (0: from the bounds).
    /// `shadows`: room for one shadow march per light of the scene, owned by the caller (a pool
    /// reused from pass to pass: no allocation per ray).
    RayJob(const Scene& scene, const glm::dvec3& direction, double start, ShadowMarch* shadows)
        : scene_(&scene), direction_(direction), shadows_(shadows) {
        span_ = intersectSphere(scene.camera_.eye, direction, scene.bounds_);
        if (!span_.valid || scene.empty_ || start > span_.far) {
            finishMarch();
            return;
        }
        seeded_ = start > span_.near;
        t_ = previousT_ = std::max(span_.near, start);
        stage_ = Stage::March;
    }

    /// A cone pre-pass: marches the cone of half-width `spread` * t around `axis` over
    /// [near, far] (its rays' spans) and stops where the set may come within reach of one of
    /// its rays; coneStart() is then where those rays may start marching (+inf: all miss).
    static RayJob cone(const Scene& scene, const glm::dvec3& axis, double spread, double near, double far) {
        RayJob job(scene, axis, kInfinity, nullptr);  // a miss: no stage yet; no shading
        job.cone_ = true;
        job.spread_ = spread;
        job.span_ = {true, near, far};
        job.t_ = near;
        job.coneStart_ = near;
        job.stage_ = scene.empty_ || !(near <= far) || !std::isfinite(near) ? Stage::Done : Stage::March;
        return job;
    }
    double coneStart() const { return coneStart_; }

    /// No more queries: finished, or paused before its shading (pausesBeforeShading()).
    bool done() const { return stage_ == Stage::Done || stage_ == Stage::Paused; }
    bool paused() const { return stage_ == Stage::Paused; }

    /// Goes on from the pause to its own occlusion and shadows.
    void resumeShading() {
        if (stage_ == Stage::Paused) beginShading();
    }

    /// Whether this paused sample may take the occlusion and shadows of `other`, a sample of the
    /// same pixel shaded already: both on one piece of surface (hit points within two hit
    /// thresholds, normals within 18 degrees) facing the same lights.
    bool canShareShading(const RayJob& other) const {
        if (!paused() || other.stage_ != Stage::Done || !other.trace_.hit) return false;
        const double reach = 2.0 * std::max(hitEps_, other.hitEps_);
        if (glm::length(p_ - other.p_) > reach || glm::dot(normal_, other.normal_) < 0.95) return false;
        for (const auto& light : scene_->lights_)
            if ((glm::dot(normal_, light.direction) > 0.0) != (glm::dot(other.normal_, light.direction) > 0.0))
                return false;
        return true;
    }

    /// Shades this paused sample with the occlusion and shadows of `other` (canShareShading()).
    void shareShading(const RayJob& other) {
        open_ = other.open_;
        std::copy(other.shadows_, other.shadows_ + scene_->lights_.size(), shadows_);
        finishShading();
    }
    const Trace& trace() const { return trace_; }
    /// The shaded colour for a hit, the background for a miss.
    const glm::dvec3& colour() const { return colour_; }
    const glm::dvec3& normal() const { return normal_; }

    /// Appends the points this ray needs evaluated next; returns how many (0 once done).
    std::size_t queries(Points3& points) const {
        const glm::dvec3& eye = scene_->camera_.eye;
        switch (stage_) {
            case Stage::March:
            case Stage::Recall: points.push_back(eye + t_ * direction_); return 1;
            case Stage::Bisect: points.push_back(eye + 0.5 * (outside_ + inside_) * direction_); return 1;
            case Stage::Normal:
                for (int axis = 0; axis < 3; ++axis) {
                    glm::dvec3 offset(0.0);
                    offset[axis] = h_;
                    points.push_back(p_ + offset);
                    points.push_back(p_ - offset);
                }
                return 6;
            case Stage::Occlusion:
                for (int i = 1; i <= kOcclusionSamples; ++i)
                    points.push_back(p_ + normal_ * (i * scene_->occlusionDelta_));
                return kOcclusionSamples;
            case Stage::Shadows: {
                std::size_t count = 0;
                const std::size_t lights = scene_->lights_.size();
                for (std::size_t index = 0; index < lights; ++index) {
                    const ShadowMarch& shadow = shadows_[index];
                    if (shadow.done) continue;
                    points.push_back(shadowOrigin_ + shadow.t * scene_->lights_[index].direction);
                    ++count;
                }
                return count;
            }
            case Stage::Paused:
            case Stage::Done: return 0;
        }
        return 0;
    }

    /// Takes the escapes of the points the last queries() named, in order, and moves on.
    /// `escapes[i]`: the Probe of the i-th point; `escapes.n(i)`, `escapes.de(i)`: its count and
    /// DE alone, all that most stages read (a view of Probes, or of the batch kernel's results
    /// read in place: no six fields converted where two are needed).
    template <class Escapes>
    void answer(const Escapes& escapes) {
        switch (stage_) {
            case Stage::March: answerMarch(escapes); return;
            case Stage::Bisect: answerBisect(escapes[0]); return;
            case Stage::Recall:
                trace_.escape = escapes[0];
                finishMarch();
                return;
            case Stage::Normal: answerNormal(escapes); return;
            case Stage::Occlusion: answerOcclusion(escapes); return;
            case Stage::Shadows: answerShadows(escapes); return;
            case Stage::Paused:
            case Stage::Done: return;
        }
    }

private:
    enum class Stage { March, Bisect, Recall, Normal, Occlusion, Shadows, Paused, Done };

    /// Sphere tracing: step by stepFactor * min(DE / stretch, maxStep) until the DE is below
    /// the hit threshold or the ray leaves the bounds.
    template <class Escapes>
    void answerMarch(const Escapes& escapes) {
        if (cone_) {
            answerCone(escapes.n(0), escapes.de(0));
            return;
        }
        const RenderSettings& settings = scene_->settings_;
        ++trace_.steps;
        const double eps = scene_->epsilon(t_);
        if (escapes.n(0) == 0) {
            trace_.hit = true;
            if (!havePrevious_) {
                trace_.t = t_;
                trace_.escape = escapes[0];
                trace_.cutFace = step_ == 0 && !seeded_ && scene_->bounds_.clipped && span_.near > 0.0;
                finishMarch();
                return;
            }
            // The step jumped over the surface of the finite-N set (the DE bounds the
            // distance to the limit set, math.md): bisect back to the last point outside.
            outside_ = previousT_;
            inside_ = t_;
            stage_ = Stage::Bisect;
            return;
        }
        double step3 = escapes.de(0) / scene_->stretch_;
        if (!std::isfinite(step3)) step3 = settings.maxStep;  // zero derivative: largest step
        if (step3 < eps) {
            trace_.hit = true;
            trace_.t = t_;
            trace_.escape = escapes[0];
            finishMarch();
            return;
        }
        // Only the last point's t is kept, not its escape (six fields copied every step): the
        // rare hits that need it (recall()) evaluate that point again, to the same result.
        previousT_ = t_;
        havePrevious_ = true;
        t_ += settings.stepFactor * std::min(step3, settings.maxStep);
        if (t_ > span_.far) {
            finishMarch();
            return;
        }
        if (++step_ == settings.maxSteps) {
            // Out of steps: close enough to count, or give up.
            if (step3 < 10.0 * eps) {
                recall(previousT_);
                return;
            }
            finishMarch();
        }
    }

    /// Cone marching (the pre-pass): every ray of the cone lies within spread * t of the axis,
    /// so the ball of radius DE around the axis point keeps it free for a step of
    /// (DE - spread * t) / (1 + spread), with the rays' step factor and largest step.
    void answerCone(int n, double de) {
        const RenderSettings& settings = scene_->settings_;
        double free = scene_->distance3(n, de);
        if (!std::isfinite(free)) free = settings.maxStep;  // zero derivative: as the rays do
        free -= spread_ * t_;
        coneStart_ = t_;
        if (n == 0 || free < kConeMargin * scene_->epsilon(t_) || ++step_ == settings.maxSteps) {
            stage_ = Stage::Done;
            return;
        }
        t_ += settings.stepFactor * std::min(free / (1.0 + spread_), settings.maxStep);
        if (t_ > span_.far) {
            coneStart_ = kInfinity;  // the cone leaves the bounds: every ray of it misses
            stage_ = Stage::Done;
        }
    }

    /// Halves [outside, inside] kBisectionSteps times; the hit is the last point outside.
    void answerBisect(const Probe& probe) {
        const double middle = 0.5 * (outside_ + inside_);
        if (probe.n == 0) {
            inside_ = middle;
        } else {
            outside_ = middle;
            trace_.escape = probe;
            bisectedOut_ = true;
        }
        if (++bisection_ == kBisectionSteps) {
            if (!bisectedOut_) {
                recall(outside_);  // every halving landed inside: the hit is the march's last point
                return;
            }
            trace_.t = outside_;
            finishMarch();
        }
    }

    /// A hit at `t`, a point the march evaluated before: its escape again (the same point gives
    /// the same result), then the normal.
    void recall(double t) {
        trace_.hit = true;
        trace_.t = t_ = t;
        stage_ = Stage::Recall;
    }

    /// A miss takes the background; a hit goes on to its normal.
    void finishMarch() {
        const Scene& scene = *scene_;
        if (!trace_.hit) {
            colour_ = scene.background(direction_);
            stage_ = Stage::Done;
            return;
        }
        p_ = scene.camera_.eye + trace_.t * direction_;
        hitEps_ = scene.epsilon(trace_.t);
        if (trace_.cutFace) {
            finishNormal(p_ - scene.bounds_.center);  // the sphere clips the set: its face is the surface
        } else if (scene.analytic_) {
            finishNormal(realPartGradient(scene.fractal_, scene.slice_.map(p_).a, scene.realAxes_));
        } else {
            h_ = std::max(hitEps_, 1e-6);
            stage_ = Stage::Normal;
        }
    }

    /// Central differences of the DE; where one side is inside (DE clamped to 0, not negative) a
    /// one-sided difference from the hit point avoids bending the normal.
    template <class Escapes>
    void answerNormal(const Escapes& probes) {
        const double here = scene_->distance3(trace_.escape);
        glm::dvec3 gradient(0.0);
        for (int axis = 0; axis < 3; ++axis) {
            const int plus = probes.n(2 * axis), minus = probes.n(2 * axis + 1);
            const double dPlus = scene_->distance3(plus, probes.de(2 * axis));
            const double dMinus = scene_->distance3(minus, probes.de(2 * axis + 1));
            if (plus != 0 && minus != 0) {
                gradient[axis] = (dPlus - dMinus) / (2.0 * h_);
            } else if (plus != 0) {
                gradient[axis] = (dPlus - here) / h_;
            } else if (minus != 0) {
                gradient[axis] = (here - dMinus) / h_;
            }
        }
        finishNormal(gradient);
    }

    void finishNormal(const glm::dvec3& gradient) {
        const double length = glm::length(gradient);
        normal_ = length > 0.0 && std::isfinite(length) ? gradient / length : -direction_;
        normal_ = facingRay(normal_, direction_);
        // With several samples a pixel, one of them shades first and the others may share its
        // occlusion and shadows (renderTile): they wait here.
        const Material& material = scene_->material_;
        if (scene_->samples_ > 1 && (material.occlusion > 0.0 || material.shadows) && !scene_->lights_.empty()) {
            stage_ = Stage::Paused;
            return;
        }
        beginShading();
    }

    void beginShading() {
        if (scene_->material_.occlusion > 0.0) {
            stage_ = Stage::Occlusion;
        } else {
            open_ = 1.0;
            startShadows();
        }
    }

    /// Ambient occlusion, 1 = open, 0 = fully occluded. Compares the DE at probes along the
    /// normal with their height above the surface; the DE is about half the true distance
    /// (exactly half for the ball, c = 0), so 2 * DE is the estimate of the free distance.
    template <class Escapes>
    void answerOcclusion(const Escapes& probes) {
        double sum = 0.0;
        double weight = 0.5;
        double totalWeight = 0.0;
        for (int i = 1; i <= kOcclusionSamples; ++i, weight *= 0.5) {
            const double height = i * scene_->occlusionDelta_;
            const double free = std::min(2.0 * scene_->distance3(probes.n(i - 1), probes.de(i - 1)), height);
            sum += weight * (height - free) / height;
            totalWeight += weight;
        }
        open_ = std::clamp(1.0 - scene_->material_.occlusion * sum / totalWeight, 0.0, 1.0);
        startShadows();
    }

    /// One shadow march for every light the surface faces (when shadows are on).
    void startShadows() {
        const Scene& scene = *scene_;
        std::fill(shadows_, shadows_ + scene.lights_.size(), ShadowMarch{});
        shadowOrigin_ = p_ + normal_ * (2.0 * hitEps_);
        bool marching = false;
        for (std::size_t index = 0; index < scene.lights_.size(); ++index) {
            const glm::dvec3& toLight = scene.lights_[index].direction;
            if (!scene.material_.shadows || glm::dot(normal_, toLight) <= 0.0) continue;
            ShadowMarch& shadow = shadows_[index];
            const Interval span = intersectSphere(shadowOrigin_, toLight, scene.bounds_);
            if (!span.valid) continue;
            shadow.far = span.far;
            shadow.t = 2.0 * hitEps_;
            shadow.done = !(kShadowSteps > 0 && shadow.t < shadow.far);
            marching = marching || !shadow.done;
        }
        if (marching) {
            stage_ = Stage::Shadows;
        } else {
            finishShading();
        }
    }

    template <class Escapes>
    void answerShadows(const Escapes& escapes) {
        const Scene& scene = *scene_;
        bool marching = false;
        std::size_t next = 0;  // the next escape: one per march still going, in light order
        for (std::size_t index = 0; index < scene.lights_.size(); ++index) {
            ShadowMarch& shadow = shadows_[index];
            if (shadow.done) continue;
            const int n = escapes.n(next);
            double d = escapes.de(next++) / scene.stretch_;
            if (!std::isfinite(d)) d = scene.settings_.maxStep;
            const bool blocked = n == 0 || d < 0.25 * hitEps_;
            if (shadow.relaxed && (blocked || shadow.t - shadow.previousT > shadow.previousD + d)) {
                // The long step may have passed an occluder (its free ball and the last one do
                // not overlap, or it landed on the set): take the plain step from the last point.
                shadow.t = shadow.previousT + shadow.plainStep;
                shadow.relaxed = false;
                shadow.done = !(++shadow.step < kShadowSteps && shadow.t < shadow.far);
            } else if (blocked) {
                shadow.result = 0.0;
                shadow.done = true;
            } else {
                shadow.result = std::min(shadow.result, scene.material_.shadowSoftness * d / shadow.t);
                const double plain = std::clamp(scene.settings_.stepFactor * d, hitEps_, scene.settings_.maxStep);
                const double relaxed = std::clamp(kShadowRelaxation * d, hitEps_, scene.settings_.maxStep);
                shadow.previousT = shadow.t;
                shadow.previousD = d;
                shadow.plainStep = plain;
                shadow.relaxed = relaxed > plain && shadow.t + relaxed < shadow.far;
                shadow.t += shadow.relaxed ? relaxed : plain;
                shadow.done = !(++shadow.step < kShadowSteps && shadow.t < shadow.far);
            }
            if (shadow.done) shadow.lit = std::clamp(shadow.result, 0.0, 1.0);
            marching = marching || !shadow.done;
        }
        if (!marching) finishShading();
    }

    /// Phong (the paper's equation, coloring.hpp) with occlusion on the ambient term and soft shadows.
    void finishShading() {
        const Scene& scene = *scene_;
        const Material& material = scene.material_;
        const glm::dvec3 base = scene.baseColour(trace_.escape.escape());
        glm::dvec3 colour = phongAmbient(material, base, open_);
        const glm::dvec3 toEye = -direction_;
        for (std::size_t index = 0; index < scene.lights_.size(); ++index) {
            const auto& light = scene.lights_[index];
            const double lit = material.shadows ? shadows_[index].lit : 1.0;
            if (lit <= 0.0) continue;
            colour += phongLight(material, base, normal_, light.direction, toEye, light.radiance, open_) * lit;
        }
        colour_ = colour;
        stage_ = Stage::Done;
    }

    const Scene* scene_;
    glm::dvec3 direction_;
    Stage stage_ = Stage::Done;
    bool seeded_ = false;  // starts where a cone stopped, not on the bounds
    bool cone_ = false;    // a cone of the pre-pass, not a camera ray
    double spread_ = 0.0;
    double coneStart_ = 0.0;
    Trace trace_;
    // Sphere tracing and bisection.
    Interval span_;
    double t_ = 0.0;
    double previousT_ = 0.0;
    bool havePrevious_ = false;
    bool bisectedOut_ = false;  // a halving landed outside: trace_.escape holds its escape
    int step_ = 0;
    double outside_ = 0.0;
    double inside_ = 0.0;
    int bisection_ = 0;
    // The surface point and its shading.
    glm::dvec3 p_{0.0};
    glm::dvec3 normal_{0.0};
    glm::dvec3 colour_{0.0};
    double hitEps_ = 0.0;
    double h_ = 0.0;  // central-difference step
    double open_ = 1.0;
    glm::dvec3 shadowOrigin_{0.0};    // where the shadow marches start: just off the surface
    ShadowMarch* shadows_ = nullptr;  // one per light (the caller's pool)
};

/// Answers the queries of ray jobs until every job is done: one query at a time with evaluate()
/// (the scalar engine, the reference), or the queries of all unfinished jobs together through
/// the SIMD batch kernel, round after round, finished jobs retiring (the packet engine).
/// Holds only buffers, so one per thread is reused from tile to tile.
class Evaluator {
public:
    /// Evaluations answered since the last call (all of them: rays, cones, shading).
    std::uint64_t takeEvaluations() { return std::exchange(evaluations_, 0); }

    void run(const Scene& scene, RenderEngine engine, std::vector<RayJob>& jobs) {
        if (engine == RenderEngine::Scalar) {
            for (RayJob& job : jobs) {
                while (!job.done()) {
                    points_.clear();
                    job.queries(points_);
                    evaluations_ += points_.size();
                    probes_.clear();
                    for (std::size_t i = 0; i < points_.size(); ++i)
                        probes_.push_back(Probe::of(scene.evaluateAt(points_[i])));
                    job.answer(ProbeEscapes{probes_.data()});
                }
            }
            return;
        }
        if (scene.floatKernel()) {
            runPackets(scene, jobs, floatBatch_);
        } else {
            runPackets(scene, jobs, batch_);
        }
    }

private:
    /// The packet engine with the kernel in T's precision.
    template <typename T>
    void runPackets(const Scene& scene, std::vector<RayJob>& jobs, BatchBuffer<T>& batch) {
        // Each job is visited once a round: it takes its answers and names its next queries at
        // once, into the other points buffer, while its state is at hand.
        active_.clear();
        points_.clear();
        counts_.clear();
        for (std::size_t index = 0; index < jobs.size(); ++index) {
            if (jobs[index].done()) continue;
            active_.push_back(index);
            counts_.push_back(jobs[index].queries(points_));
        }
        while (!active_.empty()) {
            evaluations_ += points_.size();
            evaluateBatch(scene, batch);
            nextPoints_.clear();
            std::size_t offset = 0;
            std::size_t kept = 0;
            for (std::size_t k = 0; k < active_.size(); ++k) {
                RayJob& job = jobs[active_[k]];
                job.answer(BatchEscapes<T>{&batch, offset});
                offset += counts_[k];
                if (job.done()) continue;
                active_[kept] = active_[k];
                counts_[kept++] = job.queries(nextPoints_);
            }
            active_.resize(kept);
            counts_.resize(kept);
            std::swap(points_, nextPoints_);
        }
    }

    /// points_ -> `batch`'s results through the SIMD kernel. The 8-D coordinates are Slice::map's
    /// expression, coordinate by coordinate, so they round the same; terms with a zero axis
    /// component are left out (they add a zero, which changes at most the sign of a zero).
    template <typename T>
    void evaluateBatch(const Scene& scene, BatchBuffer<T>& batch) {
        const std::size_t count = points_.size();
        const Slice& slice = scene.slice();
        batch.resize(count);
        const double* points[3] = {points_.coordinate(0), points_.coordinate(1), points_.coordinate(2)};
        if (constantsInFloat_ != std::is_same_v<T, float>) constants_.fill(0);  // the other buffer's
        constantsInFloat_ = std::is_same_v<T, float>;
        for (int k = 0; k < 8; ++k) {
            T* out = batch.start(k);
            const double origin = slice.origin[k];
            // A coordinate the slice does not move (5 of 8 on the usual slices) keeps its value
            // from round to round: the kernel only reads the start points, so only the entries
            // past those already holding this origin are written.
            constants_[k] = std::min(constants_[k], count);
            if (constants_[k] > 0 &&
                std::bit_cast<std::uint64_t>(constantOrigin_[k]) != std::bit_cast<std::uint64_t>(origin))
                constants_[k] = 0;
            // One pass a coordinate: origin + p[a] * scale over its nonzero axes, in axis order
            // (the same sums as adding one axis after the other).
            int axes[3];
            double scales[3];
            int terms = 0;
            for (int axis = 0; axis < 3; ++axis) {
                if (slice.axes[axis][k] == 0.0) continue;
                axes[terms] = axis;
                scales[terms++] = slice.axes[axis][k];
            }
            if (terms == 0) {
                std::fill(out + constants_[k], out + count, static_cast<T>(origin));
                constants_[k] = count;
                constantOrigin_[k] = origin;
                continue;
            }
            constants_[k] = 0;
            switch (terms) {
                case 1: {
                    const double* p0 = points[axes[0]];
                    for (std::size_t i = 0; i < count; ++i) out[i] = static_cast<T>(origin + p0[i] * scales[0]);
                    break;
                }
                case 2: {
                    const double *p0 = points[axes[0]], *p1 = points[axes[1]];
                    for (std::size_t i = 0; i < count; ++i)
                        out[i] = static_cast<T>(origin + p0[i] * scales[0] + p1[i] * scales[1]);
                    break;
                }
                default: {
                    const double *p0 = points[axes[0]], *p1 = points[axes[1]], *p2 = points[axes[2]];
                    for (std::size_t i = 0; i < count; ++i)
                        out[i] = static_cast<T>(origin + p0[i] * scales[0] + p1[i] * scales[1] + p2[i] * scales[2]);
                    break;
                }
            }
        }
        batch.evaluate(scene.fractal());
    }

    /// The scalar engine's escapes, as RayJob::answer reads them.
    struct ProbeEscapes {
        const Probe* probes;
        const Probe& operator[](std::size_t i) const { return probes[i]; }
        int n(std::size_t i) const { return probes[i].n; }
        double de(std::size_t i) const { return probes[i].de; }
    };

    /// The kernel's results from `first` on, read in place (RayJob::answer).
    template <typename T>
    struct BatchEscapes {
        const BatchBuffer<T>* batch;
        std::size_t first;
        Probe operator[](std::size_t i) const {
            const std::size_t j = first + i;
            return {batch->n(j), batch->r(j), batch->ra(j), batch->rb(j), batch->de(j), batch->trap(j)};
        }
        int n(std::size_t i) const { return batch->n(first + i); }
        double de(std::size_t i) const { return batch->de(first + i); }
    };

    Points3 points_;
    Points3 nextPoints_;                  // the next round's, filled while answering this one
    std::vector<Probe> probes_;           // the scalar engine's escapes
    std::vector<std::size_t> counts_;
    std::vector<std::size_t> active_;
    BatchBuffer<double> batch_;
    BatchBuffer<float> floatBatch_;
    // Per 8-D coordinate: how many leading start points hold constantOrigin_ (a coordinate the
    // slice does not move), still valid from the last round.
    std::array<std::size_t, 8> constants_{};
    std::array<double, 8> constantOrigin_{};
    bool constantsInFloat_ = false;  // which buffer constants_ describes
    std::uint64_t evaluations_ = 0;
};

struct TileStats {
    std::uint64_t rays = 0;
    std::uint64_t steps = 0;
    std::uint64_t hitPixels = 0;
    std::uint64_t evaluations = 0;
};

/// A thread's buffers for its tiles, kept from tile to tile (no allocation once they have
/// grown): render() keeps one per thread in a ThreadScratch.
struct TileBuffers {
    Evaluator evaluator;
    std::vector<RayJob> jobs;
    std::vector<ShadowMarch> shadowSlots;  // the jobs' shadow marches (RayJob's `shadows`)
    std::vector<double> columnX;           // image plane x of the tile's sub-pixel columns
    std::vector<double> rowY;              // and y of its rows
    std::vector<glm::dvec3> rowBackground;    // and the background of each row
    std::vector<glm::dvec3> pixelBackground;  // per pixel row: a pixel's colour if no sample hits
    std::vector<double> starts;            // per cone block: where its rays start (+inf: all miss)
    std::vector<std::size_t> firstJob;     // per pixel of the pass: its first job, or kNoJob
};

TileStats renderTile(const Scene& scene, RenderEngine engine, int x0, int y0, int x1, int y1, Image& image,
                     TileBuffers& buffers) {
    TileStats stats;
    const CameraFrame& camera = scene.camera();
    const int samples = scene.samples();
    const int perPixel = samples * samples;
    const double weight = 1.0 / perPixel;
    const int width = x1 - x0;
    const int pixels = width * (y1 - y0);
    // The tile's pixels go through in passes of about kRaysPerPass rays, whole pixels at a time.
    const int pixelsPerPass = std::max(1, kRaysPerPass / perPixel);
    Evaluator& evaluator = buffers.evaluator;
    std::vector<RayJob>& jobs = buffers.jobs;
    // Room for the shadow marches of a pass's rays: job k has the lights' slots from k * lights.
    std::vector<ShadowMarch>& shadowSlots = buffers.shadowSlots;
    const std::size_t lights = scene.lightCount();
    shadowSlots.resize(std::max(shadowSlots.size(), static_cast<std::size_t>(pixelsPerPass) * perPixel * lights));
    // A regular grid of sub-pixel positions; with one sample, the pixel centre. Their image
    // plane coordinates, per sub-pixel column and row of the tile, are worked out once.
    std::vector<double>& columnX = buffers.columnX;
    std::vector<double>& rowY = buffers.rowY;
    columnX.clear();
    rowY.clear();
    for (int x = x0; x < x1; ++x)
        for (int sx = 0; sx < samples; ++sx) columnX.push_back(screenX(camera, x + (sx + 0.5) / samples));
    for (int y = y0; y < y1; ++y)
        for (int sy = 0; sy < samples; ++sy) rowY.push_back(screenY(camera, y + (sy + 0.5) / samples));
    std::vector<glm::dvec3>& rowBackground = buffers.rowBackground;  // the background of each row
    rowBackground.clear();
    for (const double y : rowY) rowBackground.push_back(scene.backgroundAt(y));
    // What a pixel whose cone misses comes to, per pixel row: its samples' backgrounds summed
    // and weighted as its rays' colours would be (the same sums), worked out once a row.
    std::vector<glm::dvec3>& pixelBackground = buffers.pixelBackground;
    pixelBackground.clear();
    for (int y = y0; y < y1; ++y) {
        glm::dvec3 colour(0.0);
        for (int sample = 0; sample < perPixel; ++sample)
            colour += rowBackground[static_cast<std::size_t>(y - y0) * samples + sample / samples];
        pixelBackground.push_back(colour * weight);
    }
    auto sampleDirection = [&](int x, int y, int sx, int sy) {
        const int column = (x - x0) * samples + sx;
        const int row = (y - y0) * samples + sy;
        return screenDirection(camera, columnX[static_cast<std::size_t>(column)], rowY[static_cast<std::size_t>(row)]);
    };
    // The cone pre-pass: one cone around each block of kConeBlock^2 pixels finds how far all
    // their rays may go before they can come near the set.
    const int blocksX = (width + kConeBlock - 1) / kConeBlock;
    const int blocksY = (y1 - y0 + kConeBlock - 1) / kConeBlock;
    jobs.clear();
    for (int by = 0; by < blocksY; ++by) {
        for (int bx = 0; bx < blocksX; ++bx) {
            const int bx0 = x0 + bx * kConeBlock, by0 = y0 + by * kConeBlock;
            const int bx1 = std::min(x1, bx0 + kConeBlock), by1 = std::min(y1, by0 + kConeBlock);
            const glm::dvec3 axis = camera.rayDirection(0.5 * (bx0 + bx1), 0.5 * (by0 + by1));
            double spread = 0.0;  // the farthest corner: a ray at t is within spread * t of the axis
            for (const int cy : {by0, by1})
                for (const int cx : {bx0, bx1})
                    spread = std::max(spread, glm::length(camera.rayDirection(cx, cy) - axis));
            // Its rays meet the bounds only where the axis comes within radius + spread * t of
            // the centre: the axis through the sphere grown by its spread at the farthest t.
            Bounds grown = scene.bounds();
            grown.radius += spread * (glm::length(camera.eye - grown.center) + grown.radius);
            const Interval span = intersectSphere(camera.eye, axis, grown);
            const double near = span.valid ? span.near : kInfinity;
            const double far = span.valid ? span.far : kInfinity;
            jobs.push_back(RayJob::cone(scene, axis, 1.01 * spread, near, far));
        }
    }
    evaluator.run(scene, engine, jobs);
    std::vector<double>& starts = buffers.starts;
    std::vector<std::size_t>& firstJob = buffers.firstJob;
    constexpr std::size_t kNoJob = std::numeric_limits<std::size_t>::max();
    starts.clear();
    for (const RayJob& job : jobs) starts.push_back(job.coneStart());
    for (int first = 0; first < pixels; first += pixelsPerPass) {
        const int last = std::min(pixels, first + pixelsPerPass);
        jobs.clear();
        firstJob.clear();
        for (int index = first; index < last; ++index) {
            const int x = x0 + index % width;
            const int y = y0 + index / width;
            const std::size_t block = static_cast<std::size_t>((y - y0) / kConeBlock) * blocksX + (x - x0) / kConeBlock;
            const double start = starts[block];
            // A pixel whose cone left the bounds misses with every sample: no rays to trace.
            firstJob.push_back(start == kInfinity ? kNoJob : jobs.size());
            if (start == kInfinity) continue;
            for (int sy = 0; sy < samples; ++sy)
                for (int sx = 0; sx < samples; ++sx)
                    jobs.emplace_back(scene, sampleDirection(x, y, sx, sy), start,
                                      shadowSlots.data() + jobs.size() * lights);
        }
        evaluator.run(scene, engine, jobs);
        // Occlusion and shadows vary slowly over the surface: the first sample of a pixel to
        // hit shades itself, the pixel's others on the same piece of surface take its values.
        bool paused = false;
        for (int index = first; index < last; ++index) {
            const std::size_t pixelJobs = firstJob[static_cast<std::size_t>(index - first)];
            for (int sample = 0; sample < perPixel && pixelJobs != kNoJob; ++sample) {
                if (!jobs[pixelJobs + sample].paused()) continue;
                jobs[pixelJobs + sample].resumeShading();
                paused = true;
                break;
            }
        }
        if (paused) {
            evaluator.run(scene, engine, jobs);
            for (int index = first; index < last; ++index) {
                const std::size_t pixelJobs = firstJob[static_cast<std::size_t>(index - first)];
                if (pixelJobs == kNoJob) continue;
                const RayJob* leader = nullptr;
                for (int sample = 0; sample < perPixel; ++sample) {
                    RayJob& job = jobs[pixelJobs + sample];
                    if (!job.paused()) {
                        if (leader == nullptr && job.trace().hit) leader = &job;
                        continue;
                    }
                    if (leader != nullptr && job.canShareShading(*leader)) {
                        job.shareShading(*leader);
                    } else {
                        job.resumeShading();
                    }
                }
            }
            evaluator.run(scene, engine, jobs);
        }
        for (int index = first; index < last; ++index) {
            const int x = x0 + index % width;
            const int y = y0 + index / width;
            const std::size_t pixel = static_cast<std::size_t>(y) * image.width + x;
            const std::size_t pixelJobs = firstJob[static_cast<std::size_t>(index - first)];
            if (pixelJobs == kNoJob) {  // the background, as its rays' jobs would give it
                stats.rays += perPixel;
                const glm::dvec3& colour = pixelBackground[static_cast<std::size_t>(y - y0)];
                std::fill_n(image.surface.begin() + 3 * pixel, 3, 0.0f);
                image.rgba[4 * pixel + 0] = static_cast<float>(colour.x);
                image.rgba[4 * pixel + 1] = static_cast<float>(colour.y);
                image.rgba[4 * pixel + 2] = static_cast<float>(colour.z);
                image.rgba[4 * pixel + 3] = 0.0f;
                image.depth[pixel] = std::numeric_limits<float>::infinity();
                std::fill_n(image.normal.begin() + 3 * pixel, 3, 0.0f);
                continue;
            }
            glm::dvec3 colour(0.0);
            glm::dvec3 surfaceColour(0.0);
            glm::dvec3 normalSum(0.0);
            double depth = kInfinity;
            int hits = 0;
            for (int sample = 0; sample < perPixel; ++sample) {
                const RayJob& job = jobs[pixelJobs + sample];
                ++stats.rays;
                stats.steps += job.trace().steps;
                colour += job.colour();
                if (!job.trace().hit) continue;
                surfaceColour += job.colour();
                normalSum += job.normal();
                depth = std::min(depth, job.trace().t);
                ++hits;
            }
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
    stats.evaluations = evaluator.takeEvaluations();
    return stats;
}

}  // namespace

glm::dvec3 CameraFrame::rayDirection(double px, double py) const {
    return screenDirection(*this, screenX(*this, px), screenY(*this, py));
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

RenderResult render(const Params& params, const ProgressCallback& progress, RenderEngine engine) {
    validate(params);
    const auto start = std::chrono::steady_clock::now();
    const std::string provenEmpty = provenEmptyReason(params);
    const Scene scene(params, !provenEmpty.empty());

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
    std::atomic<std::uint64_t> evaluations{0};
    ThreadScratch<TileBuffers> scratch;  // each thread's TileBuffers, reused from tile to tile
    parallelForWithProgress(static_cast<std::size_t>(tilesX) * tilesY, progress,
                            [&](std::size_t index, const std::atomic<bool>&) {
                                const int x0 = static_cast<int>(index % tilesX) * kTileSize;
                                const int y0 = static_cast<int>(index / tilesX) * kTileSize;
                                const TileStats tile =
                                    renderTile(scene, engine, x0, y0, std::min(x0 + kTileSize, image.width),
                                               std::min(y0 + kTileSize, image.height), image, scratch.local());
                                rays += tile.rays;
                                steps += tile.steps;
                                hitPixels += tile.hitPixels;
                                evaluations += tile.evaluations;
                            });

    result.stats.rays = rays;
    result.stats.steps = steps;
    result.stats.hitPixels = hitPixels;
    result.stats.evaluations = evaluations;
    result.stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (result.stats.hitPixels == 0)
        result.emptyReason = provenEmpty.empty() ? inspect(params).emptyReason : provenEmpty;
    return result;
}

}  // namespace dqj
