// The reference vectors (math.md, "Reference values"): every row of tests/data/reference_vectors.csv
// must come out of dqj::evaluate with the exact escape count and all norms, the DE and the exit
// state to relative 1e-10.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "dqjulia/estimate.hpp"

namespace {

// The two constants of the paper's examples, as math.md gives them.
const dqj::DualQuat kC1{dqj::makeQuat(-0.10, 0.8, -0.26, 0.15), dqj::makeQuat(-0.23, -0.38, -0.86, 0.64)};
const dqj::DualQuat kC2{dqj::makeQuat(-0.39054, -0.58679, 0.0, 0.0), dqj::makeQuat(0.0, 0.5632, 0.0, 0.05)};
constexpr std::size_t kExpectedRows = 30;

struct ReferenceRow {
    int line = 0;
    std::string constant;  // "c1" or "c2"
    std::string point;
    std::string variant;  // "A", "A8" or "B"
    dqj::DualQuat start;
    int iterations = 0;
    double bailout = 0.0;
    int escape = 0;
    double r = 0.0, ra = 0.0, rb = 0.0, de = 0.0;
    dqj::DualQuat exit;
};

void PrintTo(const ReferenceRow& row, std::ostream* out) {
    *out << "line " << row.line << " (" << row.constant << ", point " << row.point << ", " << row.variant << ")";
}

// strtod accepts "inf", which the DE column uses for a zero derivative.
double parseNumber(const std::string& text) {
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0') throw std::runtime_error("not a number: \"" + text + "\"");
    return value;
}

dqj::Quat parseQuat(const std::string& text) {
    std::istringstream words(text);
    std::vector<std::string> parts;
    for (std::string word; words >> word;) parts.push_back(word);
    if (parts.size() != 4) throw std::runtime_error("expected 4 numbers in \"" + text + "\"");
    return dqj::makeQuat(parseNumber(parts[0]), parseNumber(parts[1]), parseNumber(parts[2]), parseNumber(parts[3]));
}

struct ReferenceFile {
    std::vector<ReferenceRow> rows;
    std::vector<std::string> errors;  // a malformed line is reported by the row-count test
};

ReferenceFile loadReference() {
    ReferenceFile file;
    const std::string path = std::string(DQJ_TEST_DATA) + "/reference_vectors.csv";
    std::ifstream in(path);
    if (!in) {
        file.errors.push_back("cannot open " + path);
        return file;
    }
    std::string text;
    std::getline(in, text);  // header
    for (int line = 2; std::getline(in, text); ++line) {
        if (text.empty()) continue;
        std::vector<std::string> fields;
        std::stringstream stream(text);
        for (std::string field; std::getline(stream, field, ',');) fields.push_back(field);
        try {
            if (fields.size() != 14)
                throw std::runtime_error("expected 14 columns, got " + std::to_string(fields.size()));
            ReferenceRow row;
            row.line = line;
            row.constant = fields[0];
            row.point = fields[1];
            row.start = {parseQuat(fields[2]), parseQuat(fields[3])};
            row.variant = fields[4];
            row.iterations = std::stoi(fields[5]);
            row.bailout = parseNumber(fields[6]);
            row.escape = std::stoi(fields[7]);
            row.r = parseNumber(fields[8]);
            row.ra = parseNumber(fields[9]);
            row.rb = parseNumber(fields[10]);
            row.de = parseNumber(fields[11]);
            row.exit = {parseQuat(fields[12]), parseQuat(fields[13])};
            file.rows.push_back(row);
        } catch (const std::exception& error) {
            file.errors.push_back(path + ":" + std::to_string(line) + ": " + error.what());
        }
    }
    return file;
}

const ReferenceFile& reference() {
    static const ReferenceFile file = loadReference();
    return file;
}

// Relative 1e-10; an expected 0 must come out as 0 up to a tiny absolute slack; inf exactly.
void expectClose(double actual, double expected, const char* what) {
    if (std::isinf(expected)) {
        EXPECT_EQ(actual, expected) << what;
    } else if (expected == 0.0) {
        EXPECT_LE(std::abs(actual), 1e-300) << what << " = " << actual << ", expected 0";
    } else {
        EXPECT_LE(std::abs(actual - expected), 1e-10 * std::abs(expected))
            << what << " = " << actual << ", expected " << expected;
    }
}

class ReferenceVectors : public testing::TestWithParam<ReferenceRow> {};

TEST(ReferenceFile, HasAllRows) {
    for (const std::string& error : reference().errors) ADD_FAILURE() << error;
    EXPECT_EQ(reference().rows.size(), kExpectedRows);
}

TEST_P(ReferenceVectors, MatchesEvaluate) {
    const ReferenceRow& row = GetParam();
    dqj::Fractal fractal;
    ASSERT_TRUE(row.constant == "c1" || row.constant == "c2") << row.constant;
    fractal.c = row.constant == "c1" ? kC1 : kC2;
    ASSERT_TRUE(row.variant == "A" || row.variant == "A8" || row.variant == "B") << row.variant;
    fractal.variant = row.variant == "A"    ? dqj::Variant::Paper
                      : row.variant == "A8" ? dqj::Variant::PaperCoupled
                                            : dqj::Variant::Dual;
    fractal.iterations = row.iterations;
    fractal.bailout = row.bailout;

    const dqj::Escape result = dqj::evaluate(fractal, row.start);
    EXPECT_EQ(result.n, row.escape);
    expectClose(result.r, row.r, "r");
    expectClose(result.ra, row.ra, "|a|");
    expectClose(result.rb, row.rb, "|b|");
    expectClose(result.de, row.de, "DE");
    const dqj::Vec8 actual = dqj::toVec8(result.exit);
    const dqj::Vec8 expected = dqj::toVec8(row.exit);
    for (int index = 0; index < 8; ++index) {
        const std::string what = "exit component " + std::to_string(index);
        expectClose(actual[index], expected[index], what.c_str());
    }
    EXPECT_EQ(dqj::distanceEstimate(fractal, row.start), result.de);
}

// r_K and the smallest allowed bailout (math.md, "Containment radius").
TEST(ReferenceContainment, RadiusAndMinimumBailout) {
    EXPECT_EQ(dqj::containmentRadius(dqj::makeQuat(0, 0, 0, 0)), 1.0);
    EXPECT_DOUBLE_EQ(dqj::containmentRadius(dqj::makeQuat(0, 0, 0, -2)), 2.0);  // (1 + sqrt(9)) / 2
    EXPECT_DOUBLE_EQ(dqj::containmentRadius(dqj::makeQuat(0.5, 0.5, 0.5, 0.5)), 0.5 * (1.0 + std::sqrt(5.0)));

    dqj::Fractal fractal;
    fractal.c = {dqj::makeQuat(0, 0, 0, -2), dqj::makeQuat(0, 0, 0, 0)};  // r_K = 2 and 1
    fractal.variant = dqj::Variant::Dual;
    EXPECT_DOUBLE_EQ(dqj::minimumBailout(fractal), 2.0);  // only |a| is tested
    fractal.variant = dqj::Variant::Paper;
    EXPECT_DOUBLE_EQ(dqj::minimumBailout(fractal), 2.0);  // max(2, 1)
    fractal.variant = dqj::Variant::PaperCoupled;
    EXPECT_DOUBLE_EQ(dqj::minimumBailout(fractal), std::sqrt(5.0));  // one norm over both parts
}

// With R at the minimum, no point of the set may count as escaped. c = 0: K(0) x K(0) holds
// (0.9, 0.9), whose orbit tends to 0, but its 8-D norm 1.15 exceeds max(r_K) = 1.
TEST(ReferenceContainment, MinimumBailoutKeepsSetPointsInside) {
    const dqj::DualQuat start{dqj::makeQuat(0.9, 0, 0, 0), dqj::makeQuat(0, 0.9, 0, 0)};
    for (dqj::Variant variant : {dqj::Variant::Paper, dqj::Variant::PaperCoupled, dqj::Variant::Dual}) {
        dqj::Fractal fractal;
        fractal.c = {};
        fractal.variant = variant;
        fractal.iterations = 100;
        fractal.bailout = dqj::minimumBailout(fractal);
        EXPECT_EQ(dqj::evaluate(fractal, start).n, 0) << dqj::variantName(variant);
    }
}

// The loop tests escape on squared norms: s > squaredBailout(R) must be exactly sqrt(s) > R,
// checked on the doubles and floats next to R^2 for bailouts from 1 to 1e150 (and the edges).
template <typename T>
void expectSquaredBailoutExact(double bailout) {
    const T above = dqj::squaredBailout<T>(bailout);
    const T r = static_cast<T>(bailout);
    T s = r * r;
    for (int k = 0; k < 8; ++k) s = std::nextafter(s, T(0));
    for (int k = 0; k < 16; ++k, s = std::nextafter(s, std::numeric_limits<T>::infinity()))
        EXPECT_EQ(s > above, std::sqrt(s) > r) << "R = " << bailout << ", s = " << s;
}

TEST(ReferenceContainment, SquaredBailoutIsExactlyTheBailout) {
    for (double bailout : {1.0, 1.5, 2.0, 2.236067977499790, 3.0, 4.0, 7.3, 20.0, 1e3, 12345.678, 1e19, 1e150}) {
        expectSquaredBailoutExact<double>(bailout);
        if (bailout < 1e19) expectSquaredBailoutExact<float>(bailout);
    }
    std::mt19937_64 random(3);
    std::uniform_real_distribution<double> uniform(1.0, 64.0);
    for (int k = 0; k < 2000; ++k) {
        const double bailout = uniform(random);
        expectSquaredBailoutExact<double>(bailout);
        expectSquaredBailoutExact<float>(bailout);
    }
    constexpr double kInf = std::numeric_limits<double>::infinity();
    EXPECT_EQ(dqj::squaredBailout<double>(kInf), kInf);  // nothing finite escapes
    EXPECT_TRUE(std::isnan(dqj::squaredBailout<double>(std::nan(""))));
    EXPECT_EQ(dqj::squaredBailout<double>(-1.0), -kInf);  // everything escapes, as sqrt(s) > -1
    EXPECT_EQ(dqj::squaredBailout<float>(1e30), std::numeric_limits<float>::max());  // R^2 overflows float
    EXPECT_EQ(dqj::squaredBailout<double>(0.0), 0.0);
}

std::string rowName(const testing::TestParamInfo<ReferenceRow>& info) {
    return info.param.constant + "_point" + info.param.point + "_" + info.param.variant;
}

INSTANTIATE_TEST_SUITE_P(Reference, ReferenceVectors, testing::ValuesIn(reference().rows), rowName);

}  // namespace
