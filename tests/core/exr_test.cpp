// EXR output for compositing: premultiplied surface RGBA over a transparent background,
// depth in Z and normals in N.X/N.Y/N.Z, read back with OpenEXR.
#include <gtest/gtest.h>

#include <filesystem>

#include <ImfHeader.h>
#include <ImfChannelList.h>
#include <ImfInputFile.h>
#include <ImfFrameBuffer.h>

#include "dqjulia/image.hpp"
#include "dqjulia/render.hpp"

namespace dqj {
namespace {

TEST(Exr, HoldsPremultipliedSurfaceDepthAndNormals) {
    // The unit ball (c = 0) seen from (0, 0, 3): the centre pixel's surface is 2 away, facing +z.
    Params params;
    params.fractal.c = DualQuat{};
    params.fractal.variant = Variant::Dual;
    params.bounds = Bounds{glm::dvec3(0.0), 2.0};
    params.camera.position = glm::dvec3(0.0, 0.0, 3.0);
    params.camera.target = glm::dvec3(0.0);
    params.render.width = 33;
    params.render.height = 25;
    params.render.samples = 1;
    params.render.detail = 0.1;  // the ball's DE is half its distance: stop within ~0.01 of it
    const RenderResult result = render(params);
    const std::string path = (std::filesystem::temp_directory_path() / "dqjulia_exr_test.exr").string();
    writeImage(result.image, path, ImageFormat::Exr);

    Imf::InputFile file(path.c_str());
    const auto window = file.header().dataWindow();
    const int width = window.max.x - window.min.x + 1;
    const int height = window.max.y - window.min.y + 1;
    ASSERT_EQ(width, 33);
    ASSERT_EQ(height, 25);
    for (const char* name : {"R", "G", "B", "A", "Z", "N.X", "N.Y", "N.Z"})
        EXPECT_NE(file.header().channels().findChannel(name), nullptr) << name;

    std::vector<std::vector<float>> planes(8, std::vector<float>(std::size_t(width) * height));
    Imf::FrameBuffer frame;
    const char* names[8] = {"R", "G", "B", "A", "Z", "N.X", "N.Y", "N.Z"};
    for (int index = 0; index < 8; ++index)
        frame.insert(names[index], Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(planes[index].data()), sizeof(float),
                                              sizeof(float) * width));
    file.setFrameBuffer(frame);
    file.readPixels(window.min.y, window.max.y);
    std::filesystem::remove(path);

    const std::size_t corner = 0;
    const std::size_t centre = std::size_t(12) * width + 16;
    // Background: transparent black (premultiplied), far depth, no normal.
    for (int channel = 0; channel < 4; ++channel) EXPECT_EQ(planes[channel][corner], 0.0f) << channel;
    EXPECT_GT(planes[4][corner], 1e9f);
    // Surface: opaque, lit, 2 units away, facing the camera.
    EXPECT_EQ(planes[3][centre], 1.0f);
    EXPECT_GT(planes[0][centre] + planes[1][centre] + planes[2][centre], 0.05f);
    EXPECT_NEAR(planes[4][centre], 2.0f, 0.02f);
    EXPECT_NEAR(planes[7][centre], 1.0f, 0.01f);
    // Premultiplied: colour never exceeds alpha times the picture's colour anywhere.
    for (std::size_t pixel = 0; pixel < planes[0].size(); ++pixel)
        for (int channel = 0; channel < 3; ++channel)
            EXPECT_LE(planes[channel][pixel], result.image.rgba[4 * pixel + channel] + 1e-3f) << pixel;
}

}  // namespace
}  // namespace dqj
