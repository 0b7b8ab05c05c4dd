// ray_job.hpp - one camera ray as a state machine (RayJob: marching, bisection, normal,
// occlusion and shadow probes, shading) and the Evaluator that answers the points its rays ask
// for, one at a time (scalar engine) or through the SIMD batch kernel (packet engine) (internal
// to the renderer: included by render.cpp alone, in an anonymous namespace as when it was part of
// that file, so its inner loops inline as before). Cost: the render's evaluations.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>

#include "dqjulia/batch.hpp"
#include "dqjulia/coloring.hpp"
#include "render/scene.hpp"

namespace dqj {
namespace {

inline constexpr int kOcclusionSamples = 5;
inline constexpr int kShadowSteps = 64;  // soft shadows are a look, not a measurement: cap their cost
/// Shadow marches step by this many DEs (over-relaxed; the DE is about half the distance) and
/// fall back to the plain step where two consecutive free balls do not overlap.
inline constexpr double kShadowRelaxation = 1.6;
inline constexpr int kBisectionSteps = 8;  // refines a step that landed inside to 1/256 of the step
/// A cone stops where its free margin (DE minus its radius) drops below this many hit
/// thresholds: its rays then start well before any point where they could stop.
inline constexpr double kConeMargin = 4.0;

/// The normal turned towards the eye. A gradient that tips past perpendicular to the ray (a
/// surface seen edge on, where the differences straddle a crease) is bent back onto the
/// silhouette, its component along the ray removed, not mirrored: mirroring turned a lit grazing
/// surface into a dark speckle one pixel wide. A normal pointing straight away becomes -ray.
inline glm::dvec3 facingRay(const glm::dvec3& normal, const glm::dvec3& direction) {
    const double along = glm::dot(normal, direction);
    if (along <= 0.0) return normal;
    const glm::dvec3 bent = normal - along * direction;
    const double length = glm::length(bent);
    return length > 1e-6 ? bent / length : -direction;
}

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

}  // namespace
}  // namespace dqj
