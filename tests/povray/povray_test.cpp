// dqjulia.inc and `dqjulia povray` checked with the real POV-Ray 3.7: the include's functions
// equal the core's distance estimate, its bounds and stretch equal the core's, its colouring
// (smooth count, trap scale, palette colours) equals the core's coloring unit, in the include's
// macros and in generated scenes, it parses without warnings, the chain of functions costs
// O(N), and generated scenes draw the silhouette `dqjulia render` draws (intersection over
// union). Every test spawns `povray`.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "dqjulia/coloring.hpp"
#include "dqjulia/image.hpp"
#include "dqjulia/povray.hpp"
#include "dqjulia/version.h"
#include "dqjulia/render.hpp"
#include "test_support.hpp"

namespace fs = std::filesystem;

using dqj::test::readFile;

namespace {

struct Outcome {
    int exitCode = -1;
    std::string log;  // POV-Ray's stderr (banner, #debug output, warnings, errors)
    double seconds = 0.0;
};

/// 17 significant digits: POV-Ray and the core read the same double back.
std::string number(double value) {
    char text[40];
    std::snprintf(text, sizeof text, "%.17g", value);
    return text;
}

std::string array8(const dqj::Vec8& values) {
    std::string text = "array[8] {";
    for (int index = 0; index < 8; ++index) text += (index ? ", " : "") + number(values[index]);
    return text + "}";
}

std::string sliceArray(const dqj::Slice& slice) {
    std::string text = "array[4][8] {";
    auto row = [](const dqj::Vec8& values) {
        std::string r = "{";
        for (int index = 0; index < 8; ++index) r += (index ? ", " : "") + number(values[index]);
        return r + "}";
    };
    text += row(slice.origin);
    for (const auto& axis : slice.axes) text += ", " + row(axis);
    return text + "}";
}

/// A number printed with 17 significant digits: mantissa and decimal exponent.
const char* kPrintMacro =
    "#macro Print(V)\n"
    "  #if (V = 0)\n    \"0\"\n  #else\n"
    "    #local E = floor(log(abs(V)));\n"
    "    concat(str(V / pow(10, E), 0, 16), \"e\", str(E, 0, 0))\n"
    "  #end\n"
    "#end\n";

/// Scene preamble: the include from the source tree and a tiny object (so POV-Ray does not
/// warn about an empty scene), and Print.
const std::string kPreamble = std::string(
                                  "#version 3.7;\n"
                                  "global_settings { assumed_gamma 1.0 }\n"
                                  "#include \"dqjulia.inc\"\n"
                                  "sphere { 0, 1 pigment { rgb 1 } }\n"
                                  "camera { location <0, 0, -5> look_at 0 }\n") +
                              kPrintMacro;

class Povray : public dqj::test::ScratchFolder {
protected:
    Povray() { keepWhenFailed_ = true; }  // the scene, its renders and POV-Ray's messages, to look at

    /// Runs `povray <arguments>` in the test folder with dqjulia.inc from the source tree on the
    /// library path; no display, no output file unless the arguments ask for one.
    Outcome povray(const std::string& arguments) {
        const std::string log = path("povray.log");
        const std::string command = "cd '" + dir_.string() + "' && '" + DQJ_POVRAY + "' -D +L'" +
                                    DQJ_POVRAY_INCLUDE_DIR + "' " + arguments + " > '" + log + "' 2>&1";
        const auto start = std::chrono::steady_clock::now();
        const int status = std::system(command.c_str());
        Outcome result;
        result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        result.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        result.log = readFile(log);
        return result;
    }

    /// Parses `scene` (rendering one pixel, writing nothing).
    Outcome parse(const std::string& scene) {
        write("scene.pov", scene);
        return povray("+W1 +H1 -F -A +Iscene.pov");
    }

    /// Runs `dqjulia <arguments>`; returns the exit code, stderr in `err`.
    int cli(const std::string& arguments, std::string* err = nullptr) {
        const std::string errPath = path("cli.err");
        const std::string command = std::string("'") + DQJ_CLI + "' " + arguments + " > /dev/null 2> '" + errPath + "'";
        const int status = std::system(command.c_str());
        if (err) *err = readFile(errPath);
        return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    }
};

/// The lines "TAG rest" of a log, by tag.
std::vector<std::string> tagged(const std::string& log, const std::string& tag) {
    std::vector<std::string> lines;
    std::istringstream stream(log);
    std::string line;
    while (std::getline(stream, line))
        if (line.rfind(tag + " ", 0) == 0) lines.push_back(line.substr(tag.size() + 1));
    return lines;
}

/// POV-Ray's warnings and errors in a log ("Parse Warning:", "Possible Parse Error:", ...).
/// With `allowSlowGradient`, the advice that a smaller max_gradient would render faster is
/// not counted (a DF3 scene's max_gradient is a bound over every cell of the grid, while
/// POV-Ray reports the largest slope along the rays it happened to trace).
std::vector<std::string> problems(const std::string& log, bool allowSlowGradient = false) {
    std::vector<std::string> all;
    std::istringstream stream(log);
    std::string line;
    while (std::getline(stream, line)) all.push_back(line);
    std::vector<std::string> lines;
    for (std::size_t index = 0; index < all.size(); ++index) {
        const std::string& text = all[index];
        if (text.find("Warning:") == std::string::npos && text.find("Error:") == std::string::npos &&
            text.find("error") == std::string::npos)
            continue;
        const std::string next = index + 2 < all.size() ? all[index + 1] + all[index + 2] : "";
        if (allowSlowGradient && text.find("maximum gradient found") != std::string::npos &&
            next.find("faster rendering") != std::string::npos)
            continue;
        lines.push_back(text);
    }
    return lines;
}

/// A log with POV-Ray's line wrapping undone: it breaks long messages at about 80 columns,
/// continuing on a line that starts with a space.
std::string unwrapped(const std::string& log) {
    std::string text;
    for (std::size_t index = 0; index < log.size(); ++index) {
        if (log[index] == '\n' && index + 1 < log.size() && log[index + 1] == ' ') {
            text += ' ';
            while (index + 1 < log.size() && log[index + 1] == ' ') ++index;
        } else {
            text += log[index];
        }
    }
    return text;
}

double relativeDifference(double a, double b) {
    if (a == b) return 0.0;
    return std::abs(a - b) / std::max(std::abs(a), std::abs(b));
}

struct Case {
    std::string name;
    dqj::Fractal fractal;
    dqj::Slice slice;
    std::string sliceSdl;  // how the scene builds the slice (an SDL expression)
};

dqj::Fractal fractal(const dqj::Vec8& c, dqj::Variant variant, int iterations, double bailout = 4.0) {
    dqj::Fractal f;
    f.c = dqj::toDualQuat(c);
    f.variant = variant;
    f.iterations = iterations;
    f.bailout = bailout;
    return f;
}

const dqj::Vec8 kC1{-0.10, 0.8, -0.26, 0.15, -0.23, -0.38, -0.86, 0.64};  // math.md, the paper's first example
const dqj::Vec8 kC2{-0.39054, -0.58679, 0, 0, 0, 0.5632, 0, 0.05};        // math.md, the paper's high-detail constant
const dqj::Vec8 kTest2{-0.67, -0.54, -0.07, 0.02, 0.06, -0.53, 0.15, -0.27};  // examples/paper-test2-2.json

std::vector<Case> agreementCases() {
    using dqj::Variant;
    std::vector<Case> cases;
    const dqj::Slice standard = dqj::sliceFromAxisNames("a.s,a.i,a.j");
    const std::string standardSdl = "DQJ_Slice_Names(\"a.s,a.i,a.j\")";
    for (const auto& [label, c] : {std::pair{"c1", kC1}, std::pair{"c2", kC2}}) {
        cases.push_back({std::string(label) + "-paper", fractal(c, Variant::Paper, 15), standard, standardSdl});
        cases.push_back(
            {std::string(label) + "-coupled", fractal(c, Variant::PaperCoupled, 15, 6.0), standard, standardSdl});
        cases.push_back({std::string(label) + "-dual", fractal(c, Variant::Dual, 15), standard, standardSdl});
    }
    // A slice that mixes real and dual axes, with an origin off 0 and a rotation, built in SDL
    // with the include's helpers and in C++ with the core's.
    dqj::Slice turned = dqj::sliceFromAxisNames("a.i,a.j,b.s");
    turned.origin = {0.1, 0, 0, 0.05, 0, 0.2, 0, 0};
    turned = dqj::rotated(turned, {{2, 4, 30.0}, {1, 6, -20.0}});
    const std::string turnedSdl =
        "DQJ_Slice_Rotate(DQJ_Slice_Rotate(Origin_Set(DQJ_Slice_Names(\"a.i,a.j,b.s\")), \"a.j\", \"b.s\", 30), \"a.i\", "
        "\"b.j\", -20)";
    cases.push_back({"test2-paper-turned", fractal(kTest2, Variant::Paper, 8), turned, turnedSdl});
    cases.push_back({"c2-dual-turned", fractal(kC2, Variant::Dual, 30), turned, turnedSdl});
    cases.push_back({"c2-coupled-turned", fractal(kC2, Variant::PaperCoupled, 12, 6.0), turned, turnedSdl});
    // A non-orthonormal slice given as raw vectors (stretch != 1).
    dqj::Slice skew;
    skew.origin = {0, 0, 0, 0, 0.05, 0, 0, 0};
    skew.axes = {dqj::Vec8{1.2, 0.1, 0, 0, 0, 0, 0, 0.3}, dqj::Vec8{0, 0.9, 0.2, 0, 0.1, 0, 0, 0},
                 dqj::Vec8{0, 0, 0.7, 0.4, 0, 0, 0.2, 0}};
    cases.push_back({"c2-paper-skew", fractal(kC2, Variant::Paper, 20), skew, sliceArray(skew)});
    // A deep chain: 400 nested functions.
    cases.push_back({"c2-dual-deep", fractal(kC2, Variant::Dual, 400), standard, standardSdl});
    return cases;
}

/// Points of the slice around the bounds: random ones, plus the origin (a zero derivative for
/// slices through 0) and points on the axes.
std::vector<glm::dvec3> samplePoints(const dqj::Bounds& bounds, std::mt19937& random, int count) {
    std::vector<glm::dvec3> points = {glm::dvec3(0.0), glm::dvec3(0.3, 0.0, 0.0), glm::dvec3(0.0, -0.4, 0.0),
                                      glm::dvec3(0.0, 0.0, 0.5)};
    std::uniform_real_distribution<double> unit(-1.0, 1.0);
    while (static_cast<int>(points.size()) < count) {
        const glm::dvec3 offset(unit(random), unit(random), unit(random));
        if (glm::dot(offset, offset) > 1.0) continue;
        points.push_back(bounds.center + offset * bounds.radius * 1.1);
    }
    return points;
}

TEST_F(Povray, IncludeFunctionsEqualTheCoresDistanceEstimate) {
    std::mt19937 random(20240605);
    std::ostringstream scene;
    scene << kPreamble
          << "#macro Origin_Set(S)\n  #local T = S;\n  #declare T[0][0] = 0.1; #declare T[0][3] = 0.05; "
             "#declare T[0][5] = 0.2;\n  T\n#end\n";
    struct Expected {
        std::string tag;
        double value;
        bool distance;
    };
    std::map<std::string, Expected> expected;
    std::map<std::string, std::pair<dqj::Bounds, double>> expectedBounds;
    const std::vector<Case> cases = agreementCases();
    for (std::size_t index = 0; index < cases.size(); ++index) {
        const Case& test = cases[index];
        const std::string id = std::to_string(index);
        scene << "// " << test.name << "\n"
              << "#declare C" << id << " = " << array8(dqj::toVec8(test.fractal.c)) << ";\n"
              << "#declare S" << id << " = " << test.sliceSdl << ";\n"
              << "#declare V" << id << " = \"" << dqj::variantName(test.fractal.variant) << "\";\n"
              << "#declare D" << id << " = DQJ_Distance_Function(C" << id << ", V" << id << ", "
              << test.fractal.iterations << ", " << number(test.fractal.bailout) << ", S" << id << ");\n"
              << "#declare T" << id << " = DQJ_Trap_Function(C" << id << ", V" << id << ", " << test.fractal.iterations
              << ", " << number(test.fractal.bailout) << ", S" << id << ");\n"
              << "#declare I" << id << " = DQJ_Iteration_Function(C" << id << ", V" << id << ", "
              << test.fractal.iterations << ", " << number(test.fractal.bailout) << ", S" << id << ");\n"
              << "#declare B" << id << " = DQJ_Bounds(C" << id << ", V" << id << ", S" << id << ");\n"
              << "#debug concat(\"BOUNDS " << id << " \", Print(B" << id << ".x), \" \", Print(B" << id
              << ".y), \" \", Print(B" << id << ".z), \" \", Print(B" << id << ".t), \" \", Print(DQJ_Stretch(S" << id
              << ")), \"\\n\")\n";
        const auto bounds = dqj::containingBounds(test.fractal, test.slice);
        ASSERT_TRUE(bounds) << test.name;
        expectedBounds[id] = {*bounds, dqj::stretchOf(test.slice).max};
        const int count = test.fractal.iterations > 100 ? 20 : 60;
        const std::vector<glm::dvec3> points = samplePoints(*bounds, random, count);
        for (std::size_t p = 0; p < points.size(); ++p) {
            const glm::dvec3& point = points[p];
            const dqj::Escape escape = dqj::evaluate(test.fractal, test.slice.map(point));
            const std::string key = id + "." + std::to_string(p);
            const std::string args = number(point.x) + ", " + number(point.y) + ", " + number(point.z);
            scene << "#debug concat(\"DE " << key << " \", Print(D" << id << "(" << args << ")), \" \", Print(T" << id
                  << "(" << args << ")), \" \", Print(I" << id << "(" << args << ")), \"\\n\")\n";
            expected[key + ".de"] = {test.name, escape.de, true};
            expected[key + ".trap"] = {test.name, escape.trap, false};
            // DQJ_Iteration_Function is the core's smooth count over N (coloring.hpp).
            const double smooth = dqj::smoothIterations(test.fractal, escape);
            expected[key + ".iterations"] = {test.name, smooth / test.fractal.iterations, false};
        }
    }
    const Outcome result = parse(scene.str());
    ASSERT_EQ(result.exitCode, 0) << result.log;
    EXPECT_TRUE(problems(result.log).empty()) << result.log;

    // Bounds and stretch, computed at parse time in SDL, equal the core's.
    const std::vector<std::string> boundsLines = tagged(result.log, "BOUNDS");
    ASSERT_EQ(boundsLines.size(), cases.size()) << result.log;
    for (const std::string& line : boundsLines) {
        std::istringstream fields(line);
        std::string id;
        double cx, cy, cz, radius, stretch;
        fields >> id >> cx >> cy >> cz >> radius >> stretch;
        const auto& [bounds, coreStretch] = expectedBounds.at(id);
        EXPECT_NEAR(cx, bounds.center.x, 1e-9) << line;
        EXPECT_NEAR(cy, bounds.center.y, 1e-9) << line;
        EXPECT_NEAR(cz, bounds.center.z, 1e-9) << line;
        EXPECT_NEAR(radius, bounds.radius, 1e-9 * bounds.radius) << line;
        EXPECT_NEAR(stretch, coreStretch, 1e-12) << line;
    }

    // Every value equals the core's to relative 1e-6 (+inf is DQJ_Infinite = 1e30).
    const std::vector<std::string> lines = tagged(result.log, "DE");
    std::size_t compared = 0, escaped = 0, inside = 0, infinite = 0;
    double worstDistance = 0.0, worstOther = 0.0;
    for (const std::string& line : lines) {
        std::istringstream fields(line);
        std::string key;
        double de, trap, iterations;
        fields >> key >> de >> trap >> iterations;
        ASSERT_FALSE(fields.fail()) << line;
        const Expected& wantDe = expected.at(key + ".de");
        if (std::isinf(wantDe.value)) {
            EXPECT_EQ(de, 1e30) << wantDe.tag << " " << line;
            ++infinite;
        } else {
            const double difference = relativeDifference(de, wantDe.value);
            worstDistance = std::max(worstDistance, difference);
            EXPECT_LE(difference, 1e-6) << wantDe.tag << " " << line << " core " << number(wantDe.value);
            ++(wantDe.value == 0.0 ? inside : escaped);
        }
        for (const auto& [suffix, value] : {std::pair{".trap", trap}, std::pair{".iterations", iterations}}) {
            const Expected& want = expected.at(key + suffix);
            const double difference = relativeDifference(value, want.value);
            worstOther = std::max(worstOther, difference);
            EXPECT_LE(difference, 1e-6) << want.tag << " " << suffix << " " << line << " core " << number(want.value);
        }
        ++compared;
    }
    EXPECT_EQ(compared * 3, expected.size());
    EXPECT_GT(escaped, 100u);
    EXPECT_GT(inside, 20u);
    EXPECT_GT(infinite, 0u);
    std::cout << "[ povray   ] " << compared << " points in " << cases.size() << " configurations (" << escaped
              << " escaped, " << inside << " inside, " << infinite
              << " zero derivative): largest relative difference, distance estimate " << worstDistance
              << ", trap and smooth count " << worstOther << "\n";
    RecordProperty("max_relative_de_difference", number(worstDistance));
}

/// A pigment's colour at a POV-Ray point, at parse time: "#debug TAG key r g b".
std::string debugColour(const std::string& tag, const std::string& key, const std::string& pigment,
                        const glm::dvec3& slicePoint) {
    const std::string args = number(slicePoint.x) + ", " + number(slicePoint.y) + ", " + number(-slicePoint.z);
    return "#declare Colour = " + pigment + "(" + args + ");\n#debug concat(\"" + tag + " " + key +
           " \", Print(Colour.red), \" \", Print(Colour.green), \" \", Print(Colour.blue), \"\\n\")\n";
}

std::string paletteArray(const std::vector<glm::dvec3>& palette) {
    std::string text = "array[" + std::to_string(palette.size()) + "] {";
    for (std::size_t index = 0; index < palette.size(); ++index)
        text += (index ? ", <" : "<") + number(palette[index].x) + ", " + number(palette[index].y) + ", " +
                number(palette[index].z) + ">";
    return text + "}";
}

/// Largest channel difference of "key r g b" lines against the expected colours.
double compareColours(const std::vector<std::string>& lines, const std::map<std::string, glm::dvec3>& expected,
                      double tolerance) {
    double worst = 0.0;
    for (const std::string& line : lines) {
        std::istringstream fields(line);
        std::string key;
        glm::dvec3 colour;
        fields >> key >> colour.x >> colour.y >> colour.z;
        EXPECT_FALSE(fields.fail()) << line;
        const glm::dvec3& want = expected.at(key);
        const double difference =
            std::max({std::abs(colour.x - want.x), std::abs(colour.y - want.y), std::abs(colour.z - want.z)});
        worst = std::max(worst, difference);
        EXPECT_LE(difference, tolerance) << key << ": POV-Ray " << line << ", core " << want.x << " " << want.y << " "
                                         << want.z;
    }
    return worst;
}

// POV-Ray holds colours in single precision: a colour channel is good to about 1e-7.
constexpr double kColourTolerance = 1e-6;

const std::vector<std::vector<glm::dvec3>>& testPalettes() {
    static const std::vector<std::vector<glm::dvec3>> palettes{
        dqj::Material{}.palette,  // the default, 3 colours
        {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.2, 0.9, 0.7}, {1, 1, 1}},
        {{0.3, 0.6, 0.1}},
    };
    return palettes;
}

TEST_F(Povray, IncludeColouringEqualsTheCoresColoringUnit) {
    std::mt19937 random(20261201);
    std::ostringstream scene;
    scene << kPreamble
          << "#macro Origin_Set(S)\n  #local T = S;\n  #declare T[0][0] = 0.1; #declare T[0][3] = 0.05; "
             "#declare T[0][5] = 0.2;\n  T\n#end\n";
    std::map<std::string, double> expectedValues;
    std::map<std::string, glm::dvec3> expectedColours;
    std::vector<Case> cases = agreementCases();
    cases.pop_back();  // not the 400-deep chain: each pigment below is a chain of its own
    std::size_t escaped = 0, inside = 0;
    for (std::size_t index = 0; index < cases.size(); ++index) {
        const Case& test = cases[index];
        const std::string id = std::to_string(index);
        const std::string common = "C" + id + ", V" + id + ", " + std::to_string(test.fractal.iterations) + ", " +
                                   number(test.fractal.bailout) + ", S" + id;
        scene << "// " << test.name << "\n"
              << "#declare C" << id << " = " << array8(dqj::toVec8(test.fractal.c)) << ";\n"
              << "#declare S" << id << " = " << test.sliceSdl << ";\n"
              << "#declare V" << id << " = \"" << dqj::variantName(test.fractal.variant) << "\";\n"
              << "#debug concat(\"VALUE " << id << ".scale \", Print(DQJ_Trap_Scale(C" << id << ")), \"\\n\")\n"
              << "#declare CT" << id << " = DQJ_Coloring_Function(" << common << ", \"trap\");\n"
              << "#declare CI" << id << " = DQJ_Coloring_Function(" << common << ", \"iterations\");\n";
        expectedValues[id + ".scale"] = dqj::trapScale(test.fractal);
        for (std::size_t p = 0; p < testPalettes().size(); ++p) {
            const char* coloring = p % 2 == 0 ? "trap" : "iterations";
            scene << "#declare P" << id << "_" << p << " = function { DQJ_Orbit_Pigment(" << common << ", \""
                  << coloring << "\", " << paletteArray(testPalettes()[p]) << ") };\n";
        }
        const auto bounds = dqj::containingBounds(test.fractal, test.slice);
        ASSERT_TRUE(bounds) << test.name;
        for (const glm::dvec3& point : samplePoints(*bounds, random, 30)) {
            const std::string key = id + "." + std::to_string(escaped + inside);
            const dqj::Escape escape = dqj::evaluate(test.fractal, test.slice.map(point));
            ++(escape.n == 0 ? inside : escaped);
            const std::string pov = number(point.x) + ", " + number(point.y) + ", " + number(-point.z);
            scene << "#debug concat(\"VALUE " << key << ".trap \", Print(CT" << id << "(" << pov << ")), \"\\n\")\n"
                  << "#debug concat(\"VALUE " << key << ".iterations \", Print(CI" << id << "(" << pov
                  << ")), \"\\n\")\n";
            // The include clamps the value to [0, 1], as the core's palette does.
            expectedValues[key + ".trap"] =
                std::clamp(dqj::coloringValue(dqj::Coloring::Trap, test.fractal, escape), 0.0, 1.0);
            expectedValues[key + ".iterations"] =
                std::clamp(dqj::coloringValue(dqj::Coloring::Iterations, test.fractal, escape), 0.0, 1.0);
            for (std::size_t p = 0; p < testPalettes().size(); ++p) {
                dqj::Material material;
                material.coloring = p % 2 == 0 ? dqj::Coloring::Trap : dqj::Coloring::Iterations;
                material.palette = testPalettes()[p];
                const std::string colourKey = key + "." + std::to_string(p);
                scene << debugColour("RGB", colourKey, "P" + id + "_" + std::to_string(p), point);
                expectedColours[colourKey] = dqj::orbitColour(material, test.fractal, escape);
            }
        }
    }
    const Outcome result = parse(scene.str());
    ASSERT_EQ(result.exitCode, 0) << result.log;
    EXPECT_TRUE(problems(result.log).empty()) << result.log;

    double worstValue = 0.0;
    const std::vector<std::string> values = tagged(result.log, "VALUE");
    ASSERT_EQ(values.size(), expectedValues.size()) << result.log;
    for (const std::string& line : values) {
        std::istringstream fields(line);
        std::string key;
        double value = 0.0;
        fields >> key >> value;
        const double want = expectedValues.at(key);
        const double difference = std::abs(value - want);
        worstValue = std::max(worstValue, difference);
        EXPECT_LE(difference, 1e-9 * std::max(1.0, std::abs(want))) << line << " core " << number(want);
    }
    const std::vector<std::string> colours = tagged(result.log, "RGB");
    ASSERT_EQ(colours.size(), expectedColours.size()) << result.log;
    const double worstColour = compareColours(colours, expectedColours, kColourTolerance);
    EXPECT_GT(escaped, 100u);
    EXPECT_GT(inside, 10u);
    std::cout << "[ povray   ] colouring at " << escaped + inside << " points of " << cases.size()
              << " configurations (" << escaped << " escaped, " << inside
              << " inside): largest difference of trap scale and colouring values " << worstValue
              << ", of palette colours (" << colours.size() << ") " << worstColour << "\n";
    RecordProperty("max_colour_difference", number(worstColour));
}

TEST_F(Povray, GeneratedScenesColourAsTheCore) {
    // The scene `dqjulia povray` writes declares Fractal_Pigment; its colour at points of the
    // slice, evaluated by POV-Ray while parsing, against the core's orbitColour.
    struct Scene {
        std::string name;
        std::string json;
    };
    const std::vector<Scene> scenes = {
        {"trap, default palette", R"({"material": {"coloring": "trap"}})"},
        {"iterations, 4 colours, dual",
         R"({"fractal": {"variant": "dual", "iterations": 12, "c": [-0.2, 0.6, 0.2, 0, 0, 0, 0, 0]},
             "material": {"coloring": "iterations",
                          "palette": [[1, 0, 0], [0.25, 0.5, 0.75], [0, 1, 0], [0.1, 0.1, 0.1]]}})"},
        {"solid", R"({"material": {"coloring": "solid", "color": [0.3, 0.4, 0.5]}})"},
        {"trap, one colour", R"({"material": {"coloring": "trap", "palette": [[0.7, 0.2, 0.9]]}})"},
    };
    std::mt19937 random(7);
    double worst = 0.0;
    std::size_t points = 0;
    for (std::size_t index = 0; index < scenes.size(); ++index) {
        const std::string id = std::to_string(index);
        const std::string paramsPath = write("colour" + id + ".json", scenes[index].json);
        const dqj::Params params = dqj::loadParams(paramsPath);
        std::string err;
        ASSERT_EQ(cli("povray -q -p '" + paramsPath + "' -o '" + path("colour" + id + ".pov") + "'", &err), 0) << err;
        std::string text = readFile(path("colour" + id + ".pov"));
        text += std::string(kPrintMacro) + "#declare Fractal_Colour = function { pigment { Fractal_Pigment } };\n";
        const dqj::Slice slice = params.slice.effective();
        const dqj::Bounds bounds = dqj::renderBounds(params);
        std::map<std::string, glm::dvec3> expected;
        for (const glm::dvec3& point : samplePoints(bounds, random, 40)) {
            const std::string key = id + "." + std::to_string(expected.size());
            text += debugColour("RGB", key, "Fractal_Colour", point);
            const dqj::Escape escape = dqj::evaluate(params.fractal, slice.map(point));
            expected[key] = dqj::orbitColour(params.material, params.fractal, escape);
        }
        write("colour" + id + ".pov", text);
        const Outcome result = povray("+W1 +H1 -F -A +Icolour" + id + ".pov");
        ASSERT_EQ(result.exitCode, 0) << result.log;
        EXPECT_TRUE(problems(result.log).empty()) << result.log;
        const std::vector<std::string> lines = tagged(result.log, "RGB");
        ASSERT_EQ(lines.size(), expected.size()) << scenes[index].name << "\n" << result.log;
        const double difference = compareColours(lines, expected, kColourTolerance);
        std::cout << "[ povray   ] generated scene, " << scenes[index].name << ": largest colour difference "
                  << difference << " at " << lines.size() << " points\n";
        worst = std::max(worst, difference);
        points += lines.size();
    }
    RecordProperty("max_scene_colour_difference", number(worst));
}

TEST_F(Povray, IncludeParsesCleanlyWithEveryMacro) {
    const std::string scene = std::string(kPreamble) +
                              "#include \"dqjulia.inc\"  // a second include is a no-op (include guard)\n"
                              "#declare C = array[8] {-0.39054, -0.58679, 0, 0, 0, 0.5632, 0, 0.05};\n"
                              "#declare S0 = DQJ_Slice_Names(\"a.s,a.i,a.j\");\n"
                              "#declare O = array[8] {0, 0, 0, 0, 0, 0.1, 0, 0};\n"
                              "#declare X = array[8] {1, 0, 0, 0, 0, 0, 0, 0};\n"
                              "#declare Y = array[8] {0, 1, 0, 0, 0, 0, 0, 0};\n"
                              "#declare Z = array[8] {0, 0, 0.6, 0, 0.8, 0, 0, 0};\n"
                              "#declare S1 = DQJ_Slice(O, X, Y, Z);\n"
                              "#declare S2 = DQJ_Slice_Rotate(S0, \"a.j\", \"b.s\", 30);\n"
                              "#declare R = DQJ_Min_Bailout(C, \"paper-coupled\") + 1;\n"
                              "#declare K = DQJ_Containment_Radius(C[0], C[1], C[2], C[3]);\n"
                              "#declare I = DQJ_Axis_Index(\"b.k\");\n"
                              "#declare V = DQJ_Variant_Code(\"dual\");\n"
                              "#declare B = DQJ_Bounds(C, \"dual\", S2);\n"
                              "#declare St = DQJ_Stretch(S1);\n"
                              "#declare F1 = DQJ_Distance_Function(C, \"paper\", 6, 4, S0);\n"
                              "#declare F2 = DQJ_Trap_Function(C, \"paper-coupled\", 6, R, S1);\n"
                              "#declare F3 = DQJ_Iteration_Function(C, \"dual\", 6, 4, S2);\n"
                              "#declare F4 = DQJ_Scene_Function(C, \"dual\", 6, 4, S2, DQJ_Max_Step);\n"
                              "#declare F5 = DQJ_Coloring_Function(C, \"paper\", 6, 4, S0, \"trap\");\n"
                              "#declare F6 = DQJ_Coloring_Function(C, \"paper\", 6, 4, S0, \"iterations\");\n"
                              "#declare TS = DQJ_Trap_Scale(C);\n"
                              "#declare Pal = array[2] {<1, 0, 0>, <0, 0, 1>};\n"
                              "#declare Pg = DQJ_Orbit_Pigment(C, \"dual\", 6, 4, S2, \"iterations\", Pal);\n"
                              "#declare Pg2 = pigment { function { F6(x, y, z) } DQJ_Palette_Colour_Map(Pal) };\n"
                              "#declare P = DQJ_To_Pov(<1, 2, 3>);\n"
                              "#declare Q = F1(0.1, 0.2, 0.3) + F2(0.1, 0.2, 0.3) + F3(0, 0, 0) + F4(1, 1, 1) + "
                              "F5(0, 0, 0) + F6(0, 0, 0);\n"
                              // Behind the camera: parsed, never hit (this test is about parsing).
                              "object { DQJ_Isosurface(C, \"paper\", 6, 4, S0, 0.01) pigment { rgb 1 } "
                              "translate -z * 20 }\n"
                              "object { DQJ_Isosurface_Custom(F4, DQJ_To_Pov(<B.x, B.y, B.z>), B.t, 0.01, 1.2, 0.002) "
                              "pigment { function { F5(x, y, z) } } translate -z * 30 }\n"
                              "#debug concat(\"VERSION \", DQJ_Include_Version, \"\\n\")\n";
    const Outcome result = parse(scene);
    ASSERT_EQ(result.exitCode, 0) << result.log;
    EXPECT_EQ(problems(result.log), std::vector<std::string>{}) << result.log;
    ASSERT_EQ(tagged(result.log, "VERSION").size(), 1u) << result.log;
    EXPECT_EQ(tagged(result.log, "VERSION")[0], DQJ_VERSION_STRING);
    // The include written by `dqjulia povray` is the source tree's.
    EXPECT_EQ(std::string(dqj::povrayInclude()), readFile(fs::path(DQJ_POVRAY_INCLUDE_DIR) / "dqjulia.inc"));
}

TEST_F(Povray, BadArgumentsStopWithAClearMessage) {
    const std::string c = "#declare C = array[8] {-0.39054, -0.58679, 0, 0, 0, 0.5632, 0, 0.05};\n";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"#declare F = DQJ_Distance_Function(C, \"quaternion\", 6, 4, DQJ_Slice_Names(\"a.s,a.i,a.j\"));",
         "unknown variant"},
        {"#declare F = DQJ_Distance_Function(C, \"paper\", 1001, 4, DQJ_Slice_Names(\"a.s,a.i,a.j\"));",
         "from 1 to 1000"},
        {"#declare F = DQJ_Distance_Function(C, \"paper\", 6, 1.2, DQJ_Slice_Names(\"a.s,a.i,a.j\"));",
         "below the containment"},
        {"#declare S = DQJ_Slice_Names(\"a.s,a.s,a.j\");", "named twice"},
        {"#declare S = DQJ_Slice_Names(\"a.s,a.x,a.j\");", "unknown axis \"a.x\""},
        {"#declare S = DQJ_Slice_Names(\"a.s,a.i\");", "exactly 3 axes"},
    };
    for (const auto& [line, message] : cases) {
        const Outcome result = parse(std::string(kPreamble) + c + line + "\n");
        EXPECT_NE(result.exitCode, 0) << line;
        EXPECT_NE(unwrapped(result.log).find(message), std::string::npos) << line << "\n" << result.log;
    }
}

TEST_F(Povray, SelectEvaluatesOnlyTheBranchTakenSoTheChainIsLinear) {
    // If select() evaluated both branches, ln(-1) would be a domain error, and a chain whose
    // functions call the next one in both branches would cost 2^60 calls.
    const std::string scene = std::string(kPreamble) +
                              "#declare G = function(q) { select(-1, q, ln(-1 - q * q)) };\n"
                              "#declare Next = function(q) { q };\n"
                              "#declare K = 0;\n"
                              "#while (K < 60)\n"
                              "  #declare Current = function(q) { select(q, Next(q - 1), Next(q + 1)) };\n"
                              "  #undef Next\n  #declare Next = Current;\n  #undef Current\n"
                              "  #declare K = K + 1;\n"
                              "#end\n"
                              "#debug concat(\"BRANCH \", str(G(2), 0, 3), \" \", str(Next(0.5), 0, 3), \"\\n\")\n";
    const Outcome result = parse(scene);
    ASSERT_EQ(result.exitCode, 0) << result.log;
    ASSERT_EQ(tagged(result.log, "BRANCH"), std::vector<std::string>{"2.000 60.500"}) << result.log;
    EXPECT_LT(result.seconds, 20.0);

    // Parsing and evaluating the include's chain grows linearly with N: evaluate a point inside
    // the set (every iteration runs) 2000 times for N = 125 and N = 1000.
    std::map<int, double> seconds;
    for (int n : {125, 1000}) {
        const std::string timed =
            std::string(kPreamble) + "#declare C = array[8] {-0.39054, -0.58679, 0, 0, 0, 0.5632, 0, 0.05};\n" +
            "#declare F = DQJ_Distance_Function(C, \"dual\", " + std::to_string(n) +
            ", 4, DQJ_Slice_Names(\"a.s,a.i,a.j\"));\n"
            "#declare Sum = 0;\n#declare K = 0;\n"
            "#while (K < 2000)\n  #declare Sum = Sum + F(0.01 * mod(K, 7), 0.1, 0);\n  #declare K = K + 1;\n#end\n"
            "#debug concat(\"SUM \", str(Sum, 0, 3), \"\\n\")\n";
        const Outcome run = parse(timed);
        ASSERT_EQ(run.exitCode, 0) << run.log;
        ASSERT_EQ(tagged(run.log, "SUM"), std::vector<std::string>{"0.000"}) << run.log;  // inside: DE 0
        seconds[n] = run.seconds;
    }
    std::cout << "[ povray   ] parse + 2000 evaluations inside the set: N = 125 " << seconds[125] << " s, N = 1000 "
              << seconds[1000] << " s\n";
    EXPECT_LT(seconds[1000], 30.0);
}

/// Fraction of pixels in `a` and `b` where the surface is (luminance above half).
struct Overlap {
    double iou = 0.0;
    std::size_t pixelsA = 0, pixelsB = 0;
};

Overlap silhouetteOverlap(const dqj::Image& a, const dqj::Image& b) {
    Overlap overlap;
    std::size_t both = 0, either = 0;
    const std::size_t pixels = static_cast<std::size_t>(a.width) * a.height;
    for (std::size_t pixel = 0; pixel < pixels; ++pixel) {
        const bool inA = a.rgba[4 * pixel] + a.rgba[4 * pixel + 1] + a.rgba[4 * pixel + 2] > 1.5f;
        const bool inB = b.rgba[4 * pixel] + b.rgba[4 * pixel + 1] + b.rgba[4 * pixel + 2] > 1.5f;
        overlap.pixelsA += inA;
        overlap.pixelsB += inB;
        both += inA && inB;
        either += inA || inB;
    }
    overlap.iou = either ? double(both) / double(either) : 1.0;
    return overlap;
}

/// A parameter file whose picture is a silhouette: white surface (ambient 1, no lights' terms,
/// no occlusion) on a flat black background, one sample a pixel, 160 x 120.
std::string silhouetteParams(const std::string& fractalJson, const std::string& sliceJson) {
    return "{\"fractal\": " + fractalJson + (sliceJson.empty() ? "" : ", \"slice\": " + sliceJson) +
           ", \"material\": {\"coloring\": \"solid\", \"color\": [1, 1, 1], \"ambient\": 1, \"diffuse\": 0, "
           "\"specular\": 0, \"occlusion\": 0, \"shadows\": false},"
           " \"render\": {\"width\": 160, \"height\": 120, \"samples\": 1, \"background\": [0, 0, 0]}}";
}

TEST_F(Povray, GeneratedScenesDrawTheSilhouetteOfDqjuliaRender) {
    struct View {
        std::string name;
        std::string fractal;
        std::string slice;
        double minimumIou;
    };
    const std::vector<View> views = {
        {"default (paper, c2, N = 15)", R"({"variant": "paper", "iterations": 15})", "", 0.95},
        {"dual, c1, N = 12",
         R"({"c": [-0.10, 0.8, -0.26, 0.15, -0.23, -0.38, -0.86, 0.64], "variant": "dual", "iterations": 12})", "",
         0.95},
        {"paper-coupled, test2-2, turned slice",
         R"({"c": [-0.67, -0.54, -0.07, 0.02, 0.06, -0.53, 0.15, -0.27], "variant": "paper-coupled", "iterations": 8, "bailout": 6})",
         R"({"axes": "a.s,a.i,a.j", "origin": [0, 0, 0, 0, 0, 0.05, 0, 0], "rotations": [{"plane": "a.j,a.k", "degrees": 40}]})",
         0.95},
    };
    int index = 0;
    for (const View& view : views) {
        const std::string id = std::to_string(index++);
        const std::string params = write("view" + id + ".json", silhouetteParams(view.fractal, view.slice));
        const dqj::Image core = dqj::render(dqj::loadParams(params)).image;
        std::string err;
        ASSERT_EQ(cli("povray -q -p '" + params + "' -o '" + path("view" + id + ".pov") + "'", &err), 0) << err;
        const Outcome result = povray("+W160 +H120 -A +FN +Iview" + id + ".pov +Oview" + id + ".png");
        ASSERT_EQ(result.exitCode, 0) << result.log;
        EXPECT_EQ(problems(result.log), std::vector<std::string>{}) << result.log;
        const dqj::Image pov = dqj::readPng(path("view" + id + ".png"));
        ASSERT_EQ(pov.width, 160);
        ASSERT_EQ(pov.height, 120);
        const Overlap overlap = silhouetteOverlap(core, pov);
        std::cout << "[ povray   ] " << view.name << ": IoU " << overlap.iou << " (dqjulia render " << overlap.pixelsA
                  << " px, POV-Ray " << overlap.pixelsB << " px, " << result.seconds << " s)\n";
        EXPECT_GT(overlap.pixelsA, 500u) << view.name;
        EXPECT_GE(overlap.iou, view.minimumIou) << view.name;
        RecordProperty("iou_" + id, number(overlap.iou));
        // The measure tells a mirrored picture (a handedness mistake) from the right one.
        dqj::Image mirrored = pov;
        for (int y = 0; y < pov.height; ++y)
            for (int x = 0; x < pov.width; ++x)
                for (int channel = 0; channel < 4; ++channel)
                    mirrored.rgba[4 * (y * pov.width + x) + channel] =
                        pov.rgba[4 * (y * pov.width + pov.width - 1 - x) + channel];
        EXPECT_LT(silhouetteOverlap(core, mirrored).iou, 0.9) << view.name;
    }
}

TEST_F(Povray, Df3SceneDrawsTheSameSilhouetteFromTheGrid) {
    const std::string params = write("p.json", silhouetteParams(R"({"variant": "paper", "iterations": 15})", ""));
    const dqj::Image core = dqj::render(dqj::loadParams(params)).image;
    std::string err;
    ASSERT_EQ(cli("povray -q --df3 --df3-resolution 160 -p '" + params + "' -o '" + path("grid.pov") + "'", &err), 0)
        << err;
    ASSERT_TRUE(fs::exists(path("grid.df3")));
    ASSERT_TRUE(fs::exists(path("grid_df3.pov")));
    EXPECT_EQ(fs::file_size(path("grid.df3")), 6u + 2u * 160u * 160u * 160u);  // 16-bit samples
    const Outcome result = povray("+W160 +H120 -A +FN +Igrid_df3.pov +Ogrid.png");
    ASSERT_EQ(result.exitCode, 0) << result.log;
    EXPECT_EQ(problems(result.log, true), std::vector<std::string>{}) << result.log;
    const Overlap overlap = silhouetteOverlap(core, dqj::readPng(path("grid.png")));
    std::cout << "[ povray   ] DF3 grid 160^3: IoU " << overlap.iou << " (" << result.seconds << " s)\n";
    EXPECT_GE(overlap.iou, 0.85);
    RecordProperty("iou_df3", number(overlap.iou));
}

TEST_F(Povray, Df3FilesAreBigEndianWithTheirSizeFirst) {
    dqj::DensityGrid grid;
    grid.resolution = 2;
    grid.values = {0.0f, 1.0f, 0.5f, 0.25f, 0.0f, 0.0f, 0.0f, 1.0f};
    for (int bits : {8, 16, 32}) {
        const std::string file = path("g" + std::to_string(bits) + ".df3");
        dqj::writeDf3(grid, file, bits);
        const std::string data = readFile(file);
        const std::size_t bytes = bits / 8;
        ASSERT_EQ(data.size(), 6 + 8 * bytes) << bits;
        for (int axis = 0; axis < 3; ++axis) {
            EXPECT_EQ(static_cast<unsigned char>(data[2 * axis]), 0);
            EXPECT_EQ(static_cast<unsigned char>(data[2 * axis + 1]), 2);
        }
        auto sample = [&](int index) {
            std::uint64_t value = 0;
            for (std::size_t byte = 0; byte < bytes; ++byte)
                value = (value << 8) | static_cast<unsigned char>(data[6 + index * bytes + byte]);
            return value;
        };
        const std::uint64_t maximum = bits == 32 ? 4294967295u : (1u << bits) - 1u;
        EXPECT_EQ(sample(0), 0u);
        EXPECT_EQ(sample(1), maximum);
        EXPECT_EQ(sample(2), (maximum + 1) / 2);  // 0.5 rounds half up
        EXPECT_EQ(sample(7), maximum);
    }
    EXPECT_THROW(dqj::writeDf3(grid, path("bad.df3"), 12), std::invalid_argument);
}

TEST_F(Povray, CommandWritesSceneAndIncludeAndRefusesToClobber) {
    std::string err;
    ASSERT_EQ(cli("povray -q -o '" + path("a.pov") + "'", &err), 0) << err;
    EXPECT_TRUE(fs::exists(path("a.pov")));
    EXPECT_EQ(readFile(path("dqjulia.inc")), std::string(dqj::povrayInclude()));
    // A second scene in the same folder shares the identical include.
    EXPECT_EQ(cli("povray -q -o '" + path("b.pov") + "'", &err), 0) << err;
    // Existing scenes need --force; a different dqjulia.inc is not replaced silently.
    EXPECT_EQ(cli("povray -q -o '" + path("a.pov") + "'", &err), 2);
    EXPECT_NE(err.find("exists; pass --force"), std::string::npos) << err;
    // Bad input: exit 2, nothing written.
    EXPECT_EQ(cli("povray -q -n 2000 -o '" + path("deep.pov") + "'", &err), 2);
    EXPECT_NE(err.find("at most 1000"), std::string::npos) << err;
    EXPECT_EQ(cli("povray -q -o '" + path("missing/x.pov") + "'", &err), 2);
    EXPECT_FALSE(fs::exists(path("deep.pov")));
    // An empty slice: a warning that says why, and a scene without the fractal.
    EXPECT_EQ(cli("povray -q --c -0.10 0.8 -0.26 0.15 -0.23 -0.38 -0.86 0.64 -o '" + path("empty.pov") + "'", &err), 0);
    EXPECT_NE(err.find("outside the Mandelbrot set"), std::string::npos) << err;
    const std::string empty = readFile(path("empty.pov"));
    EXPECT_EQ(empty.find("DQJ_Isosurface"), std::string::npos);
    EXPECT_NE(empty.find("No fractal"), std::string::npos);
    // A dqjulia.inc that differs (a user's edits, another version) is not replaced silently.
    write("dqjulia.inc", "// my own edits\n");
    EXPECT_EQ(cli("povray -q -o '" + path("c.pov") + "'", &err), 2);
    EXPECT_NE(err.find("differs"), std::string::npos) << err;
    EXPECT_FALSE(fs::exists(path("c.pov")));
    EXPECT_EQ(cli("povray -q --no-include -o '" + path("c.pov") + "'", &err), 0) << err;
    EXPECT_EQ(readFile(path("dqjulia.inc")), "// my own edits\n");
    EXPECT_EQ(cli("povray -q --force -o '" + path("d.pov") + "'", &err), 0) << err;
    EXPECT_EQ(readFile(path("dqjulia.inc")), std::string(dqj::povrayInclude()));
}

}  // namespace
