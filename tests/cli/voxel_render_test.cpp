// `dqjulia render --voxels`: a bake drawn as cubes (the paper's "Voxel vs Ray-Traced" figure)
// lines up with the traced picture of the same view: the same silhouette, depth within a voxel,
// the same background, and faces that are cube faces. A coarser bake loses detail the tracer keeps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <ImfChannelList.h>
#include <ImfFrameBuffer.h>
#include <ImfHeader.h>
#include <ImfInputFile.h>

#include "dqjulia/image.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

namespace {

constexpr int kWidth = 96;
constexpr int kHeight = 72;

/// An EXR as written by `render -o x.exr`: alpha, depth (1e10 for misses) and normals.
struct ExrPlanes {
    std::vector<float> alpha, depth, nx, ny, nz;
};

ExrPlanes readExr(const std::string& path) {
    Imf::InputFile file(path.c_str());
    const auto window = file.header().dataWindow();
    const int width = window.max.x - window.min.x + 1;
    const int height = window.max.y - window.min.y + 1;
    EXPECT_EQ(width, kWidth);
    EXPECT_EQ(height, kHeight);
    const std::size_t pixels = std::size_t(width) * height;
    ExrPlanes planes{std::vector<float>(pixels), std::vector<float>(pixels), std::vector<float>(pixels),
                     std::vector<float>(pixels), std::vector<float>(pixels)};
    Imf::FrameBuffer frame;
    const std::pair<const char*, std::vector<float>*> channels[] = {
        {"A", &planes.alpha}, {"Z", &planes.depth}, {"N.X", &planes.nx}, {"N.Y", &planes.ny}, {"N.Z", &planes.nz}};
    for (const auto& [name, plane] : channels)
        frame.insert(name, Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(plane->data()), sizeof(float),
                                      sizeof(float) * std::size_t(width)));
    file.setFrameBuffer(frame);
    file.readPixels(window.min.y, window.max.y);
    return planes;
}

/// Pixels at least half covered.
std::vector<bool> silhouette(const std::vector<float>& alpha) {
    std::vector<bool> mask(alpha.size());
    for (std::size_t index = 0; index < alpha.size(); ++index) mask[index] = alpha[index] >= 0.5f;
    return mask;
}

double coverage(const std::vector<bool>& mask) {
    return double(std::count(mask.begin(), mask.end(), true)) / double(mask.size());
}

/// Intersection over union of two silhouettes.
double iou(const std::vector<bool>& a, const std::vector<bool>& b) {
    std::size_t both = 0, either = 0;
    for (std::size_t index = 0; index < a.size(); ++index) {
        both += a[index] && b[index];
        either += a[index] || b[index];
    }
    return either ? double(both) / double(either) : 0.0;
}

/// The silhouette's centre in pixels (x, y).
std::pair<double, double> centroid(const std::vector<bool>& mask) {
    double x = 0.0, y = 0.0, count = 0.0;
    for (std::size_t index = 0; index < mask.size(); ++index)
        if (mask[index]) {
            const std::size_t row = index / kWidth, column = index % kWidth;
            x += double(column);
            y += double(row);
            ++count;
        }
    return {x / count, y / count};
}

class VoxelRender : public dqj::test::ScratchFolder {
protected:
    /// Runs `dqjulia <arguments>`; fails the test if it does not exit 0.
    void run(const std::string& arguments) {
        const dqj::test::CommandResult result = dqj::test::runCommand(DQJ_CLI, arguments, dir_, "");
        ASSERT_EQ(result.exitCode, 0) << arguments << "\n" << result.err;
    }
    /// `render` of the same view: traced, or the voxels of `vdb` when it is given.
    void render(const std::string& fractal, const std::string& output, const std::string& vdb = "") {
        run("render -q -s 1 -W " + std::to_string(kWidth) + " -H " + std::to_string(kHeight) + " " + fractal +
            (vdb.empty() ? "" : " --voxels " + path(vdb)) + " -o " + path(output));
    }
};

TEST_F(VoxelRender, TheUnitBallAsCubesLinesUpWithTheTracedBall) {
    // c = 0 under the true algebra is the unit ball; baked in a box of side 3 at 24 voxels across.
    const std::string ball = "--c 0 0 0 0 0 0 0 0 --variant dual";
    const double voxel = 3.0 / 24;
    run("bake -q -r 24 " + ball + " --bounds-min -1.5 -1.5 -1.5 --bounds-max 1.5 1.5 1.5 -o " + path("ball.vdb"));
    ASSERT_NO_FATAL_FAILURE(render(ball, "traced.exr"));
    ASSERT_NO_FATAL_FAILURE(render(ball, "voxels.exr", "ball.vdb"));
    ASSERT_NO_FATAL_FAILURE(render(ball, "traced.png"));
    ASSERT_NO_FATAL_FAILURE(render(ball, "voxels.png", "ball.vdb"));
    const ExrPlanes traced = readExr(path("traced.exr")), voxels = readExr(path("voxels.exr"));
    const std::vector<bool> tracedMask = silhouette(traced.alpha), voxelMask = silhouette(voxels.alpha);

    // The cubes are the voxels of density >= 0.5, and the fog ramps from 0 at the surface to 1
    // three voxels inside: they sit about 1.5 voxels within the ball, their silhouette a ring of
    // 2 - 4 pixels inside the traced one here (IoU measured 0.795), and never outside it.
    EXPECT_GT(coverage(voxelMask), 0.05) << "the voxels are not drawn";
    EXPECT_LT(coverage(voxelMask), 0.9) << "the voxels fill the picture";
    EXPECT_GE(iou(tracedMask, voxelMask), 0.75) << "the cubes are not where the ball is";
    std::size_t outside = 0;
    for (std::size_t index = 0; index < voxelMask.size(); ++index) outside += voxelMask[index] && !tracedMask[index];
    EXPECT_LE(outside, 5u) << "cubes outside the ball";
    const auto [tx, ty] = centroid(tracedMask);
    const auto [vx, vy] = centroid(voxelMask);
    EXPECT_NEAR(vx, tx, 0.5);
    EXPECT_NEAR(vy, ty, 0.5);
    // Seen straight on (the ray through the ball's centre), the cube face is that much behind the sphere.
    const std::size_t centre = std::size_t(kHeight / 2) * kWidth + kWidth / 2;
    ASSERT_TRUE(voxelMask[centre] && tracedMask[centre]);
    const double gap = double(voxels.depth[centre]) - traced.depth[centre];
    EXPECT_GT(gap, 0.5 * voxel);
    EXPECT_LT(gap, 2.0 * voxel);

    // Every face is a cube's: its normal is a coordinate axis. The traced ball's are not.
    std::size_t hits = 0, axisAligned = 0, bothHit = 0, tracedAxisAligned = 0;
    auto isAxis = [](const ExrPlanes& planes, std::size_t index) {
        const float n[3] = {std::abs(planes.nx[index]), std::abs(planes.ny[index]), std::abs(planes.nz[index])};
        return std::count(n, n + 3, 1.0f) == 1 && std::count(n, n + 3, 0.0f) == 2;
    };
    for (std::size_t index = 0; index < voxelMask.size(); ++index) {
        if (voxels.alpha[index] != 1.0f) continue;
        ++hits;
        axisAligned += isAxis(voxels, index);
        if (traced.alpha[index] != 1.0f) continue;
        ++bothHit;
        tracedAxisAligned += isAxis(traced, index);
    }
    ASSERT_GT(hits, 100u);
    EXPECT_EQ(axisAligned, hits) << "a face whose normal is no coordinate axis";
    EXPECT_LT(tracedAxisAligned, bothHit / 10);
    std::printf("    IoU %.3f, %zu pixels outside, centre %.3f behind the sphere (voxel %.3f)\n",
                iou(tracedMask, voxelMask), outside, gap, voxel);

    // Where neither picture has the ball, both show render()'s background.
    const dqj::Image tracedPng = dqj::readPng(path("traced.png")), voxelPng = dqj::readPng(path("voxels.png"));
    std::size_t background = 0;
    float largestDifference = 0.0f;
    for (std::size_t index = 0; index < voxelMask.size(); ++index) {
        if (traced.alpha[index] != 0.0f || voxels.alpha[index] != 0.0f) continue;
        ++background;
        for (int channel = 0; channel < 3; ++channel)
            largestDifference = std::max(largestDifference, std::abs(tracedPng.rgba[4 * index + channel] -
                                                                     voxelPng.rgba[4 * index + channel]));
    }
    EXPECT_GT(background, voxelMask.size() / 4);
    EXPECT_LE(largestDifference, 1.0f / 255) << "the background differs from render()'s";
}

TEST_F(VoxelRender, ACoarserBakeLosesDetailTheTracerKeeps) {
    // The default fractal, as `dqjulia bake` makes it, at a coarse and a finer resolution.
    run("bake -q -r 16 -o " + path("coarse.vdb"));
    run("bake -q -r 64 -o " + path("fine.vdb"));
    ASSERT_NO_FATAL_FAILURE(render("", "traced.exr"));
    ASSERT_NO_FATAL_FAILURE(render("", "coarse.exr", "coarse.vdb"));
    ASSERT_NO_FATAL_FAILURE(render("", "fine.exr", "fine.vdb"));
    const std::vector<bool> traced = silhouette(readExr(path("traced.exr")).alpha);
    const std::vector<bool> coarse = silhouette(readExr(path("coarse.exr")).alpha);
    const std::vector<bool> fine = silhouette(readExr(path("fine.exr")).alpha);
    ASSERT_GT(coverage(traced), 0.05);
    EXPECT_GT(coverage(coarse), 0.02);
    EXPECT_GT(coverage(fine), 0.05);
    const double coarseIou = iou(traced, coarse), fineIou = iou(traced, fine);
    std::printf("    IoU with the traced picture: %.3f at 16^3, %.3f at 64^3\n", coarseIou, fineIou);
    // Measured 0.467 and 0.697 (0.752 at 160^3): the default fractal has parts thinner than the
    // 1.5 voxels by which the cubes sit inside the surface, so they vanish at coarse resolutions.
    EXPECT_GE(fineIou, 0.6);
    EXPECT_LT(coarseIou, fineIou - 0.1);
}

}  // namespace
