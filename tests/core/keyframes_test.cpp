// Keyframes (keyframes.hpp): the parameter file's "animation" section interpolated linearly and
// smoothly, and bad keyframes refused with the key.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "dqjulia/params.hpp"

using namespace dqj;

namespace {

TEST(Animation, KeyframesInterpolateLinearlyAndSmoothly) {
    const Params params = parseParams(R"({
      "slice": {"rotations": [{"plane": "a.j,b.s", "degrees": 0}]},
      "animation": {
        "fractal.iterations": [{"frame": 1, "value": 10}, {"frame": 11, "value": 20}],
        "slice.rotations[0].degrees": [{"frame": 0, "value": 0, "interpolation": "smooth"},
                                       {"frame": 10, "value": 90, "interpolation": "smooth"},
                                       {"frame": 20, "value": 100}],
        "fractal.c": [{"frame": 1, "value": [-0.39054, -0.58679, 0, 0, 0, 0.5632, 0, 0.05]},
                      {"frame": 5, "value": [-0.2, -0.58679, 0, 0, 0, 0.5632, 0, 0.05]}]
      }})");
    EXPECT_EQ(atFrame(params, -3).fractal.iterations, 10);  // before the first key: the first value
    EXPECT_EQ(atFrame(params, 6).fractal.iterations, 15);
    EXPECT_EQ(atFrame(params, 6.4).fractal.iterations, 15);  // rounded
    EXPECT_EQ(atFrame(params, 99).fractal.iterations, 20);
    EXPECT_NEAR(scalarPart(atFrame(params, 3).fractal.c.a), -0.29527, 1e-12);
    // Smooth: through the keys, flat at the ends, never overshooting, rising monotonically.
    auto degrees = [&](double frame) { return atFrame(params, frame).slice.rotations[0].degrees; };
    EXPECT_DOUBLE_EQ(degrees(10), 90.0);
    EXPECT_NEAR(degrees(0.01), 0.0, 1e-3);
    double previous = -1.0;
    for (double frame = 0; frame <= 20; frame += 0.25) {
        EXPECT_GE(degrees(frame), previous);
        EXPECT_LE(degrees(frame), 100.0);
        previous = degrees(frame);
    }
    EXPECT_LT(degrees(5), 45.0 + 20.0);
    // The document round-trips.
    EXPECT_EQ(toJson(parseParams(toJson(params))), toJson(params));
}

TEST(Animation, BadKeyframesAreRejectedWithTheKey) {
    const std::vector<std::pair<std::string, std::string>> cases = {
        {R"({"animation": {"fractal.iterations": [{"frame": 5, "value": 10}, {"frame": 2, "value": 12}]}})",
         "frames must increase"},
        {R"({"animation": {"fractal.variant": [{"frame": 1, "value": 1}]}})", "cannot be animated"},
        {R"({"animation": {"fractal.iterations": [{"frame": 1, "value": 10.5}]}})", "whole number"},
        {R"({"animation": {"fractal.c": [{"frame": 1, "value": [1, 2]}]}})", "array of 8 numbers"},
        {R"({"animation": {"slice.rotations[2].degrees": [{"frame": 1, "value": 3}]}})", "slice.rotations has 0"},
        {R"({"animation": {"fractal.bailout": [{"frame": 1, "value": 1.2}]}})", "at frame 1"},
        {R"({"animation": {"fractal.iterations": [{"frame": 1, "value": 10, "interpolation": "cubic"}]}})",
         "linear, smooth"},
        {R"({"animation": {"fractal.iterations": []}})", "non-empty array"},
    };
    for (const auto& [json, message] : cases) {
        try {
            parseParams(json);
            ADD_FAILURE() << "accepted: " << json;
        } catch (const ParamError& error) {
            EXPECT_NE(std::string(error.what()).find(message), std::string::npos) << error.what();
        }
    }
}

}  // namespace
