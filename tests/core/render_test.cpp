// The renderer against exact answers: with c = 0 the set is the unit ball (for every variant,
// in the default slice), so silhouette, normals and depth can be checked per pixel against
// ray/sphere intersection. Plus image files, progress and cancellation.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <glm/geometric.hpp>
#include <unistd.h>

#include "dqjulia/image.hpp"
#include "dqjulia/render.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;
using namespace dqj;

namespace {

Params ballParams(Variant variant, NormalMethod normals) {
    Params params;
    params.fractal.c = DualQuat{};  // c = 0: the filled Julia set is the unit ball
    params.fractal.variant = variant;
    params.render.width = 160;
    params.render.height = 120;
    params.render.samples = 1;
    params.render.normals = normals;
    // A tenth-of-a-pixel hit threshold. The DE is exactly half the true distance for the ball, so
    // rays passing within 2 * detail pixel footprints of the surface count as hits; at the
    // default detail of 1 the silhouette would grow by 2 pixels.
    params.render.detail = 0.1;
    // The containment radius for c = 0 is 1: the ball itself. Larger bounds make the rays march.
    params.bounds = Bounds{glm::dvec3(0.0), 2.0, false};
    params.camera.position = glm::dvec3(0.0, 0.0, 3.0);
    params.camera.target = glm::dvec3(0.0);
    params.camera.fovDegrees = 40.0;
    return params;
}

/// Distance along the ray to the unit sphere, or -1 for a miss.
double sphereHit(const glm::dvec3& eye, const glm::dvec3& direction) {
    const double b = glm::dot(eye, direction);
    const double c = glm::dot(eye, eye) - 1.0;
    const double discriminant = b * b - c;
    if (discriminant < 0.0) return -1.0;
    const double t = -b - std::sqrt(discriminant);
    return t > 0.0 ? t : -1.0;
}

double encodeSrgb(double linear) {
    linear = std::clamp(linear, 0.0, 1.0);
    return linear <= 0.0031308 ? 12.92 * linear : 1.055 * std::pow(linear, 1.0 / 2.4) - 0.055;
}

/// The tests that write image files, each in a folder of its own.
using RenderFiles = dqj::test::ScratchFolder;

void checkBall(Variant variant, NormalMethod normals) {
    const Params params = ballParams(variant, normals);
    const RenderResult result = render(params);
    const Image& image = result.image;
    ASSERT_EQ(image.width, 160);
    ASSERT_EQ(image.height, 120);
    const CameraFrame camera = frameCamera(params, renderBounds(params));
    const double footprint = 2.0 * camera.tanHalfFov / camera.height;

    // The analytic picture first, so disagreements can be tested for lying on its boundary.
    const int width = image.width;
    const int height = image.height;
    std::vector<double> exact(static_cast<std::size_t>(width) * height);
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            exact[y * width + x] = sphereHit(camera.eye, camera.rayDirection(x + 0.5, y + 0.5));
    auto onBoundary = [&](int x, int y) {
        const bool inside = exact[y * width + x] > 0.0;
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                const int nx = std::clamp(x + dx, 0, width - 1);
                const int ny = std::clamp(y + dy, 0, height - 1);
                if ((exact[ny * width + nx] > 0.0) != inside) return true;
            }
        return false;
    };

    int disagreements = 0;
    int interiorDisagreements = 0;
    int checkedNormals = 0;
    int badNormals = 0;
    double worstDot = 1.0;
    int badDepths = 0;
    double worstDepthError = 0.0;  // in pixel footprints
    for (int y = 0; y < height; ++y) {
        for (int x = 0; x < width; ++x) {
            const std::size_t pixel = static_cast<std::size_t>(y) * width + x;
            const bool rendered = image.rgba[4 * pixel + 3] > 0.5f;
            const double t = exact[pixel];
            if (rendered != (t > 0.0)) {
                ++disagreements;
                if (!onBoundary(x, y)) ++interiorDisagreements;
            }
            if (!rendered || t <= 0.0) continue;
            const glm::dvec3 direction = camera.rayDirection(x + 0.5, y + 0.5);
            const glm::dvec3 surfaceNormal = camera.eye + t * direction;  // unit sphere: point = normal
            const glm::dvec3 normal(image.normal[3 * pixel], image.normal[3 * pixel + 1], image.normal[3 * pixel + 2]);
            const double agreement = glm::dot(normal, surfaceNormal);
            ++checkedNormals;
            worstDot = std::min(worstDot, agreement);
            if (!(agreement > 0.99)) ++badNormals;
            // Depth: a hit is accepted within 2 * detail footprints of the surface, measured
            // across it; along the ray that is divided by the cosine of the incidence angle.
            // Grazing pixels are left to the silhouette test.
            const double cosine = -glm::dot(direction, surfaceNormal);
            if (cosine > 0.5) {
                const double error = std::abs(image.depth[pixel] - t) / (t * footprint);
                worstDepthError = std::max(worstDepthError, error);
                if (!(error < 3.0)) ++badDepths;
            }
        }
    }
    const int pixels = width * height;
    EXPECT_LE(disagreements, pixels / 100)
        << disagreements << " of " << pixels << " pixels disagree with the exact silhouette";
    EXPECT_EQ(interiorDisagreements, 0) << interiorDisagreements << " disagreeing pixels are not on the silhouette";
    EXPECT_GT(checkedNormals, pixels / 3);
    EXPECT_EQ(badNormals, 0) << badNormals << " of " << checkedNormals
                             << " normals off by more than 8 degrees; worst dot " << worstDot;
    EXPECT_EQ(badDepths, 0) << "worst depth error " << worstDepthError << " pixel footprints";
    EXPECT_EQ(result.stats.rays, static_cast<std::uint64_t>(pixels));
    EXPECT_GT(result.stats.steps, result.stats.rays / 2);
    std::printf("    %s normals %s: %d/%d silhouette pixels differ, worst normal dot %.5f, worst depth error %.2f px\n",
                std::string(variantName(params.fractal.variant)).c_str(),
                std::string(normalMethodName(normals)).c_str(), disagreements, pixels, worstDot, worstDepthError);
}

}  // namespace

TEST(RenderBall, DualAnalyticNormals) { checkBall(Variant::Dual, NormalMethod::Analytic); }
TEST(RenderBall, DualCentralDifferences) { checkBall(Variant::Dual, NormalMethod::CentralDifferences); }
TEST(RenderBall, PaperCentralDifferences) { checkBall(Variant::Paper, NormalMethod::CentralDifferences); }
TEST(RenderBall, PaperAuto) { checkBall(Variant::Paper, NormalMethod::Auto); }

TEST(RenderBall, AutoFramingKeepsTheSphereInView) {
    // Taller than wide: the horizontal field of view decides the distance.
    for (const auto& [width, height] : {std::pair{160, 120}, std::pair{90, 160}}) {
        Params params = ballParams(Variant::Dual, NormalMethod::Auto);
        params.camera.position.reset();
        params.camera.target.reset();
        params.render.width = width;
        params.render.height = height;
        const Bounds bounds = renderBounds(params);
        const CameraFrame camera = frameCamera(params, bounds);
        EXPECT_NEAR(glm::dot(camera.forward, camera.up), 0.0, 1e-12);
        EXPECT_NEAR(glm::dot(camera.forward, camera.right), 0.0, 1e-12);
        // The four image edges' midpoints see past the sphere.
        for (const auto& [px, py] : {std::pair{0.0, height / 2.0}, std::pair{double(width), height / 2.0},
                                     std::pair{width / 2.0, 0.0}, std::pair{width / 2.0, double(height)}}) {
            const glm::dvec3 direction = camera.rayDirection(px, py);
            const glm::dvec3 offset = camera.eye - bounds.center;
            const double b = glm::dot(offset, direction);
            EXPECT_LT(b * b - (glm::dot(offset, offset) - bounds.radius * bounds.radius), 0.0)
                << width << "x" << height << " edge (" << px << ", " << py << ") cuts the bounding sphere";
        }
        // Pixel (0, 0) is the top-left corner: up and to the left of the view.
        const glm::dvec3 corner = camera.rayDirection(0.0, 0.0);
        EXPECT_GT(glm::dot(corner, camera.up), 0.0);
        EXPECT_LT(glm::dot(corner, camera.right), 0.0);
    }
}

TEST(RenderBall, EmptySliceIsExplained) {
    Params params;
    params.slice.base.origin[4] = 5.0;  // b far outside the containment radius of c_b
    try {
        renderBounds(params);
        FAIL() << "expected ParamError";
    } catch (const ParamError& error) {
        EXPECT_EQ(error.key(), "slice");
        EXPECT_NE(std::string(error.what()).find("bounds"), std::string::npos) << error.what();
    }
}

/// Lone dark pixels: covered pixels darker than a quarter of the median of their 8 neighbours,
/// with the whole 5 x 5 neighbourhood covered and none of it darker than half that median (a
/// crease or an occluding edge is a line of such pixels, so it does not count). The preview
/// test (tests/blender/preview_test.py) counts the same on the GLSL preview.
int loneDarkPixels(const Image& image) {
    const int width = image.width, height = image.height;
    auto covered = [&](int x, int y) { return image.rgba[4 * (std::size_t(y) * width + x) + 3] > 0.5f; };
    auto luminance = [&](int x, int y) {
        const float* p = &image.rgba[4 * (std::size_t(y) * width + x)];
        return (p[0] + p[1] + p[2]) / 3.0f;
    };
    int found = 0;
    for (int y = 2; y < height - 2; ++y)
        for (int x = 2; x < width - 2; ++x) {
            bool all = true;
            float darkest = 1e30f;
            std::vector<float> near;
            for (int dy = -2; dy <= 2; ++dy)
                for (int dx = -2; dx <= 2; ++dx) {
                    all = all && covered(x + dx, y + dy);
                    if (dx == 0 && dy == 0) continue;
                    darkest = std::min(darkest, luminance(x + dx, y + dy));
                    if (std::abs(dx) <= 1 && std::abs(dy) <= 1) near.push_back(luminance(x + dx, y + dy));
                }
            if (!all) continue;
            std::sort(near.begin(), near.end());
            const float median = near[near.size() / 2];
            found += luminance(x, y) < 0.25f * median && darkest >= 0.5f * median;
        }
    return found;
}

TEST(RenderImage, NoLoneDarkPixelsOnTheDefaultFractal) {
    // One ray a pixel, no occlusion or shadows: what is left is the normal. A gradient tipped past
    // perpendicular to the ray (a surface seen edge on, the differences straddling a crease) used
    // to be mirrored towards the eye, which lit the pixel from behind: 13 lone dark pixels here
    // then, 1 now (a crease point seen by one ray).
    Params params;
    params.render.width = 640;
    params.render.height = 480;
    params.render.samples = 1;
    params.material.occlusion = 0.0;
    params.material.shadows = false;
    const RenderResult result = render(params);
    EXPECT_LE(loneDarkPixels(result.image), 2);
}

TEST_F(RenderFiles, DefaultParametersRoundTripThroughFiles) {
    Params params;
    params.render.width = 160;
    params.render.height = 120;
    const RenderResult result = render(params);
    EXPECT_GT(result.stats.hitPixels, 1000u);
    const Image& image = result.image;

    const std::string png8 = (dir_ / "default8.png").string();
    writeImage(image, png8, ImageFormat::Png8);
    const Image read8 = readPng(png8);
    ASSERT_EQ(read8.width, image.width);
    ASSERT_EQ(read8.height, image.height);
    double worst8 = 0.0;
    for (std::size_t pixel = 0; pixel < static_cast<std::size_t>(image.width) * image.height; ++pixel) {
        for (int channel = 0; channel < 3; ++channel)
            worst8 = std::max(worst8, std::abs(encodeSrgb(read8.rgba[4 * pixel + channel]) -
                                               encodeSrgb(image.rgba[4 * pixel + channel])));
        EXPECT_EQ(read8.rgba[4 * pixel + 3], 1.0f);  // written as RGB: opaque
    }
    EXPECT_LE(worst8, 1.0 / 255.0);

    const std::string png16 = (dir_ / "default16.png").string();
    writeImage(image, png16, ImageFormat::Png16);
    const Image read16 = readPng(png16);
    ASSERT_EQ(read16.width, image.width);
    ASSERT_EQ(read16.height, image.height);
    double worst16 = 0.0;
    for (std::size_t pixel = 0; pixel < static_cast<std::size_t>(image.width) * image.height; ++pixel)
        for (int channel = 0; channel < 3; ++channel)
            worst16 = std::max(worst16, std::abs(encodeSrgb(read16.rgba[4 * pixel + channel]) -
                                                 encodeSrgb(image.rgba[4 * pixel + channel])));
    EXPECT_LE(worst16, 1.0 / 65535.0 + 1e-6);  // float storage adds ~1e-7
    EXPECT_LT(worst16, worst8 + 1e-9);

    const fs::path exr = dir_ / "default.exr";
    writeImage(image, exr.string(), ImageFormat::Exr);
    ASSERT_TRUE(fs::exists(exr));
    EXPECT_GT(fs::file_size(exr), 0u);
    std::ifstream file(exr, std::ios::binary);
    unsigned char magic[4] = {};
    file.read(reinterpret_cast<char*>(magic), 4);
    EXPECT_EQ(magic[0], 0x76);
    EXPECT_EQ(magic[1], 0x2f);
    EXPECT_EQ(magic[2], 0x31);
    EXPECT_EQ(magic[3], 0x01);

    EXPECT_EQ(files().size(), 3u) << "temporary files left behind";
}

TEST_F(RenderFiles, FailedWritesLeaveNothing) {
    Image image;
    image.width = 2;
    image.height = 2;
    image.rgba.assign(16, 0.5f);

    // A missing folder: a clear message naming the path, and no file.
    const fs::path missing = dir_ / "missing" / "x.png";
    for (ImageFormat format : {ImageFormat::Png8, ImageFormat::Png16, ImageFormat::Exr}) {
        try {
            writeImage(image, missing.string(), format);
            ADD_FAILURE() << "expected an error writing into a missing folder";
        } catch (const std::runtime_error& error) {
            const std::string message = error.what();
            EXPECT_NE(message.find(missing.string()), std::string::npos) << message;
            EXPECT_NE(message.find("No such file or directory"), std::string::npos) << message;
        }
        EXPECT_FALSE(fs::exists(missing));
    }

    // The target is a folder: the rename fails after the data was written; the temporary
    // file must be gone and the folder untouched.
    const fs::path occupied = dir_ / "occupied.png";
    fs::create_directory(occupied);
    EXPECT_THROW(writeImage(image, occupied.string(), ImageFormat::Png8), std::runtime_error);
    EXPECT_TRUE(fs::is_directory(occupied));
    EXPECT_EQ(files().size(), 1u) << "temporary file left behind";

    // Replacing an existing file works and leaves only that file.
    const fs::path existing = dir_ / "existing.png";
    std::ofstream(existing) << "old";
    writeImage(image, existing.string(), ImageFormat::Png8);
    EXPECT_EQ(readPng(existing.string()).width, 2);
    EXPECT_EQ(files().size(), 2u);

    // Reading something that is not a PNG fails with the path in the message.
    const fs::path text = dir_ / "text.png";
    std::ofstream(text) << "not a png at all";
    try {
        readPng(text.string());
        ADD_FAILURE() << "expected an error reading a non-PNG";
    } catch (const std::runtime_error& error) {
        EXPECT_NE(std::string(error.what()).find(text.string()), std::string::npos) << error.what();
    }
}

TEST(RenderProgress, CallbackSeesIncreasingFractionsEndingAtOne) {
    Params params;  // the default 640 x 480 render takes long enough for several reports
    std::vector<double> fractions;
    const RenderResult result = render(params, [&](double fraction) {
        fractions.push_back(fraction);
        return true;
    });
    ASSERT_FALSE(fractions.empty());
    EXPECT_EQ(fractions.back(), 1.0);
    EXPECT_TRUE(std::is_sorted(fractions.begin(), fractions.end()));
    EXPECT_GE(fractions.front(), 0.0);
    EXPECT_GT(result.stats.hitPixels, 0u);
    std::printf("    %zu progress calls in %.2f s\n", fractions.size(), result.stats.seconds);
}

TEST(RenderProgress, ReturningFalseCancels) {
    // Several seconds of work if it were not cancelled, so the first report (after ~100 ms)
    // comes long before the end.
    Params params;
    params.render.width = 1600;
    params.render.height = 1200;
    std::atomic<int> calls{0};
    const auto start = std::chrono::steady_clock::now();
    EXPECT_THROW(render(params,
                        [&](double) {
                            ++calls;
                            return false;
                        }),
                 Cancelled);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_EQ(calls.load(), 1) << "no calls after cancelling";
    std::printf("    cancelled after %.2f s\n", seconds);
}

// linearToSrgb8 reads a table, not pow: its code must be the formula's (sRGB-encoded, times
// 255, rounded) for every float. Here every 61st float of [0, 1] and each float within 64 of a
// code's step; DQJ_SRGB_EVERY_FLOAT=1 checks all 1,065,353,217 of them (about 30 s).
TEST(Image, Srgb8CodesAreTheFormulas) {
    auto formula = [](float linear) { return int(std::lround(encodeSrgb(linear) * 255.0)); };
    const std::uint32_t one = std::bit_cast<std::uint32_t>(1.0f);
    const std::uint32_t stride = std::getenv("DQJ_SRGB_EVERY_FLOAT") ? 1 : 61;
    std::uint64_t checked = 0, differ = 0;
    int previous = 0;
    for (std::uint32_t bits = 0; bits <= one; bits += stride) {
        const float linear = std::bit_cast<float>(bits);
        const int code = formula(linear);
        // Around a step (the code changes): every float within 64 of it.
        const std::uint32_t from = code != previous && bits >= stride ? bits - stride : bits;
        const std::uint32_t to = code != previous ? std::min(bits + 64, one) : bits;
        for (std::uint32_t near = from; near <= to; ++near) {
            const float x = std::bit_cast<float>(near);
            ++checked;
            differ += dqj::linearToSrgb8(x) != formula(x);
        }
        previous = code;
    }
    EXPECT_EQ(differ, 0u) << "of " << checked;
    EXPECT_GT(checked, one / 61);
    EXPECT_EQ(dqj::linearToSrgb8(-0.5f), 0);
    EXPECT_EQ(dqj::linearToSrgb8(std::nanf("")), 0);
    EXPECT_EQ(dqj::linearToSrgb8(1.5f), 255);
    EXPECT_EQ(dqj::linearToSrgb8(std::numeric_limits<float>::infinity()), 255);
}
