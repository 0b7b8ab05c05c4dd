// The parameter file: defaults, round trips, and one clear message per bad value.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "dqjulia/estimate.hpp"
#include "dqjulia/params.hpp"

namespace dqj {
namespace {

std::string errorOf(const std::string& json) {
    try {
        parseParams(json, "test.json");
    } catch (const ParamError& error) {
        return error.what();
    }
    return "";
}

TEST(Params, EmptyDocumentGivesValidDefaults) {
    const Params params = parseParams("{}");
    EXPECT_EQ(params.fractal.variant, Variant::Paper);
    EXPECT_EQ(params.fractal.iterations, 15);
    EXPECT_EQ(params.fractal.bailout, 4.0);
    EXPECT_EQ(axisNamesOf(params.slice.base), "a.s,a.i,a.j");
    EXPECT_NO_THROW(validate(params));
}

TEST(Params, RoundTripKeepsEveryValue) {
    const std::string json = R"({
      "description": "round trip",
      "fractal": {"c": [0.1, -0.2, 0.3, -0.4, 0.05, 0.06, -0.07, 0.08], "variant": "dual", "iterations": 33, "bailout": 16},
      "slice": {"axes": "a.i,a.j,b.s", "origin": [0, 0, 0, 0.1, 0, 0, 0, 0], "rotations": [{"plane": "a.j,b.k", "degrees": 30}]},
      "bounds": {"center": [0.1, 0.2, 0.3], "radius": 1.7},
      "camera": {"position": [0, 0, 4], "target": [0, 0.1, 0], "up": [0, 1, 0], "fov": 35},
      "lights": [{"direction": [1, 2, 3], "color": [1, 0.5, 0.25], "intensity": 2}],
      "material": {"coloring": "iterations", "palette": [[1, 0, 0], [0, 0, 1]], "shininess": 50, "shadows": false},
      "render": {"width": 320, "height": 200, "samples": 3, "normals": "analytic", "background": [0.1, 0.2, 0.3]},
      "output": {"path": "out/x.exr", "format": "exr"}
    })";
    const Params first = parseParams(json);
    const Params second = parseParams(toJson(first));
    EXPECT_EQ(toJson(first), toJson(second));
    EXPECT_EQ(second.description, "round trip");
    EXPECT_EQ(second.fractal.iterations, 33);
    EXPECT_EQ(second.fractal.variant, Variant::Dual);
    EXPECT_DOUBLE_EQ(second.fractal.c.b.z, 0.08);  // b's k component
    EXPECT_EQ(axisNamesOf(second.slice.base), "a.i,a.j,b.s");
    ASSERT_EQ(second.slice.rotations.size(), 1u);
    EXPECT_EQ(second.slice.rotations[0].first, 2);
    EXPECT_EQ(second.slice.rotations[0].second, 7);
    ASSERT_TRUE(second.bounds.has_value());
    EXPECT_DOUBLE_EQ(second.bounds->radius, 1.7);
    ASSERT_TRUE(second.camera.position.has_value());
    EXPECT_EQ(second.lights.size(), 1u);
    EXPECT_EQ(second.material.coloring, Coloring::Iterations);
    EXPECT_FALSE(second.material.shadows);
    EXPECT_EQ(second.render.samples, 3);
    EXPECT_EQ(second.render.normals, NormalMethod::Analytic);
    EXPECT_EQ(formatFor(second.output), ImageFormat::Exr);
}

TEST(Params, FullSliceFormReadsAxisVectors) {
    const Params params =
        parseParams(R"({"slice": {"axes": [[0.6,0.8,0,0,0,0,0,0],[-0.8,0.6,0,0,0,0,0,0],[0,0,0,0,1,0,0,0]]}})");
    EXPECT_DOUBLE_EQ(params.slice.base.axes[0][1], 0.8);
    EXPECT_DOUBLE_EQ(params.slice.base.axes[2][4], 1.0);
    EXPECT_EQ(axisNamesOf(params.slice.base), "");
}

TEST(Params, EachBadValueNamesItsKey) {
    struct Case {
        const char* json;
        const char* expected;
    };
    const Case cases[] = {
        {R"({"fractal": {"iterations": 0}})",
         "test.json: fractal.iterations: must be a whole number from 1 to 100000, got 0"},
        {R"({"fractal": {"iterations": 2.5}})", "fractal.iterations: must be a whole number"},
        {R"({"fractal": {"variant": "octonion"}})",
         "fractal.variant: must be one of paper, paper-coupled, dual, got \"octonion\""},
        {R"({"fractal": {"c": [1, 2]}})", "fractal.c: must be an array of 8 numbers"},
        // one axis vector short (found by the fuzzer): named, not an internal error
        {R"({"slice": {"axes": [[1,0,0,0,0,0,0,0],[0,1,0,0,0,0,0],[0,0,1,0,0,0,0,0]]}})",
         "slice.axes[1]: must be an array of 8 numbers"},
        {R"({"slice": {"axes": [[1,0,0,0,0,0,0,0],[0,1,0,0,0,0,0,0],[0,0,1,0,0,0,0,"z"]]}})",
         "slice.axes[2][7]: must be a number"},
        {R"({"fractal": {"c": [0, 0, 0, 0, 0, 0, 0, "x"]}})", "fractal.c[7]: must be a number"},
        {R"({"fractal": {"c": [0, 0, 0, 0, 0, 0, 0, 1e999]}})",
         "test.json: malformed JSON: number overflow parsing '1e999'"},
        {R"({"fractal": {"bailout": 1.2}})", "fractal.bailout: is 1.2 but must be at least the containment radius"},
        {R"({"fractal": {"iteratons": 3}})", "unknown key \"iteratons\"; did you mean \"iterations\"?"},
        {R"({"fractl": {}})", "did you mean \"fractal\"?"},
        {R"({"slice": {"axes": "a.s,a.i"}})", "slice.axes: a slice names exactly 3 axes"},
        {R"({"slice": {"rotations": [{"plane": "a.s,a.s", "degrees": 3}]}})", "slice.rotations[0].plane"},
        {R"({"slice": {"axes": [[0,0,0,0,0,0,0,0],[0,1,0,0,0,0,0,0],[0,0,1,0,0,0,0,0]]}})",
         "slice.axes: the three axes are zero or parallel"},
        {R"({"camera": {"fov": 0}})", "camera.fov"},
        {R"({"camera": {"position": [0, 0, 3], "target": [0, 0, 3]}})", "camera.position: equals camera.target"},
        {R"({"camera": {"up": [0, 0, 0]}})", "camera.up"},
        {R"({"lights": [{"direction": [0, 0, 0]}]})", "lights[0].direction"},
        {R"({"material": {"palette": []}})", "material.palette"},
        {R"({"material": {"occlusion": 3}})", "material.occlusion: must be at least 0 and at most 1, got 3"},
        {R"({"render": {"samples": 0}})", "render.samples"},
        {R"({"render": {"normals": "analytic"}})", "render.normals: \"analytic\" normals"},
        {R"({"output": {"path": "x.tiff"}})", "output.path"},
        {R"({"version": 2})", "version"},
        {R"([1, 2])", "must be an object"},
        {"{\n  \"fractal\": {\n    \"iterations\": 5,\n  }\n}", "test.json: line 4, column 3: malformed JSON"},
    };
    for (const Case& c : cases) {
        const std::string message = errorOf(c.json);
        EXPECT_NE(message.find(c.expected), std::string::npos) << "input: " << c.json << "\nmessage: " << message;
    }
}

TEST(Params, MissingFileIsAParamError) {
    try {
        loadParams("/no/such/params.json");
        FAIL() << "no error";
    } catch (const ParamError& error) {
        EXPECT_NE(std::string(error.what()).find("/no/such/params.json"), std::string::npos);
    }
}

TEST(Params, TypesOnlyDefersCrossFieldRules) {
    // A file whose bailout is too small for its constant can still be loaded for overriding.
    const std::string json = R"({"fractal": {"bailout": 1.2}})";
    EXPECT_THROW(parseParams(json), ParamError);
    Params params = parseParams(json, "x", Validation::TypesOnly);
    params.fractal.bailout = 8.0;
    EXPECT_NO_THROW(validate(params));
}

// --- Keyframes: checkFrames finds what checking every frame finds ----------------------------

/// The message validAtFrame gives at the first frame of [first, last] it refuses, or "".
std::string everyFrameRefusal(const Params& params, int first, int last) {
    for (int frame = first; frame <= last; ++frame) {
        try {
            validAtFrame(params, frame);
        } catch (const ParamError& error) {
            return error.what();
        }
    }
    return "";
}

std::string checkFramesRefusal(const Params& params, int first, int last) {
    try {
        checkFrames(params, first, last);
    } catch (const ParamError& error) {
        return error.what();
    }
    return "";
}

TEST(Keyframes, ConstantsPeakingBetweenKeysAreFoundAtTheirFrame) {
    // Two smooth components of c, each monotone, peak together between frames 10 and 20: |c|
    // there exceeds every key's, and the bailout, enough for the keys, is too small.
    const Params params = parseParams(R"({"fractal": {"c": [1, 0, 0, 0, 0, 0, 0, 0], "bailout": 10}, "animation": {
      "fractal.c": [{"frame": 9, "value": [1, -1, 0, 0, 0, 0, 0, 0], "interpolation": "smooth"},
                    {"frame": 10, "value": [1, 0, 0, 0, 0, 0, 0, 0], "interpolation": "smooth"},
                    {"frame": 20, "value": [0, 1, 0, 0, 0, 0, 0, 0], "interpolation": "smooth"},
                    {"frame": 21, "value": [-1, 1, 0, 0, 0, 0, 0, 0]}],
      "fractal.bailout": [{"frame": 9, "value": 10}, {"frame": 10, "value": 1.62},
                          {"frame": 20, "value": 1.62}, {"frame": 21, "value": 10}]}})");
    const std::string refusal = checkFramesRefusal(params, 1, 30);
    EXPECT_EQ(refusal, everyFrameRefusal(params, 1, 30));
    EXPECT_EQ(refusal.rfind("at frame 11: fractal.bailout: is 1.62 but must be at least", 0), 0u) << refusal;
    EXPECT_EQ(checkFramesRefusal(params, 1, 10), "");  // no whole frame between the keys
    EXPECT_EQ(checkFramesRefusal(params, 21, 999999), "");
    EXPECT_EQ(checkFramesRefusal(params, 19, 999999).rfind("at frame 19: ", 0), 0u);
}

TEST(Keyframes, EachRuleIsCheckedOverItsTracksKeys) {
    // The constant's keys span frames 10-20, the bailout's 0-30, a rotation's 5-8: checkFrames
    // applies each rule's tracks only, over their span, and must agree with checking every frame.
    Fractal small, large;
    large.c = toDualQuat(Vec8{1.2, 0.9, 0, 0, 0.5, 0, 0, 0});
    small.c = toDualQuat(Vec8{0.1, 0, 0, 0, 0, 0, 0, 0});
    for (const double margin : {1.0, 1.3}) {
        const double first = minimumBailout(small) * 1.01, enough = minimumBailout(large) * margin;
        char document[1024];
        std::snprintf(document, sizeof document, R"({"slice": {"rotations": [{"plane": "a.s,b.s", "degrees": 0}]},
          "animation": {
          "fractal.c": [{"frame": 10, "value": [0.1, 0, 0, 0, 0, 0, 0, 0]}, {"frame": 20, "value": [1.2, 0.9, 0, 0, 0.5, 0, 0, 0]}],
          "fractal.bailout": [{"frame": 0, "value": %.17g}, {"frame": 30, "value": %.17g}],
          "slice.rotations[0].degrees": [{"frame": 5, "value": 0}, {"frame": 8, "value": 90, "interpolation": "smooth"}]}})",
                      first, first + 1.5 * (enough - first));
        const Params params = parseParams(document);  // the keys pass
        EXPECT_EQ(checkFramesRefusal(params, -5, 40), everyFrameRefusal(params, -5, 40)) << margin;
        EXPECT_EQ(checkFramesRefusal(params, 20, 999999), "");
    }
    // Without a track of the constant, r_K stays and a bailout between passing keys passes.
    const Params bailoutOnly = parseParams(R"({"fractal": {"bailout": 100}, "animation": {
      "fractal.bailout": [{"frame": 0, "value": 2.1}, {"frame": 30, "value": 90, "interpolation": "smooth"},
                          {"frame": 60, "value": 3}]}})");
    EXPECT_EQ(checkFramesRefusal(bailoutOnly, 0, 999999), "");
    EXPECT_EQ(everyFrameRefusal(bailoutOnly, 0, 70), "");
}

TEST(Keyframes, CheckFramesAgreesWithEveryFrameOnRandomAnimations) {
    // Random tracks of c and the bailout, linear and smooth, keys at fractional frames too, with
    // the bailout at each key of c just above that key's r_K (so the frames between keys fall on
    // either side of the rule), and a rotation and an iteration count animated across the whole
    // range (their keys outside it, so that every key passes): checkFrames must
    // refuse exactly where, and with the message that, checking every frame does.
    std::mt19937_64 random(35);
    auto uniform = [&](double low, double high) { return low + (high - low) * double(random() >> 11) * 0x1.0p-53; };
    auto number = [](double value) {
        char text[32];
        std::snprintf(text, sizeof text, "%.17g", value);
        return std::string(text);
    };
    auto interpolation = [&] { return random() % 2 ? ", \"interpolation\": \"smooth\"}" : "}"; };
    int compared = 0, refused = 0;
    for (int trial = 0; trial < 120; ++trial) {
        const bool coupled = random() % 2;
        std::string c = "[", bailout = "[";
        double frame = uniform(-2, 4);
        for (int key = 0, keys = 2 + int(random() % 3); key < keys; ++key) {
            Vec8 value{};
            for (const int k : {0, 1, 2, 4}) value[k] = uniform(-1.5, 1.5);
            Fractal fractal;
            fractal.c = toDualQuat(value);
            fractal.variant = coupled ? Variant::PaperCoupled : Variant::Paper;
            std::string components;
            for (int k = 0; k < 8; ++k) components += (k ? ", " : "") + number(value[k]);
            const std::string separator = key ? ", " : "";
            c += separator + "{\"frame\": " + number(frame) + ", \"value\": [" + components + "]" + interpolation();
            bailout += separator + "{\"frame\": " + number(frame) +
                       ", \"value\": " + number(minimumBailout(fractal) * uniform(1.0, 1.005)) + interpolation();
            frame += random() % 3 ? std::floor(uniform(1, 12)) : uniform(0.3, 12);
        }
        const std::string document =
            R"({"fractal": {"variant": ")" + std::string(coupled ? "paper-coupled" : "paper") +
            R"(", "bailout": 40}, "slice": {"axes": "a.s,a.i,b.s", "rotations": [{"plane": "b.s,a.j", "degrees": 0}]},
              "animation": {"fractal.c": )" +
            c + "], \"fractal.bailout\": " + bailout + R"(],
                "slice.rotations[0].degrees": [{"frame": -30, "value": -30, "interpolation": "smooth"},
                                               {"frame": 60, "value": 400}],
                "fractal.iterations": [{"frame": -10, "value": 3}, {"frame": 50, "value": 20}]}})";
        const Params params = parseParams(document);  // the keys pass by construction
        const std::string expected = everyFrameRefusal(params, -2, 30);
        EXPECT_EQ(checkFramesRefusal(params, -2, 30), expected) << document;
        ++compared;
        refused += !expected.empty();
    }
    // Both outcomes happen often enough for the comparison to mean something.
    EXPECT_GT(refused, 20) << compared;
    EXPECT_GT(compared - refused, 20);
}

TEST(Keyframes, ValuesBetweenKeysNeverLeaveTheKeys) {
    // The bound checkFrames relies on, in floating point: each value lies between its two keys',
    // for huge and tiny values, uneven spacing, both interpolations.
    std::mt19937_64 random(12);
    auto uniform = [&](double low, double high) { return low + (high - low) * double(random() >> 11) * 0x1.0p-53; };
    for (int trial = 0; trial < 200; ++trial) {
        Params params;
        Track track;
        track.target = AnimatedValue::Bailout;
        double frame = 0;
        for (int key = 0; key < 5; ++key) {
            const double value = trial % 2 ? std::pow(10.0, uniform(0, 150)) : uniform(1, 1 + 1e-9);
            track.keys.push_back({frame, {value}, random() % 2 ? Interpolation::Smooth : Interpolation::Linear});
            frame += random() % 2 ? uniform(1e-6, 1e-3) : uniform(1, 1e6);
        }
        params.animation = {track};
        for (std::size_t key = 0; key + 1 < track.keys.size(); ++key) {
            const double from = track.keys[key].frame, to = track.keys[key + 1].frame;
            const double low = std::min(track.keys[key].value[0], track.keys[key + 1].value[0]);
            const double high = std::max(track.keys[key].value[0], track.keys[key + 1].value[0]);
            for (int step = 0; step <= 64; ++step) {
                const double value = atFrame(params, from + (to - from) * step / 64).fractal.bailout;
                ASSERT_GE(value, low) << trial << " " << key << " " << step;
                ASSERT_LE(value, high) << trial << " " << key << " " << step;
            }
        }
    }
}

TEST(BakeParams, TheBakeSectionRoundTripsAndIsChecked) {
    const Params params = parseParams(R"({"bake": {"resolution": 96, "bounds": {"min": [-1, -1, -1], "max": [1, 2, 1]},
        "band_width": 2, "grids": ["density", "color"], "adaptivity": 0.25, "mesh_colors": false}})");
    EXPECT_EQ(params.bake.resolution, 96);
    EXPECT_EQ(params.bake.bounds->max.y, 2.0);
    EXPECT_EQ(params.bake.grids, (std::vector<BakeGrid>{BakeGrid::Density, BakeGrid::Color}));
    EXPECT_FALSE(params.bake.meshColors);
    EXPECT_EQ(toJson(parseParams(toJson(params))), toJson(params));
    const std::vector<std::pair<std::string, std::string>> bad = {
        {R"({"bake": {"resolution": 4}})", "bake.resolution"},
        {R"({"bake": {"grids": ["surface", "surface"]}})", "twice"},
        {R"({"bake": {"grids": ["fog"]}})", "surface, density, color, trap, iterations"},
        {R"({"bake": {"bounds": {"min": [1, 0, 0], "max": [0, 1, 1]}}})", "min must be below max"},
        {R"({"bake": {"adaptivity": 2}})", "bake.adaptivity"},
        {R"({"bake": {"resolutoin": 64}})", "did you mean \"resolution\""},
    };
    for (const auto& [json, message] : bad) {
        try {
            parseParams(json);
            ADD_FAILURE() << "accepted: " << json;
        } catch (const ParamError& error) {
            EXPECT_NE(std::string(error.what()).find(message), std::string::npos) << error.what();
        }
    }
}

}  // namespace
}  // namespace dqj
