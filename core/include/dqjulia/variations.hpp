// dqjulia/variations.hpp - variations of a parameter document: the fractal next to the one in
// front of you, as fractal-flame editors' "Mutate" and Mandelbulber's "Randomizer" offer, but
// each one proven non-empty, not dust, not a featureless ball, not too small in the frame, and
// different enough from the original and from the others (docs/examples.md, "Exploring").
// Code: core/src/explore/variations.cpp.
//
// Candidates: every group that is not locked changes by an amount set by the strength (the
// constant's real part a and dual part b by a random 4-D step, the slice turned in a random
// 8-D plane or its origin moved across it, N and R scaled; the variant switched at large
// strengths). The randomness is the library's own integer generator (splitmix64), candidate k
// drawing from (seed, k) alone, and every changed number is rounded to 5 decimals (angles to
// 0.01 degree): the same seed gives the same documents on every platform and compiler.
//
// The measures (docs/variations.md has the figures):
//   empty   inspect() proves the slice empty or finds no sample inside (16^3), or the
//           thumbnail grid below has no point inside;
//   dust    a part that decides escape (a; b too except under "dual") has its equivalent complex
//           constant outside the Mandelbrot set (inspect(): the Julia set is totally disconnected)
//           where the original's was inside; or, outside it, the set at N already falls apart
//           (its largest 26-connected piece on the thumbnail lattice holds less than
//           kMinConnected of its points). So a variation never turns a fractal into dust, and a
//           document beyond the set's edge (the paper's "test2" figures) is varied as it is;
//   tiny    the set covers less than kMinCoverage of its thumbnail (the render's frame);
//   ball    its surface is less than kMinRoughness times a ball's of the same volume;
//   similar its thumbnail differs from the original's, or from one accepted before it, by less
//           than minimumDistance(strength).
// The thumbnail is a depth image: the escape test at N on a kThumbnail^3 lattice filling the
// render bounds' cube, aligned with the camera's view (x right, y up, z away from the camera);
// a pixel holds the depth of the first point inside along z. Only exact arithmetic decides, so
// the measures are the same on every instruction set (the batch kernel's double escape counts
// equal evaluate()'s). Two thumbnails differ by the weighted Jaccard distance of their pixel
// values (2G - depth for a hit, 0 for a miss): 1 - sum(min) / sum(max), 0 for identical
// pictures, 1 for pictures that share no pixel.
//
// Cost: a candidate is one inspect() at 16^3, kThumbnail^3 = 40^3 evaluations and a flood fill
// of the lattice (a few ms on one core at N = 15); candidates are measured in parallel, in
// blocks of 8, and accepted in their order.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "dqjulia/export.h"
#include "dqjulia/params.hpp"
#include "dqjulia/progress.hpp"

namespace dqj {

/// What a variation may change; the values are the C ABI's DQJ_GROUP_* bits.
enum VariationGroup : unsigned {
    kGroupA = 1u << 0,                 ///< fractal.c's real part a
    kGroupB = 1u << 1,                 ///< fractal.c's dual part b
    kGroupSliceOrientation = 1u << 2,  ///< slice.rotations (a turn in a random plane is added or changed)
    kGroupSliceOrigin = 1u << 3,       ///< slice.axes' origin, moved across the slice
    kGroupIterations = 1u << 4,        ///< fractal.iterations and fractal.bailout
    kGroupVariant = 1u << 5,           ///< fractal.variant (switched only at large strengths)
};
inline constexpr unsigned kAllVariationGroups = 0x3f;

/// Named strengths, in the words of Mandelbulber's Randomizer.
struct StrengthName {
    std::string_view name;
    double value;
    std::string_view words;
};
DQJ_API std::span<const StrengthName> strengthNames();
inline constexpr double kMinStrength = 0.01, kMaxStrength = 1.0;
/// "tiny" ... "huge", or a number; nullopt for anything else (range not checked).
DQJ_API std::optional<double> parseStrength(std::string_view text);
/// "a,b,slice,origin,iterations,variant" (any subset, "slice" = orientation and origin,
/// "none" = nothing) to group bits; nullopt, with the unknown name in `unknown`, for a bad name.
DQJ_API std::optional<unsigned> parseGroups(std::string_view text, std::string* unknown = nullptr);
/// "a, b, slice orientation" for messages ("none" for 0).
DQJ_API std::string groupNames(unsigned groups);

struct VariationOptions {
    std::uint64_t seed = 1;
    double strength = 0.3;            ///< kMinStrength..kMaxStrength; "medium"
    unsigned locked = kGroupVariant;  ///< groups kept bit for bit (the variant by default)
    int count = 9;                    ///< 1..100
    int maxCandidates = 0;            ///< 0: 60 * count
};

/// The measures of one candidate's thumbnail (the header's comment defines them).
struct VariationMeasures {
    double coverage = 0.0;   ///< share of the thumbnail's pixels on the set
    double roughness = 0.0;  ///< surface / a ball's of the same volume (1 = ball)
    double distance = 0.0;   ///< image distance to the original's thumbnail
    double connected = 0.0;  ///< share of the set's lattice points in its largest piece
};

struct Variation {
    Params params;  ///< complete and valid; description says whence it came
    VariationMeasures measures;
    int candidate = 0;  ///< the candidate's index (0-based): where it came from in the seed's sequence
};

enum class Rejection { Invalid, Empty, Dust, Tiny, Ball, Similar };
inline constexpr int kRejectionCount = 6;
DQJ_API std::string_view rejectionName(Rejection rejection);

struct VariationResult {
    std::vector<Variation> variations;
    int candidates = 0;                           ///< candidates judged (accepted and rejected)
    std::array<int, kRejectionCount> rejected{};  ///< by Rejection
    double minimumDistance = 0.0;                 ///< the bound every pair (and the original) kept
};

/// The thresholds (docs/variations.md says how they were chosen).
inline constexpr int kThumbnail = 40;
inline constexpr double kMinCoverage = 0.02;
inline constexpr double kMinRoughness = 1.25;
inline constexpr double kMinConnected = 0.5;
/// The smallest image distance between two variations, and from the original, at a strength.
DQJ_API double minimumDistance(double strength);

/// `count` variations of `base` (a still: no "animation"). Throws ParamError for a bad
/// strength, count or lock (key "variations.*"), a starting document that is empty or otherwise
/// invalid, and when fewer than `count` variations pass within
/// maxCandidates (the message says how many were rejected by which measure and how to loosen the
/// settings); Cancelled if `progress` returns false.
DQJ_API VariationResult vary(const Params& base, const VariationOptions& options,
                             const ProgressCallback& progress = {});

/// Judges exactly `candidates` candidates of vary()'s sequence and keeps every one that passes
/// (for the measures' figures: docs/variations.md, the benchmark). No checks of the settings.
DQJ_API VariationResult sampleVariations(const Params& base, const VariationOptions& options, int candidates);

/// A document's depth thumbnail (kThumbnail^2 pixels, row 0 at the top: 2 kThumbnail - depth on
/// the set, 0 off it), and the image distance of two of them (for tests and the benchmark).
DQJ_API std::vector<std::uint16_t> thumbnailOf(const Params& params);
DQJ_API double thumbnailDistance(const std::vector<std::uint16_t>& first, const std::vector<std::uint16_t>& second);

}  // namespace dqj
