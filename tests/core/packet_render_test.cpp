// The packet renderer (rays of a tile marched together through the SIMD batch kernel) against
// the scalar one (evaluate() one point at a time): the same pictures. Both run the same marching
// and shading logic; the packet engine evaluates in float where the derivative cannot overflow
// (all the scenes here), whose DE differs from evaluate()'s by a small fraction of the hit
// threshold at the distances the marcher probes, so at least 99.5% of pixels must agree within 2/255 in every 8-bit channel
// (in practice all of them, within 1/255), the silhouettes must agree, and so must the
// statistics that count steps and hits.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>

#include "dqjulia/image.hpp"
#include "dqjulia/render.hpp"

using namespace dqj;

namespace {

struct Agreement {
    std::size_t pixels = 0;
    std::size_t within = 0;      // every channel within 2/255 (8-bit sRGB, alpha linear)
    std::size_t silhouette = 0;  // alpha > 0.5 in one and not the other
    int worst = 0;               // largest 8-bit difference
};

int code(float value, bool alpha) {
    return alpha ? static_cast<int>(std::lround(std::clamp(value, 0.0f, 1.0f) * 255.0f)) : linearToSrgb8(value);
}

Agreement compare(const Image& packet, const Image& scalar) {
    Agreement agreement;
    agreement.pixels = static_cast<std::size_t>(packet.width) * packet.height;
    for (std::size_t pixel = 0; pixel < agreement.pixels; ++pixel) {
        int largest = 0;
        for (int channel = 0; channel < 4; ++channel) {
            const std::size_t at = 4 * pixel + channel;
            largest =
                std::max(largest, std::abs(code(packet.rgba[at], channel == 3) - code(scalar.rgba[at], channel == 3)));
        }
        agreement.worst = std::max(agreement.worst, largest);
        if (largest <= 2) ++agreement.within;
        if ((packet.rgba[4 * pixel + 3] > 0.5f) != (scalar.rgba[4 * pixel + 3] > 0.5f)) ++agreement.silhouette;
    }
    return agreement;
}

void expectSamePicture(const Params& params, const std::string& what) {
    const RenderResult packet = render(params, {}, RenderEngine::Packet);
    const RenderResult scalar = render(params, {}, RenderEngine::Scalar);
    ASSERT_EQ(packet.image.width, scalar.image.width);
    ASSERT_EQ(packet.image.height, scalar.image.height);
    const Agreement agreement = compare(packet.image, scalar.image);
    std::printf(
        "%s: %zu of %zu pixels within 2/255, %zu silhouette differences, worst %d/255; packet %.3f s, scalar %.3f s\n",
        what.c_str(), agreement.within, agreement.pixels, agreement.silhouette, agreement.worst, packet.stats.seconds,
        scalar.stats.seconds);
    EXPECT_GE(agreement.within, agreement.pixels * 995 / 1000) << what;
    EXPECT_LE(agreement.silhouette, agreement.pixels / 1000) << what;
    EXPECT_EQ(packet.stats.rays, scalar.stats.rays) << what;
    // Steps and hits may differ only where a last-bit difference in the DE flips a decision.
    EXPECT_NEAR(static_cast<double>(packet.stats.steps), static_cast<double>(scalar.stats.steps),
                1e-3 * scalar.stats.steps)
        << what;
    EXPECT_NEAR(static_cast<double>(packet.stats.hitPixels), static_cast<double>(scalar.stats.hitPixels),
                1e-3 * agreement.pixels)
        << what;
}

Params smallParams() {
    Params params;  // the default fractal: paper variant, the paper's high-detail constant, N = 15
    params.render.width = 200;
    params.render.height = 150;
    return params;
}

}  // namespace

TEST(PacketRender, DefaultFractalMatchesTheScalarRenderer) {
    expectSamePicture(smallParams(), "default (paper, trap colouring, central-difference normals, 2x2 samples)");
}

TEST(PacketRender, QuaternionJuliaWithAnalyticNormalsMatches) {
    Params params = smallParams();
    params.fractal.variant = Variant::Dual;
    params.fractal.c = DualQuat{makeQuat(-0.083, 0.0, -0.83, -0.025), makeQuat(0, 0, 0, 0)};
    params.fractal.iterations = 12;
    params.fractal.bailout = 2.0;
    params.render.samples = 1;
    expectSamePicture(params, "dual, zero dual constant, N = 12, analytic normals");
}

TEST(PacketRender, PaperCoupledTurnedSliceWithIterationColouringMatches) {
    Params params = smallParams();
    params.fractal.variant = Variant::PaperCoupled;
    params.fractal.bailout = minimumBailout(params.fractal) + 0.5;
    params.slice.base = sliceFromAxisNames("a.i,a.j,b.s");
    params.slice.rotations = {{0, 4, 20.0}};
    params.material.coloring = Coloring::Iterations;
    params.material.shadows = false;
    expectSamePicture(params, "paper-coupled, turned slice through a dual axis, no shadows");
}

TEST(PacketRender, ClippedExtrusionAndNoOcclusionMatch) {
    Params params = smallParams();
    params.fractal.variant = Variant::Dual;
    params.slice.base = sliceFromAxisNames("a.s,a.i,b.s");  // extrusion along a dual axis: clipped by the bounds
    params.material.occlusion = 0.0;
    params.render.samples = 1;
    expectSamePicture(params, "dual, slice along a dual axis (cut faces), no occlusion");
}

// N log2(2R) = 40 * 3 >= 100: the derivative could overflow float, so the packet engine takes
// the double kernel (render.cpp, Scene::floatKernel) and must match as well.
TEST(PacketRender, DeepIterationsTakeTheDoubleKernelAndMatch) {
    Params params = smallParams();
    params.fractal.variant = Variant::Dual;
    params.fractal.c = DualQuat{makeQuat(-0.083, 0.0, -0.83, -0.025), makeQuat(0, 0, 0, 0)};
    params.fractal.iterations = 40;
    params.fractal.bailout = 4.0;
    params.render.samples = 1;
    expectSamePicture(params, "dual, N = 40, R = 4 (the double kernel)");
}
