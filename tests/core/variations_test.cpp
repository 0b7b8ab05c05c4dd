// Variations (variations.hpp): determinism, validity, locks, strength, diversity, bad input.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>

#include "dqjulia/inspect.hpp"
#include "dqjulia/params.hpp"
#include "dqjulia/threads.hpp"
#include "dqjulia/variations.hpp"

namespace {

using dqj::Params;
using dqj::VariationOptions;

VariationOptions options(std::uint64_t seed, double strength, unsigned locked = dqj::kGroupVariant, int count = 9) {
    VariationOptions o;
    o.seed = seed;
    o.strength = strength;
    o.locked = locked;
    o.count = count;
    return o;
}

/// Bit for bit: every double of `x` and `y` (a double, a quaternion, an array of doubles or of
/// arrays) has the same bits, so -0 and 0 differ and a NaN equals only itself.
bool same(double x, double y) { return std::bit_cast<std::uint64_t>(x) == std::bit_cast<std::uint64_t>(y); }
bool same(const dqj::Quat& x, const dqj::Quat& y) {
    for (int k = 0; k < 4; ++k)
        if (!same(dqj::component(x, k), dqj::component(y, k))) return false;
    return true;
}
template <typename T, std::size_t N>
bool same(const std::array<T, N>& x, const std::array<T, N>& y) {
    for (std::size_t k = 0; k < N; ++k)
        if (!same(x[k], y[k])) return false;
    return true;
}

double meanDistance(const dqj::VariationResult& result) {
    double sum = 0.0;
    for (const dqj::Variation& variation : result.variations) sum += variation.measures.distance;
    return sum / double(result.variations.size());
}

TEST(Variations, SameSeedGivesTheSameDocumentsByteForByte) {
    const Params base;
    const dqj::VariationResult first = dqj::vary(base, options(7, 0.3));
    const dqj::VariationResult second = [&] {  // on one thread: candidates are judged in their order
        const dqj::ThreadLimit one(1);
        return dqj::vary(base, options(7, 0.3));
    }();
    ASSERT_EQ(first.variations.size(), 9u);
    ASSERT_EQ(second.variations.size(), 9u);
    for (std::size_t i = 0; i < 9; ++i)
        EXPECT_EQ(dqj::toJson(first.variations[i].params), dqj::toJson(second.variations[i].params)) << i;
    const dqj::VariationResult other = dqj::vary(base, options(8, 0.3));
    EXPECT_NE(dqj::toJson(first.variations[0].params), dqj::toJson(other.variations[0].params));
}

TEST(Variations, EveryVariationIsValidNonEmptyAndWithinTheMeasures) {
    for (const double strength : {0.05, 0.3, 1.0}) {
        const dqj::VariationResult result = dqj::vary(Params(), options(3, strength, 0));
        ASSERT_EQ(result.variations.size(), 9u);
        for (const dqj::Variation& variation : result.variations) {
            const std::string json = dqj::toJson(variation.params);
            const Params again = dqj::parseParams(json, "variation");  // complete and valid
            EXPECT_EQ(dqj::toJson(again), json);
            const dqj::InspectReport report = dqj::inspect(again, 16);
            EXPECT_TRUE(report.emptyReason.empty()) << report.emptyReason;
            // Not dust: inside the Mandelbrot set, or still in one piece at N.
            const bool inside =
                report.real.inMandelbrot && (again.fractal.variant == dqj::Variant::Dual || report.dual.inMandelbrot);
            EXPECT_TRUE(inside || variation.measures.connected >= dqj::kMinConnected);
            EXPECT_GE(variation.measures.coverage, dqj::kMinCoverage);
            EXPECT_GE(variation.measures.roughness, dqj::kMinRoughness);
            EXPECT_GE(variation.measures.distance, result.minimumDistance);
            EXPECT_NE(variation.params.description.find("Variation "), std::string::npos);
        }
    }
}

TEST(Variations, LockedGroupsStayBitForBit) {
    Params base;
    base.slice.rotations = {dqj::PlaneRotation{2, 4, 12.5}};
    base.slice.base.origin[6] = 0.125;
    for (const unsigned locked :
         {dqj::kGroupA | dqj::kGroupVariant, dqj::kGroupB | dqj::kGroupIterations | dqj::kGroupVariant,
          dqj::kGroupSliceOrientation | dqj::kGroupSliceOrigin | dqj::kGroupVariant,
          dqj::kAllVariationGroups & ~dqj::kGroupA}) {
        const dqj::VariationResult result = dqj::vary(base, options(5, 0.6, locked, 6));
        ASSERT_EQ(result.variations.size(), 6u);
        for (const dqj::Variation& variation : result.variations) {
            const Params& p = variation.params;
            if (locked & dqj::kGroupA) EXPECT_TRUE(same(p.fractal.c.a, base.fractal.c.a));
            if (locked & dqj::kGroupB) EXPECT_TRUE(same(p.fractal.c.b, base.fractal.c.b));
            if (locked & dqj::kGroupIterations) {
                EXPECT_EQ(p.fractal.iterations, base.fractal.iterations);
                EXPECT_TRUE(same(p.fractal.bailout, base.fractal.bailout));
            }
            if (locked & dqj::kGroupSliceOrientation) {
                ASSERT_EQ(p.slice.rotations.size(), base.slice.rotations.size());
                for (std::size_t i = 0; i < p.slice.rotations.size(); ++i) {
                    EXPECT_EQ(p.slice.rotations[i].first, base.slice.rotations[i].first);
                    EXPECT_EQ(p.slice.rotations[i].second, base.slice.rotations[i].second);
                    EXPECT_TRUE(same(p.slice.rotations[i].degrees, base.slice.rotations[i].degrees));
                }
                EXPECT_TRUE(same(p.slice.base.axes, base.slice.base.axes));
            }
            if (locked & dqj::kGroupSliceOrigin) EXPECT_TRUE(same(p.slice.base.origin, base.slice.base.origin));
            if (locked & dqj::kGroupVariant) EXPECT_EQ(p.fractal.variant, base.fractal.variant);
            // What no group covers is never touched.
            EXPECT_EQ(p.render.width, base.render.width);
            Params rest = p;
            rest.description = base.description;
            rest.fractal = base.fractal;
            rest.slice = base.slice;
            EXPECT_EQ(dqj::toJson(rest), dqj::toJson(base));
        }
    }
}

TEST(Variations, StrengthRaisesTheMeanDistanceFromTheOriginal) {
    // Averaged over three seeds: tiny < small < medium < large < huge.
    double previous = 0.0;
    for (const dqj::StrengthName& name : dqj::strengthNames()) {
        double sum = 0.0;
        for (const std::uint64_t seed : {1u, 2u, 3u})
            sum += meanDistance(dqj::vary(Params(), options(seed, name.value)));
        const double mean = sum / 3.0;
        EXPECT_GT(mean, previous) << name.name;
        previous = mean;
    }
}

TEST(Variations, NoTwoThumbnailsNearlyTheSame) {
    for (const double strength : {0.05, 0.6}) {
        const dqj::VariationResult result = dqj::vary(Params(), options(11, strength));
        std::vector<std::vector<std::uint16_t>> thumbnails;
        for (const dqj::Variation& variation : result.variations)
            thumbnails.push_back(dqj::thumbnailOf(variation.params));
        const auto original = dqj::thumbnailOf(Params());
        for (std::size_t i = 0; i < thumbnails.size(); ++i) {
            EXPECT_GE(dqj::thumbnailDistance(thumbnails[i], original), dqj::minimumDistance(strength));
            for (std::size_t j = 0; j < i; ++j)
                EXPECT_GE(dqj::thumbnailDistance(thumbnails[i], thumbnails[j]), dqj::minimumDistance(strength))
                    << i << j;
        }
    }
}

/// What each measure rejected among the first `candidates` candidates.
std::array<int, dqj::kRejectionCount> rejected(const Params& base, double strength, unsigned locked, int candidates) {
    return dqj::sampleVariations(base, options(1, strength, locked), candidates).rejected;
}

int count(const std::array<int, dqj::kRejectionCount>& counts, dqj::Rejection rejection) {
    return counts[int(rejection)];
}

TEST(Variations, EachMeasureRejectsWhatItShould) {
    using dqj::Rejection;
    const unsigned variant = dqj::kGroupVariant;
    // Near c = 0 the Julia set is a ball (z^2 + 0: the unit ball exactly).
    Params ball;
    ball.fractal.c = {dqj::makeQuat(0.02, 0.01, 0, 0), dqj::makeQuat(0, 0, 0, 0)};
    const auto balls = rejected(ball, 0.05, variant, 24);
    EXPECT_GE(count(balls, Rejection::Ball), 20) << "ball";
    // Bounds far wider than the set (radius 7): it covers under 2% of the frame.
    // Every candidate is rejected: as tiny, or as dust (the default constant lies near the edge).
    Params far;
    far.bounds = dqj::Bounds{glm::dvec3(0.0), 7.0};
    const auto tiny = rejected(far, 0.05, variant, 16);
    EXPECT_GE(count(tiny, Rejection::Tiny), 6) << "tiny";
    EXPECT_EQ(count(tiny, Rejection::Tiny) + count(tiny, Rejection::Dust), 16) << "tiny";
    // The default constant's real part lies near the Mandelbrot set's edge: large steps leave it
    // (dust) or empty the slice.
    const auto huge = rejected(Params(), 1.0, variant, 48);
    EXPECT_GT(count(huge, Rejection::Dust), 0);
    EXPECT_GT(count(huge, Rejection::Empty), 0);
    // Tiny steps of only the iterations group: the same picture as the original.
    const auto same = rejected(Params(), 0.05, dqj::kAllVariationGroups & ~dqj::kGroupIterations, 16);
    EXPECT_EQ(count(same, Rejection::Similar), 16) << "similar";
    // R at its least allowed value, and locked: a constant that needs a larger R is invalid.
    Params tight;
    tight.fractal.bailout = dqj::minimumBailout(tight.fractal);
    EXPECT_GT(count(rejected(tight, 0.3, dqj::kGroupIterations | variant, 24), Rejection::Invalid), 0) << "invalid";
}

TEST(Variations, ADocumentBeyondTheMandelbrotSetsEdgeIsVariedAsItIs) {
    // The paper's "test2" constants lie outside the Mandelbrot set, yet at N = 8 their sets are
    // one solid each (examples/paper-test2-2.json). Variations keep a where it is (locked) and
    // stay in one piece; the default document, inside, never gets a part outside.
    Params beyond;
    beyond.fractal.c = {dqj::makeQuat(-0.67, -0.54, -0.07, 0.02), dqj::makeQuat(0.06, -0.53, 0.15, -0.27)};
    beyond.fractal.iterations = 8;
    ASSERT_FALSE(dqj::inspect(beyond, 16).real.inMandelbrot);
    const dqj::VariationResult result = dqj::vary(beyond, options(2, 0.15, dqj::kGroupA | dqj::kGroupVariant, 4));
    for (const dqj::Variation& variation : result.variations) {
        EXPECT_FALSE(dqj::inspect(variation.params, 16).real.inMandelbrot);
        EXPECT_GE(variation.measures.connected, dqj::kMinConnected);
    }
    for (const dqj::Variation& variation : dqj::vary(Params(), options(2, 1.0)).variations) {
        const dqj::InspectReport report = dqj::inspect(variation.params, 16);
        EXPECT_TRUE(report.real.inMandelbrot && report.dual.inMandelbrot);
    }
}

TEST(Variations, ThumbnailDistanceIsAJaccardDistance) {
    const std::vector<std::uint16_t> a{0, 10, 10, 0}, b{0, 10, 0, 10};
    EXPECT_EQ(dqj::thumbnailDistance(a, a), 0.0);
    EXPECT_DOUBLE_EQ(dqj::thumbnailDistance(a, b), 1.0 - 10.0 / 30.0);
    EXPECT_EQ(dqj::thumbnailDistance({0, 0}, {5, 0}), 1.0);
}

TEST(Variations, NamesOfStrengthsAndGroups) {
    EXPECT_EQ(dqj::parseStrength("tiny"), 0.05);
    EXPECT_EQ(dqj::parseStrength("huge"), 1.0);
    EXPECT_EQ(dqj::parseStrength("0.4"), 0.4);
    EXPECT_FALSE(dqj::parseStrength("enormous"));
    EXPECT_FALSE(dqj::parseStrength(""));
    EXPECT_EQ(dqj::parseGroups("a,slice"), dqj::kGroupA | dqj::kGroupSliceOrientation | dqj::kGroupSliceOrigin);
    EXPECT_EQ(dqj::parseGroups("none"), 0u);
    std::string unknown;
    EXPECT_FALSE(dqj::parseGroups("a,colour", &unknown));
    EXPECT_EQ(unknown, "colour");
    EXPECT_EQ(dqj::groupNames(dqj::kGroupB | dqj::kGroupIterations), "b, iterations");
}

/// The ParamError's message of vary(base, o), or "" if it passed.
std::string failure(const Params& base, const VariationOptions& o) {
    try {
        dqj::vary(base, o);
    } catch (const dqj::ParamError& error) {
        return error.what();
    }
    return "";
}

TEST(Variations, BadInputGetsAClearMessage) {
    const Params base;
    EXPECT_NE(failure(base, options(1, 1.5)).find("strength 1.5 is out of range"), std::string::npos);
    EXPECT_NE(failure(base, options(1, 0.0)).find("out of range"), std::string::npos);
    EXPECT_NE(failure(base, options(1, std::nan(""))).find("out of range"), std::string::npos);
    EXPECT_NE(failure(base, options(1, 0.3, dqj::kAllVariationGroups)).find("every group is locked"),
              std::string::npos);
    EXPECT_NE(failure(base, options(1, 0.3, 0, 0)).find("count 0"), std::string::npos);
    // A starting document that is itself empty: the dual part's own orbit escapes.
    Params empty;
    empty.fractal.c.b = dqj::makeQuat(0.6, 0.6, 0, 0);
    EXPECT_NE(failure(empty, options(1, 0.3)).find("starting document is itself empty"), std::string::npos);
}

TEST(Variations, BoundedTriesSayHowToLoosenTheSettings) {
    // Only the iterations may change, at a tiny strength: N moves by at most one or two, too
    // little for nine different thumbnails. The search stops at its bound and says why.
    VariationOptions o = options(1, 0.05, dqj::kAllVariationGroups & ~dqj::kGroupIterations);
    o.maxCandidates = 40;
    const std::string message = failure(Params(), o);
    EXPECT_NE(message.find("found only"), std::string::npos) << message;
    EXPECT_NE(message.find("in 40 candidates"), std::string::npos) << message;
    EXPECT_NE(message.find("raise the strength"), std::string::npos) << message;
    EXPECT_NE(message.find("unlock groups"), std::string::npos) << message;
}

TEST(Variations, ProgressCanCancel) {
    EXPECT_THROW(dqj::vary(Params(), options(1, 0.3), [](double fraction) { return fraction < 0.01; }), dqj::Cancelled);
}

}  // namespace
