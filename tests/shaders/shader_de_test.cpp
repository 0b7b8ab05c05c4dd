// The shaders' distance estimate against the core's: the add-on's GLSL (viewport preview) and
// OSL (Cycles script node) sources compiled as C++ against GLM (shader_shims.hpp), evaluated
// in float at sample points, and compared with dqj::evaluate in double.
//
// What agreement to expect, and why the tolerances are what they are:
// - Float rounding (2^-24 = 6e-8 relative a step) is amplified along the orbit by the same
//   derivative the DE divides by: after n steps an error e grows to about e * |dz_n|. So the
//   relative difference of the DE is about eps_float * |dz_n| (times a small constant), and
//   |dz_n| = 0.5 |z_n| ln|z_n| / DE is large exactly where the DE is small (near the set).
//   The test checks |DE_float - DE_double| / DE_double <= 16 * eps_float * max(1, |dz_n|),
//   and reports the largest relative difference overall and where |dz_n| <= 100.
// - The escape count is discrete: when |z_k| lies within float rounding of R at some step, or
//   the orbit comes so near the set that the amplified rounding decides whether it escapes,
//   float and double may stop at different k. Every disagreement must be one of these two:
//   the double escape count changes when R moves by 1e-4 relative, or the amplified rounding
//   (eps_float * |dz|) reaches 1e-3 of |z| before the escape. Such points must also stay rare.
// - The sphere tracer (dqj_march) is compared as a picture: the silhouette it finds along
//   the core camera's rays against the alpha of the core's own render (IoU).
// - The preview's colouring and Phong terms (dqjulia_shading.glsl) against coloring.hpp: see
//   the section at the end.
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "dqjulia/coloring.hpp"
#include "dqjulia/estimate.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/render.hpp"
#include "dqjulia/slice.hpp"
#include "shader_shims.hpp"

namespace {

struct Config {
    std::string name;
    dqj::Vec8 c;
};

const std::vector<Config>& constants() {
    static const std::vector<Config> list{
        {"c1 (paper test2-1)", {-0.10, 0.8, -0.26, 0.15, -0.23, -0.38, -0.86, 0.64}},
        {"c2 (paper high-detail, default)", {-0.39054, -0.58679, 0, 0, 0, 0.5632, 0, 0.05}},
        {"c3 (paper high-detail 2)", {-0.04, 0.95, 0.4, -0.43, 0.09, -0.35, -0.27, -0.31}},
        {"c4 (README dual example)", {-0.2, 0.6, 0.2, 0, 0, 0, 0, 0}},
    };
    return list;
}

constexpr dqj::Variant kVariants[] = {dqj::Variant::Paper, dqj::Variant::PaperCoupled, dqj::Variant::Dual};
constexpr int kIterations[] = {8, 15, 30};
constexpr double kEpsFloat = FLT_EPSILON / 2.0;  // unit roundoff of float, 2^-24

glm::vec4 quatToVec4(const dqj::Quat& q) {
    return glm::vec4(float(dqj::component(q, 0)), float(dqj::component(q, 1)), float(dqj::component(q, 2)),
                     float(dqj::component(q, 3)));
}

/// The derivative norm the DE divides by, recovered from the double result: |dz| = 0.5 r ln r / DE.
double derivativeOf(const dqj::Escape& e) {
    if (e.n == 0 || !(e.de > 0.0) || !std::isfinite(e.de)) return 1.0;
    const double r = e.r > 1.0 ? e.r : std::max(e.ra, e.rb);
    return 0.5 * r * std::log(r) / e.de;
}

/// Is a disagreement of escape counts explained by float rounding (see the file comment)?
bool escapeDisagreementExplained(const dqj::Fractal& fractal, const dqj::DualQuat& start, int floatEscape,
                                 int doubleEscape) {
    for (double factor : {1.0 - 1e-4, 1.0 + 1e-4}) {
        dqj::Fractal moved = fractal;
        moved.bailout *= factor;
        if (dqj::evaluate(moved, start).n == floatEscape) return true;
    }
    // Amplified rounding: the derivative before the earlier of the two escapes.
    const int first = std::min(floatEscape == 0 ? fractal.iterations : floatEscape,
                               doubleEscape == 0 ? fractal.iterations : doubleEscape);
    // Recompute the derivative norm along the orbit (as the variant does).
    dqj::Quat a = start.a, b = start.b;
    double da = 1.0, db = 1.0;
    for (int k = 1; k <= first; ++k) {
        const double ra = dqj::norm(a), rb = dqj::norm(b);
        if (fractal.variant == dqj::Variant::PaperCoupled) {
            da *= 2.0 * std::hypot(ra, rb);
        } else {
            da *= 2.0 * ra;
            db *= 2.0 * rb;
        }
        const dqj::Quat previous = a;
        a = dqj::square(a) + fractal.c.a;
        b = fractal.variant == dqj::Variant::Dual ? dqj::symmetricProduct(previous, b) + fractal.c.b
                                                  : dqj::square(b) + fractal.c.b;
    }
    const double amplification = fractal.variant == dqj::Variant::Paper ? std::max(da, db) : da;
    return kEpsFloat * amplification >= 1e-3;
}

struct Agreement {
    long points = 0;
    long escapeMismatches = 0;
    long unexplainedMismatches = 0;
    long compared = 0;                 // both escaped at the same iteration
    double maxRelative = 0.0;          // over all compared points
    double maxRelativeModerate = 0.0;  // where |dz| <= 100 (away from the set's surface)
    double maxRatioToBound = 0.0;      // max of relative / (eps_float * max(1, |dz|))
    long overTolerance = 0;

    void add(const Agreement& other) {
        points += other.points;
        escapeMismatches += other.escapeMismatches;
        unexplainedMismatches += other.unexplainedMismatches;
        compared += other.compared;
        overTolerance += other.overTolerance;
        maxRelative = std::max(maxRelative, other.maxRelative);
        maxRelativeModerate = std::max(maxRelativeModerate, other.maxRelativeModerate);
        maxRatioToBound = std::max(maxRatioToBound, other.maxRatioToBound);
    }
};

template <typename Evaluate>
void compare(const dqj::Fractal& fractal, const dqj::DualQuat& start, Evaluate&& shader, Agreement& out) {
    const dqj::Escape core = dqj::evaluate(fractal, start);
    int n = 0;
    float de = 0.0f;
    shader(n, de);
    ++out.points;
    if (n != core.n) {
        ++out.escapeMismatches;
        if (!escapeDisagreementExplained(fractal, start, n, core.n)) ++out.unexplainedMismatches;
        return;
    }
    if (core.n == 0) {
        if (de != 0.0f) ++out.overTolerance;  // inside: both must say 0
        return;
    }
    if (!std::isfinite(core.de)) {
        if (!(de >= 1e29f)) ++out.overTolerance;
        return;
    }
    ++out.compared;
    const double relative = std::abs(double(de) - core.de) / core.de;
    const double derivative = derivativeOf(core);
    out.maxRelative = std::max(out.maxRelative, relative);
    if (derivative <= 100.0) out.maxRelativeModerate = std::max(out.maxRelativeModerate, relative);
    const double ratio = relative / (kEpsFloat * std::max(1.0, derivative));
    out.maxRatioToBound = std::max(out.maxRatioToBound, ratio);
    if (ratio > 16.0) ++out.overTolerance;
}

/// Random 8-D start points: uniform in a ball around 0 of 1.1 r_K for each part.
std::vector<dqj::DualQuat> samplePoints(const dqj::Fractal& fractal, int count, unsigned seed) {
    std::mt19937 random(seed);
    std::normal_distribution<double> gaussian;
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    const double radiusA = 1.1 * dqj::containmentRadius(fractal.c.a);
    const double radiusB = 1.1 * dqj::containmentRadius(fractal.c.b);
    auto ball = [&](double radius) {
        double v[4], length = 0.0;
        for (double& x : v) {
            x = gaussian(random);
            length += x * x;
        }
        length = std::sqrt(length);
        const double scale = radius * std::pow(uniform(random), 0.25) / length;
        return dqj::makeQuat(v[0] * scale, v[1] * scale, v[2] * scale, v[3] * scale);
    };
    std::vector<dqj::DualQuat> points;
    for (int index = 0; index < count; ++index) {
        dqj::DualQuat z;
        z.a = ball(radiusA);
        // Half the points in the default slice's space (b = 0), half with b in its ball.
        z.b = index % 2 == 0 ? dqj::makeQuat(0, 0, 0, 0) : ball(radiusB);
        // Round the start to float, so both sides iterate the same point.
        for (int i = 0; i < 8; ++i) dqj::component(z, i) = double(float(dqj::component(z, i)));
        points.push_back(z);
    }
    return points;
}

dqj::Fractal roundedFractal(const dqj::Vec8& c, dqj::Variant variant, int iterations) {
    dqj::Fractal fractal;
    dqj::Vec8 rounded = c;
    for (double& x : rounded) x = double(float(x));
    fractal.c = dqj::toDualQuat(rounded);
    fractal.variant = variant;
    fractal.iterations = iterations;
    fractal.bailout = std::max(4.0, std::ceil(dqj::minimumBailout(fractal) * 100.0) / 100.0);
    return fractal;
}

void report(const char* backend, const Agreement& total) {
    std::printf(
        "[%s] %ld points: escape count differs at %ld (%.4f%%; %ld unexplained); DE compared at %ld: max relative "
        "difference %.3g overall, %.3g where |dz| <= 100; max (relative / (eps_float * max(1,|dz|))) = %.1f\n",
        backend, total.points, total.escapeMismatches, 100.0 * total.escapeMismatches / std::max(1L, total.points),
        total.unexplainedMismatches, total.compared, total.maxRelative, total.maxRelativeModerate,
        total.maxRatioToBound);
}

void checkAgreement(const char* backend, const Agreement& total) {
    report(backend, total);
    EXPECT_EQ(total.unexplainedMismatches, 0) << backend;
    EXPECT_LT(double(total.escapeMismatches), 0.01 * double(total.points))
        << backend << ": too many escape disagreements";
    EXPECT_EQ(total.overTolerance, 0) << backend << ": DE beyond 16 eps_float * max(1, |dz|)";
    EXPECT_LT(total.maxRelativeModerate, 1e-4) << backend;
    EXPECT_GT(total.compared, total.points / 4) << backend;
}

TEST(ShaderDistanceEstimate, GlslMatchesCore) {
    Agreement total;
    unsigned seed = 1;
    for (const Config& config : constants()) {
        for (dqj::Variant variant : kVariants) {
            for (int iterations : kIterations) {
                const dqj::Fractal fractal = roundedFractal(config.c, variant, iterations);
                Agreement one;
                for (const dqj::DualQuat& z : samplePoints(fractal, 4000, seed++)) {
                    compare(
                        fractal, z,
                        [&](int& n, float& de) {
                            const glsl::DqjEscape e =
                                glsl::dqj_evaluate(quatToVec4(z.a), quatToVec4(z.b), quatToVec4(fractal.c.a),
                                                   quatToVec4(fractal.c.b), int(variant), iterations,
                                                   float(fractal.bailout));
                            n = e.n;
                            de = e.de;
                        },
                        one);
                }
                total.add(one);
                if (one.unexplainedMismatches || one.overTolerance)
                    ADD_FAILURE() << config.name << " variant " << dqj::variantName(variant) << " N=" << iterations;
            }
        }
    }
    checkAgreement("GLSL", total);
}

TEST(ShaderDistanceEstimate, OslMatchesCore) {
    Agreement total;
    unsigned seed = 1001;
    for (const Config& config : constants()) {
        for (dqj::Variant variant : kVariants) {
            for (int iterations : kIterations) {
                const dqj::Fractal fractal = roundedFractal(config.c, variant, iterations);
                for (const dqj::DualQuat& z : samplePoints(fractal, 4000, seed++)) {
                    compare(
                        fractal, z,
                        [&](int& n, float& de) {
                            const glm::vec4 a = quatToVec4(z.a), b = quatToVec4(z.b);
                            const glm::vec4 ca = quatToVec4(fractal.c.a), cb = quatToVec4(fractal.c.b);
                            float r = 0.0f, trap = 0.0f;
                            osl::dqj_evaluate(a.x, glm::vec3(a.y, a.z, a.w), b.x, glm::vec3(b.y, b.z, b.w), ca.x,
                                              glm::vec3(ca.y, ca.z, ca.w), cb.x, glm::vec3(cb.y, cb.z, cb.w),
                                              int(variant), iterations, float(fractal.bailout), n, r, de, trap);
                        },
                        total);
                }
            }
        }
    }
    checkAgreement("OSL", total);
}

// The GLSL slice map (mat4 columns origin, x, y, z) against the core's Slice::map.
TEST(ShaderDistanceEstimate, GlslSliceMapMatchesCore) {
    dqj::Params params;
    params.slice.base = dqj::sliceFromAxisNames("a.i,a.j,b.s");
    params.slice.base.origin = {0.1, 0, 0, 0.05, 0, 0.02, 0, 0};
    params.slice.rotations = {{2, 4, 30.0}, {0, 5, -20.0}};
    const dqj::Slice slice = params.slice.effective();
    glsl::DqjFractal f{};
    for (int column = 0; column < 4; ++column) {
        const dqj::Vec8& v = column == 0 ? slice.origin : slice.axes[column - 1];
        f.slice_a[column] = glm::vec4(float(v[0]), float(v[1]), float(v[2]), float(v[3]));
        f.slice_b[column] = glm::vec4(float(v[4]), float(v[5]), float(v[6]), float(v[7]));
    }
    double worst = 0.0;
    for (double x : {-1.3, 0.0, 0.7})
        for (double y : {-0.4, 0.9})
            for (double z : {-1.1, 0.25}) {
                const dqj::DualQuat expected = slice.map({x, y, z});
                const glm::vec4 p(1.0f, float(x), float(y), float(z));
                const glm::vec4 a = f.slice_a * p, b = f.slice_b * p;
                for (int i = 0; i < 4; ++i) {
                    worst = std::max(worst, std::abs(a[i] - dqj::component(expected, i)));
                    worst = std::max(worst, std::abs(b[i] - dqj::component(expected, 4 + i)));
                }
            }
    std::printf("[GLSL slice map] max absolute difference %.3g\n", worst);
    EXPECT_LT(worst, 1e-6);
}

/// The silhouette of dqj_march along the core camera's rays against the core render's alpha.
double marchIoU(const dqj::Params& given, int width, int height) {
    dqj::Params params = given;
    params.render.width = width;
    params.render.height = height;
    params.render.samples = 1;
    params.material.shadows = false;
    params.material.occlusion = 0.0;
    const dqj::RenderResult core = dqj::render(params);
    const dqj::Bounds bounds = dqj::renderBounds(params);
    const dqj::CameraFrame camera = dqj::frameCamera(params, bounds);
    const dqj::Slice slice = params.slice.effective();

    glsl::DqjFractal f{};
    for (int column = 0; column < 4; ++column) {
        const dqj::Vec8& v = column == 0 ? slice.origin : slice.axes[column - 1];
        f.slice_a[column] = glm::vec4(float(v[0]), float(v[1]), float(v[2]), float(v[3]));
        f.slice_b[column] = glm::vec4(float(v[4]), float(v[5]), float(v[6]), float(v[7]));
    }
    f.ca = quatToVec4(params.fractal.c.a);
    f.cb = quatToVec4(params.fractal.c.b);
    f.variant = int(params.fractal.variant);
    f.iterations = params.fractal.iterations;
    f.bailout = float(params.fractal.bailout);
    f.stretch = float(dqj::stretchOf(slice).max);
    glsl::DqjTrace m{};
    m.bounds = glm::vec4(float(bounds.center.x), float(bounds.center.y), float(bounds.center.z), float(bounds.radius));
    m.clipped = bounds.clipped;
    m.step_factor = float(params.render.stepFactor);
    m.max_step = float(params.render.maxStep);
    m.max_steps = params.render.maxSteps;
    m.detail = float(params.render.detail);
    m.footprint = glm::vec2(float(2.0 * camera.tanHalfFov / camera.height), 0.0f);

    long both = 0, either = 0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const glm::dvec3 direction = camera.rayDirection(x + 0.5, y + 0.5);
            const glsl::DqjHit hit = glsl::dqj_march(f, m, glm::vec3(camera.eye), glm::vec3(direction));
            const bool coreHit = core.image.rgba[4 * (size_t(y) * width + x) + 3] > 0.5f;
            both += hit.hit && coreHit;
            either += hit.hit || coreHit;
        }
    return either == 0 ? 1.0 : double(both) / double(either);
}

TEST(ShaderMarch, SilhouetteMatchesCoreRender) {
    struct Case {
        std::string name;
        std::string json;
    };
    const std::vector<Case> cases{
        {"defaults (paper, c2, N=15)", "{}"},
        {"paper-coupled, N=10", R"({"fractal": {"variant": "paper-coupled", "iterations": 10, "bailout": 4.2}})"},
        {"dual, c4, N=30",
         R"({"fractal": {"variant": "dual", "iterations": 30, "c": [-0.2, 0.6, 0.2, 0, 0, 0, 0, 0]}})"},
        {"turned slice", R"({"slice": {"axes": "a.s,a.i,a.j", "rotations": [{"plane": "a.j,a.k", "degrees": 35}]}})"},
    };
    for (const Case& item : cases) {
        const double iou = marchIoU(dqj::parseParams(item.json), 160, 120);
        std::printf("[GLSL march] %s: silhouette IoU with the core render %.4f\n", item.name.c_str(), iou);
        EXPECT_GT(iou, 0.97) << item.name;
    }
}

// ---- The preview's colouring and Phong terms (dqjulia_shading.glsl) against the core's
// (coloring.hpp), in float against double on the same inputs.
//
// Both sides get the same escape results (the core's, rounded to float, as the GPU would hold
// them) and the same vectors, so what differs is float against double arithmetic:
// - the colouring value (smooth count / N, trap / trap scale) to a few float roundings, and the
//   palette colour, linear in it, to those times the palette's slope (at most 3 colours a unit);
// - Phong: the highlight max(0, R.V)^s turns a relative rounding e of R.V into about s * e, so
//   the tolerance is 16 eps_float (1 + s) of the terms' size. The one discontinuity of the
//   model, a light grazing the surface (N.L = 0, where the highlight switches on), is kept out.

double roundToFloat(double value) { return double(float(value)); }

/// The escape as the shader holds it, and the core's escape rounded the same way.
glsl::DqjEscape toShader(const dqj::Escape& e) {
    glsl::DqjEscape result;
    result.n = e.n;
    result.r = float(e.r);
    result.ra = float(e.ra);
    result.rb = float(e.rb);
    result.de = float(std::min(e.de, 1e30));
    result.trap = float(e.trap);
    return result;
}

dqj::Escape rounded(dqj::Escape e) {
    e.r = roundToFloat(e.r);
    e.ra = roundToFloat(e.ra);
    e.rb = roundToFloat(e.rb);
    e.trap = roundToFloat(e.trap);
    return e;
}

/// The preview's material (preview.py fills the same fields from the document).
glsl::DqjMaterial toShader(const dqj::Material& material) {
    glsl::DqjMaterial m{};
    m.coloring = int(material.coloring);
    m.color = glm::vec3(material.color);
    const std::size_t count = std::min<std::size_t>(material.palette.size(), 4);
    for (std::size_t index = 0; index < 4; ++index)
        m.palette[int(index)] = glm::vec4(glm::vec3(material.palette[std::min(index, count - 1)]), 1.0f);
    m.palette_size = int(count);
    m.phong = glm::vec4(float(material.ambient), float(material.diffuse), float(material.specular),
                        float(material.shininess));
    return m;
}

double largestDifference(const glm::dvec3& core, const glm::vec3& shader) {
    double worst = 0.0;
    for (int channel = 0; channel < 3; ++channel)
        worst = std::max(worst, std::abs(core[channel] - double(shader[channel])));
    return worst;
}

/// Random start points in the 8-D ball of 1.1 r_K of each part, as samplePoints' (unrounded).
std::vector<dqj::DualQuat> shadingPoints(const dqj::Fractal& fractal, int count, std::mt19937& random) {
    std::normal_distribution<double> gaussian;
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    auto ball = [&](double radius) {
        double v[4], length = 0.0;
        for (double& x : v) {
            x = gaussian(random);
            length += x * x;
        }
        const double scale = radius * std::pow(uniform(random), 0.25) / std::sqrt(length);
        return dqj::makeQuat(v[0] * scale, v[1] * scale, v[2] * scale, v[3] * scale);
    };
    std::vector<dqj::DualQuat> points;
    for (int index = 0; index < count; ++index)
        points.push_back({ball(1.1 * dqj::containmentRadius(fractal.c.a)),
                          index % 2 ? ball(1.1 * dqj::containmentRadius(fractal.c.b)) : dqj::makeQuat(0, 0, 0, 0)});
    return points;
}

TEST(ShaderShading, GlslColouringMatchesCore) {
    const std::vector<dqj::Vec8> constants{{-0.10, 0.8, -0.26, 0.15, -0.23, -0.38, -0.86, 0.64},
                                           {-0.39054, -0.58679, 0, 0, 0, 0.5632, 0, 0.05},
                                           {-0.2, 0.6, 0.2, 0, 0, 0, 0, 0}};
    const std::vector<std::vector<glm::dvec3>> palettes{
        dqj::Material{}.palette,  // the default: 3 colours
        {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 1, 1}},
        {{0.1, 0.2, 0.3}, {0.9, 0.8, 0.1}},
        {{0.4, 0.5, 0.6}},
    };
    std::mt19937 random(1313);
    double worst[3] = {0.0, 0.0, 0.0};  // solid, iterations, trap: largest colour difference
    double worstSmooth = 0.0, worstTrapScale = 0.0;
    long escaped = 0, inside = 0, compared = 0;
    for (const dqj::Vec8& c : constants) {
        for (dqj::Variant variant : {dqj::Variant::Paper, dqj::Variant::PaperCoupled, dqj::Variant::Dual}) {
            for (int iterations : {8, 30}) {
                dqj::Fractal fractal;
                dqj::Vec8 floatC = c;
                for (double& x : floatC) x = roundToFloat(x);
                fractal.c = dqj::toDualQuat(floatC);
                fractal.variant = variant;
                fractal.iterations = iterations;
                fractal.bailout = std::max(4.0, std::ceil(dqj::minimumBailout(fractal) * 100.0) / 100.0);
                fractal.bailout = roundToFloat(fractal.bailout);
                // The preview passes r_K (from the core) and the shader scales it.
                const float trapScale = glsl::dqj_trap_scale(float(dqj::containmentRadius(fractal.c.a)));
                worstTrapScale = std::max(worstTrapScale, std::abs(double(trapScale) - dqj::trapScale(fractal)) /
                                                              dqj::trapScale(fractal));
                for (const dqj::DualQuat& z : shadingPoints(fractal, 500, random)) {
                    const dqj::Escape escape = rounded(dqj::evaluate(fractal, z));
                    const glsl::DqjEscape e = toShader(escape);
                    ++(escape.n == 0 ? inside : escaped);
                    const double smooth = dqj::smoothIterations(fractal, escape);
                    const float shaderSmooth = glsl::dqj_smooth_iterations(e, iterations, float(fractal.bailout));
                    worstSmooth = std::max(worstSmooth, std::abs(double(shaderSmooth) - smooth) / iterations);
                    for (const auto& palette : palettes) {
                        for (dqj::Coloring coloring :
                             {dqj::Coloring::Solid, dqj::Coloring::Iterations, dqj::Coloring::Trap}) {
                            dqj::Material material;
                            material.palette = palette;
                            material.coloring = coloring;
                            const glm::dvec3 core = dqj::orbitColour(material, fractal, escape);
                            const glm::vec3 shader = glsl::dqj_orbit_colour(toShader(material), e, iterations,
                                                                            float(fractal.bailout), trapScale);
                            const double difference = largestDifference(core, shader);
                            worst[int(coloring)] = std::max(worst[int(coloring)], difference);
                            // Float roundings of the value, times the palette's slope (<= 3 a unit).
                            EXPECT_LE(difference, 64.0 * kEpsFloat)
                                << "coloring " << int(coloring) << " n=" << escape.n << " r=" << escape.r
                                << " trap=" << escape.trap << " palette of " << palette.size();
                            ++compared;
                        }
                    }
                }
            }
        }
    }
    std::printf(
        "[GLSL colouring] %ld colours compared (%ld escaped, %ld inside points): largest colour difference "
        "solid %.3g, iterations %.3g, trap %.3g; smooth count / N %.3g, trap scale (relative) %.3g\n",
        compared, escaped, inside, worst[0], worst[1], worst[2], worstSmooth, worstTrapScale);
    EXPECT_LE(worst[0], kEpsFloat);  // the material colour, rounded to float
    EXPECT_LE(worstSmooth, 16.0 * kEpsFloat);
    EXPECT_LE(worstTrapScale, 2.0 * kEpsFloat);
    EXPECT_GT(escaped, 1000);
    EXPECT_GT(inside, 200);
}

TEST(ShaderShading, GlslPhongMatchesCore) {
    std::mt19937 random(2424);
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    std::uniform_real_distribution<double> positive(0.0, 1.0);
    auto direction = [&] {
        for (;;) {
            const glm::dvec3 v(unit(random), unit(random), unit(random));
            const double length = glm::length(v);
            if (length > 0.1 && length <= 1.0) {
                const glm::vec3 f(v / length);  // the shader's float vector; the core gets the same values
                return glm::dvec3(f);
            }
        }
    };
    double worstAmbient = 0.0, worstLight = 0.0, worstRatio = 0.0;
    long lit = 0, behind = 0, grazing = 0;
    for (double shininess : {1.0, 8.0, 24.0, 100.0}) {
        for (int sample = 0; sample < 4000; ++sample) {
            dqj::Material material;
            material.ambient = roundToFloat(positive(random));
            material.diffuse = roundToFloat(positive(random));
            material.specular = roundToFloat(positive(random));
            material.shininess = shininess;
            const glsl::DqjMaterial m = toShader(material);
            const glm::dvec3 base = glm::dvec3(glm::vec3(positive(random), positive(random), positive(random)));
            const glm::dvec3 radiance =
                glm::dvec3(glm::vec3(1.5 * positive(random), positive(random), positive(random)));
            const double open = std::vector<double>{1.0, 0.5, 0.0}[sample % 3];
            const glm::dvec3 normal = direction(), toLight = direction(), toEye = direction();
            const double facing = glm::dot(normal, toLight);
            if (std::abs(facing) < 1e-5) {  // the highlight switches on at N.L = 0 (file comment)
                ++grazing;
                continue;
            }
            ++(facing > 0.0 ? lit : behind);

            const glm::dvec3 ambient = dqj::phongAmbient(material, base, open);
            const glm::vec3 shaderAmbient = glsl::dqj_phong_ambient(m, glm::vec3(base), float(open));
            worstAmbient = std::max(worstAmbient, largestDifference(ambient, shaderAmbient));
            EXPECT_LE(largestDifference(ambient, shaderAmbient), 4.0 * kEpsFloat);

            const glm::dvec3 core = dqj::phongLight(material, base, normal, toLight, toEye, radiance, open);
            const glm::vec3 shader = glsl::dqj_phong_light(m, glm::vec3(base), glm::vec3(normal), glm::vec3(toLight),
                                                           glm::vec3(toEye), glm::vec3(radiance), float(open));
            // The terms' size: what the light could give at most here.
            const double size = (material.diffuse + material.specular) * std::max({radiance.x, radiance.y, radiance.z});
            const double difference = largestDifference(core, shader);
            worstLight = std::max(worstLight, difference);
            const double ratio = difference / (kEpsFloat * (1.0 + shininess) * std::max(size, 1e-3));
            worstRatio = std::max(worstRatio, ratio);
            EXPECT_LE(ratio, 16.0) << "shininess " << shininess << " facing " << facing << " core " << core.x << " "
                                   << core.y << " " << core.z << " shader " << shader.x << " " << shader.y << " "
                                   << shader.z;
            if (facing < 0.0) {
                EXPECT_EQ(glm::length(shader), 0.0f);
            }
        }
    }
    std::printf(
        "[GLSL Phong] %ld lit, %ld behind (%ld grazing left out): largest difference ambient %.3g, one light "
        "%.3g; max difference / (eps_float (1 + s) size) = %.2f\n",
        lit, behind, grazing, worstAmbient, worstLight, worstRatio);
    EXPECT_GT(lit, 5000);
    EXPECT_GT(behind, 5000);
}

}  // namespace
