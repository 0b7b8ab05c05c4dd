// Variations of a parameter document (variations.hpp): seeded candidates, their thumbnails'
// measures, and the choice of the ones that pass.
#include "dqjulia/variations.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numbers>
#include <string>

#include <glm/geometric.hpp>
#include <tbb/parallel_for.h>

#include "dqjulia/batch.hpp"
#include "dqjulia/inspect.hpp"

namespace dqj {
namespace {

constexpr StrengthName kStrengths[] = {
    {"tiny", 0.05, "the same fractal with its details moved a little"},
    {"small", 0.15, "a close relative: the same overall form, different details"},
    {"medium", 0.3, "a sibling: recognisably related, noticeably different"},
    {"large", 0.6, "a cousin: a different form from the same neighbourhood"},
    {"huge", 1.0, "a stranger: anything the unlocked groups can reach"},
};

constexpr struct {
    std::string_view name;
    unsigned groups;
} kGroupNames[] = {
    {"a", kGroupA},
    {"b", kGroupB},
    {"slice", kGroupSliceOrientation | kGroupSliceOrigin},
    {"orientation", kGroupSliceOrientation},
    {"origin", kGroupSliceOrigin},
    {"iterations", kGroupIterations},
    {"variant", kGroupVariant},
    {"none", 0},
};

/// splitmix64 (Steele, Lea and Flood 2014): the library's own generator, the same numbers everywhere.
class Random {
public:
    Random(std::uint64_t seed, std::uint64_t index) : state_(mixed(seed ^ mixed(index + 0x632be59bd9b4e019ULL))) {}
    std::uint64_t next() { return mixed(state_ += 0x9e3779b97f4a7c15ULL); }
    /// Uniform in [0, 1) from the top 53 bits.
    double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
    /// Uniform in 0..count-1 (count small: the bias is below 2^-58).
    int below(int count) { return static_cast<int>(next() % static_cast<std::uint64_t>(count)); }
    double sign() { return (next() >> 63) ? 1.0 : -1.0; }

private:
    static std::uint64_t mixed(std::uint64_t z) {
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
        return z ^ (z >> 31);
    }
    std::uint64_t state_;
};

/// A uniformly random unit vector of `Size` dimensions: points of the cube kept inside the
/// ball (no logarithms or cosines: the same bits on every platform).
template <std::size_t Size>
std::array<double, Size> unitVector(Random& random) {
    while (true) {
        std::array<double, Size> v;
        double squared = 0.0;
        for (double& x : v) {
            x = 2.0 * random.uniform() - 1.0;
            squared += x * x;
        }
        if (squared > 1e-4 && squared <= 1.0) {
            const double length = std::sqrt(squared);
            for (double& x : v) x /= length;
            return v;
        }
    }
}

/// To `scale` (1e5: 5 decimals): what a variation writes for every number it changed.
double rounded(double value, double scale = 1e5) { return std::round(value * scale) / scale + 0.0; }

/// An amount between half and all of `reach * strength`: the strength sets the size of a change.
double amount(Random& random, double reach, double strength) {
    return reach * strength * (0.5 + 0.5 * random.uniform());
}

/// 1 + x or 1 / (1 + x): a factor that grows or shrinks by the same step.
double factor(Random& random, double step) {
    const double grow = 1.0 + step;
    return random.sign() > 0 ? grow : 1.0 / grow;
}

/// The thumbnail of a document: the escape test on a lattice aligned with the camera's view.
struct Thumbnail {
    std::vector<std::uint16_t> pixels;  ///< kThumbnail^2, row 0 at the top: 2G - depth on the set, 0 off it
    std::int64_t inside = 0;            ///< lattice points inside at N
    std::int64_t faces = 0;             ///< faces between inside points and outside ones (or the lattice's edge)
    std::int64_t largest = 0;           ///< inside points in the largest piece (26-connected)
    double connected() const { return inside == 0 ? 0.0 : double(largest) / double(inside); }
    double coverage() const {
        return double(std::count_if(pixels.begin(), pixels.end(), [](std::uint16_t v) { return v != 0; })) /
               double(pixels.size());
    }
    /// (faces / a ball's faces at the same volume)^3: a digital ball of volume V has about
    /// 1.5 (36 pi)^(1/3) V^(2/3) faces (1.5: the mean staircase factor of a surface).
    double roughnessCubed() const {
        if (inside == 0) return 0.0;
        const double f = double(faces), v = double(inside);
        return f * f * f / (1.5 * 1.5 * 1.5 * 36.0 * std::numbers::pi * v * v);
    }
};

Thumbnail thumbnail(const Params& params) {
    const Slice slice = params.slice.effective();
    const Bounds bounds = renderBounds(params);
    const Camera& camera = params.camera;
    // The view as frameCamera (render.cpp) orients it, from the document's values alone.
    glm::dvec3 view = camera.position ? camera.target.value_or(bounds.center) - *camera.position : -camera.direction;
    view = glm::length(view) > 0.0 ? glm::normalize(view) : glm::dvec3(0.0, 0.0, -1.0);
    glm::dvec3 up = camera.up;
    if (!(glm::length(glm::cross(view, up)) > 1e-9 * glm::length(up))) {
        const glm::dvec3 f = glm::abs(view);
        up = f.x <= f.y && f.x <= f.z ? glm::dvec3(1, 0, 0) : (f.y <= f.z ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, 1));
    }
    const glm::dvec3 right = glm::normalize(glm::cross(view, up));
    up = glm::cross(right, view);

    constexpr int g = kThumbnail;
    auto at = [](int index) { return ((index + 0.5) / g * 2.0 - 1.0); };
    BatchBuffer<double> batch;
    batch.resize(std::size_t(g) * g * g);
    std::size_t index = 0;
    for (int z = 0; z < g; ++z)
        for (int y = 0; y < g; ++y)
            for (int x = 0; x < g; ++x, ++index) {
                const glm::dvec3 p = bounds.center + bounds.radius * (at(x) * right - at(y) * up + at(z) * view);
                for (int k = 0; k < 8; ++k) batch.start(k)[index] = slice.coordinate(k, p);
            }
    batch.evaluate(params.fractal);
    std::vector<std::uint8_t> in(batch.size());
    for (std::size_t i = 0; i < in.size(); ++i) in[i] = batch.escape(i).n == 0;

    Thumbnail result;
    result.pixels.assign(std::size_t(g) * g, 0);
    auto inside = [&](int x, int y, int z) {
        return x >= 0 && y >= 0 && z >= 0 && x < g && y < g && z < g && in[(std::size_t(z) * g + y) * g + x];
    };
    for (int z = 0; z < g; ++z)
        for (int y = 0; y < g; ++y)
            for (int x = 0; x < g; ++x) {
                if (!inside(x, y, z)) continue;
                ++result.inside;
                result.faces += !inside(x - 1, y, z) + !inside(x + 1, y, z) + !inside(x, y - 1, z) +
                                !inside(x, y + 1, z) + !inside(x, y, z - 1) + !inside(x, y, z + 1);
                std::uint16_t& pixel = result.pixels[std::size_t(y) * g + x];
                if (pixel == 0) pixel = std::uint16_t(2 * g - z);
            }
    // The pieces: flood fills over the 26 neighbours, marking each point when it is reached.
    std::vector<int> stack;
    for (std::size_t seed = 0; seed < in.size(); ++seed) {
        if (in[seed] != 1) continue;
        std::int64_t size = 0;
        in[seed] = 2;
        stack.assign(1, int(seed));
        while (!stack.empty()) {
            const int at = stack.back();
            stack.pop_back();
            ++size;
            const int x = at % g, y = at / g % g, z = at / (g * g);
            for (int dz = -1; dz <= 1; ++dz)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int nx = x + dx, ny = y + dy, nz = z + dz;
                        if (nx < 0 || ny < 0 || nz < 0 || nx >= g || ny >= g || nz >= g) continue;
                        const int next = (nz * g + ny) * g + nx;
                        if (in[std::size_t(next)] != 1) continue;
                        in[std::size_t(next)] = 2;
                        stack.push_back(next);
                    }
        }
        result.largest = std::max(result.largest, size);
    }
    return result;
}


/// The parts whose constant decides escape: a always, b too except under "dual".
unsigned decidingParts(const Fractal& fractal) {
    return fractal.variant == Variant::Dual ? kGroupA : kGroupA | kGroupB;
}

/// The deciding parts whose equivalent complex constant lies outside the Mandelbrot set.
unsigned dustParts(const InspectReport& report) {
    const unsigned deciding = decidingParts(report.fractal);
    return ((deciding & kGroupA) && !report.real.inMandelbrot ? kGroupA : 0u) |
           ((deciding & kGroupB) && !report.dual.inMandelbrot ? kGroupB : 0u);
}

/// Dust: a part that decides escape lies outside the Mandelbrot set (inspect: its Julia set is
/// totally disconnected) where the original's was inside, or the set at N already falls apart (its
/// largest piece holds less than kMinConnected of its points). A variation never turns a fractal
/// into dust; one already beyond the Mandelbrot set's edge (as the paper's "test2" figures are),
/// whose set at N is still one solid, is varied as it is. `outsideBefore`: the original's parts
/// outside the Mandelbrot set (dustParts).
bool isDust(const InspectReport& report, const Thumbnail& thumbnail, unsigned outsideBefore) {
    const unsigned outside = dustParts(report);
    return (outside & ~outsideBefore) != 0 || (outside != 0 && thumbnail.connected() < kMinConnected);
}

/// Candidate `index` of the seed's sequence. Every group's change is drawn whether it is
/// locked or not, so locking one group leaves the others' changes as they were.
Params candidateFor(const Params& base, const Slice& baseSlice, const VariationOptions& options, int index) {
    Random random(options.seed, std::uint64_t(index));
    const double s = options.strength;
    const unsigned open = ~options.locked & kAllVariationGroups;
    Params params = base;

    for (const unsigned group : {kGroupA, kGroupB}) {
        const auto direction = unitVector<4>(random);
        const double step = amount(random, 0.5, s);
        Quat& part = group == kGroupA ? params.fractal.c.a : params.fractal.c.b;
        if (open & group)
            for (int k = 0; k < 4; ++k) component(part, k) = rounded(component(part, k) + step * direction[k]);
    }

    {  // A turn in a plane from an axis the slice uses towards one it does not (where there is one).
        auto used = [&](int k) {
            return baseSlice.axes[0][k] != 0.0 || baseSlice.axes[1][k] != 0.0 || baseSlice.axes[2][k] != 0.0;
        };
        std::vector<int> inSlice, outside;
        for (int k = 0; k < 8; ++k) (used(k) ? inSlice : outside).push_back(k);
        const int first = inSlice[random.below(int(inSlice.size()))];
        int second = first;
        if (!outside.empty()) second = outside[random.below(int(outside.size()))];
        while (second == first) second = random.below(8);
        const double degrees = random.sign() * amount(random, 90.0, s);
        const int which = random.below(std::max<int>(1, int(params.slice.rotations.size())));
        if (open & kGroupSliceOrientation) {
            std::vector<PlaneRotation>& rotations = params.slice.rotations;
            if (!rotations.empty() && rotations.back().first == first && rotations.back().second == second)
                rotations.back().degrees = rounded(rotations.back().degrees + degrees, 100.0);
            else if (rotations.size() >= 8)  // a list that stays short: turn one already there
                rotations[which].degrees = rounded(rotations[which].degrees + degrees, 100.0);
            else
                rotations.push_back({first, second, rounded(degrees, 100.0)});
        }
    }

    {  // The origin moved across the slice (along the slice it would only shift the picture).
        std::array<Vec8, 3> basis = baseSlice.axes;  // Gram-Schmidt
        for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < i; ++j) {
                double dot = 0.0;
                for (int k = 0; k < 8; ++k) dot += basis[i][k] * basis[j][k];
                for (int k = 0; k < 8; ++k) basis[i][k] -= dot * basis[j][k];
            }
            double squared = 0.0;
            for (int k = 0; k < 8; ++k) squared += basis[i][k] * basis[i][k];
            const double length = std::sqrt(squared);
            for (int k = 0; k < 8; ++k) basis[i][k] = length > 0.0 ? basis[i][k] / length : 0.0;
        }
        std::array<double, 8> direction = unitVector<8>(random);
        for (const Vec8& axis : basis) {
            double dot = 0.0;
            for (int k = 0; k < 8; ++k) dot += direction[k] * axis[k];
            for (int k = 0; k < 8; ++k) direction[k] -= dot * axis[k];
        }
        double squared = 0.0;
        for (const double x : direction) squared += x * x;
        const double step = amount(random, 0.5, s) / std::max(std::sqrt(squared), 1e-300);
        if ((open & kGroupSliceOrigin) && squared > 1e-12)
            for (int k = 0; k < 8; ++k)
                params.slice.base.origin[k] = rounded(params.slice.base.origin[k] + step * direction[k]);
    }

    const double iterationFactor = factor(random, amount(random, 0.6, s));
    const double bailoutFactor = factor(random, amount(random, 0.5, s));
    if (open & kGroupIterations) {
        params.fractal.iterations = std::clamp(int(std::lround(base.fractal.iterations * iterationFactor)), 1, 100000);
        params.fractal.bailout = rounded(base.fractal.bailout * bailoutFactor);
    }

    // The variant: switched with a chance that grows from nothing at "medium" to 30% at "huge";
    // always when it is the only group that may change.
    const double pick = random.uniform();
    const int other = random.below(2);
    const double chance = open == kGroupVariant ? 1.0 : 0.5 * std::max(0.0, s - 0.4);
    if ((open & kGroupVariant) && pick < chance) {
        const Variant others[3][2] = {{Variant::PaperCoupled, Variant::Dual},
                                      {Variant::Paper, Variant::Dual},
                                      {Variant::Paper, Variant::PaperCoupled}};
        params.fractal.variant = others[int(base.fractal.variant)][other];
    }

    // R must stay at least r_K (validate): raised when the iterations group may change.
    if ((open & kGroupIterations) && params.fractal.bailout < minimumBailout(params.fractal))
        params.fractal.bailout = minimumBailout(params.fractal);
    return params;
}

struct Judged {
    Params params;
    std::optional<Rejection> rejection;
    Thumbnail thumbnail;
};

Judged judge(Params params, unsigned outsideBefore) {
    Judged judged;
    try {
        validate(params);
    } catch (const ParamError&) {
        judged.rejection = Rejection::Invalid;  // e.g. R below the new r_K with the iterations group locked
        return judged;
    }
    const InspectReport report = inspect(params, 16);
    if (!report.emptyReason.empty()) {
        judged.rejection = Rejection::Empty;
    } else {
        judged.thumbnail = thumbnail(params);
        if (judged.thumbnail.inside == 0)
            judged.rejection = Rejection::Empty;
        else if (isDust(report, judged.thumbnail, outsideBefore))
            judged.rejection = Rejection::Dust;
        else if (judged.thumbnail.coverage() < kMinCoverage)
            judged.rejection = Rejection::Tiny;
        else if (judged.thumbnail.roughnessCubed() < kMinRoughness * kMinRoughness * kMinRoughness)
            judged.rejection = Rejection::Ball;
    }
    judged.params = std::move(params);
    return judged;
}

std::string number(double value) {
    char text[32];
    const auto end = std::to_chars(text, text + sizeof text, value);
    return std::string(text, end.ptr);
}

std::string strengthText(double strength) {
    for (const StrengthName& name : kStrengths)
        if (name.value == strength) return std::string(name.name) + " (" + number(strength) + ")";
    return number(strength);
}

/// "Variation 3 (seed 7, strength medium (0.3)) of: <the original's description>", without
/// stacking "Variation ... of:" prefixes when a variation is varied again.
std::string describe(const std::string& original, const VariationOptions& options, int number) {
    std::string rest = original;
    if (rest.rfind("Variation ", 0) == 0)
        if (const auto of = rest.find(" of: "); of != std::string::npos) rest = rest.substr(of + 5);
    return "Variation " + std::to_string(number) + " (seed " + std::to_string(options.seed) + ", strength " +
           strengthText(options.strength) + ", locked: " + groupNames(options.locked) + ")" +
           (rest.empty() ? std::string() : " of: " + rest);
}

/// Judges candidates 0, 1, ... in order until `wanted` pass or `limit` were judged.
VariationResult search(const Params& base, const std::vector<std::uint16_t>& original, const VariationOptions& options,
                       int limit, int wanted, const ProgressCallback& progress) {
    const unsigned outsideBefore = dustParts(inspect(base, 16));
    VariationResult result;
    result.minimumDistance = minimumDistance(options.strength);
    const Slice baseSlice = base.slice.effective();
    std::vector<std::vector<std::uint16_t>> accepted;
    if (progress && !progress(0.0)) throw Cancelled();
    constexpr int kBlock = 8;  // candidates measured in parallel, then judged in their order
    for (int next = 0; int(result.variations.size()) < wanted && next < limit; next += kBlock) {
        const int size = std::min(kBlock, limit - next);
        std::vector<Judged> judged(size);
        tbb::parallel_for(0, size, [&](int i) {
            judged[i] = judge(candidateFor(base, baseSlice, options, next + i), outsideBefore);
        });
        for (int i = 0; i < size && int(result.variations.size()) < wanted; ++i) {
            ++result.candidates;
            Judged& candidate = judged[i];
            if (candidate.rejection) {
                ++result.rejected[int(*candidate.rejection)];
                continue;
            }
            const double distance = thumbnailDistance(candidate.thumbnail.pixels, original);
            bool similar = distance < result.minimumDistance;
            for (const auto& other : accepted)
                similar = similar || thumbnailDistance(candidate.thumbnail.pixels, other) < result.minimumDistance;
            if (similar) {
                ++result.rejected[int(Rejection::Similar)];
                continue;
            }
            Variation variation;
            variation.params = std::move(candidate.params);
            variation.params.description = describe(base.description, options, int(result.variations.size()) + 1);
            variation.measures = {candidate.thumbnail.coverage(), std::cbrt(candidate.thumbnail.roughnessCubed()),
                                  distance, candidate.thumbnail.connected()};
            variation.candidate = next + i;
            accepted.push_back(std::move(candidate.thumbnail.pixels));
            result.variations.push_back(std::move(variation));
        }
        if (progress && !progress(double(result.variations.size()) / wanted)) throw Cancelled();
    }
    return result;
}

}  // namespace

std::span<const StrengthName> strengthNames() { return kStrengths; }

std::optional<double> parseStrength(std::string_view text) {
    for (const StrengthName& name : kStrengths)
        if (text == name.name) return name.value;
    double value = 0.0;
    const auto end = std::from_chars(text.data(), text.data() + text.size(), value);
    if (text.empty() || end.ec != std::errc() || end.ptr != text.data() + text.size()) return std::nullopt;
    return value;
}

std::optional<unsigned> parseGroups(std::string_view text, std::string* unknown) {
    unsigned groups = 0;
    while (true) {
        const std::size_t comma = text.find(',');
        std::string_view item = text.substr(0, comma);
        while (!item.empty() && item.front() == ' ') item.remove_prefix(1);
        while (!item.empty() && item.back() == ' ') item.remove_suffix(1);
        bool known = false;
        for (const auto& group : kGroupNames)
            if (item == group.name) {
                groups |= group.groups;
                known = true;
            }
        if (!known) {
            if (unknown) *unknown = std::string(item);
            return std::nullopt;
        }
        if (comma == std::string_view::npos) return groups;
        text.remove_prefix(comma + 1);
    }
}

std::string groupNames(unsigned groups) {
    static constexpr std::pair<unsigned, std::string_view> kNames[] = {{kGroupA, "a"},
                                                                       {kGroupB, "b"},
                                                                       {kGroupSliceOrientation, "slice orientation"},
                                                                       {kGroupSliceOrigin, "slice origin"},
                                                                       {kGroupIterations, "iterations"},
                                                                       {kGroupVariant, "variant"}};
    std::string text;
    for (const auto& [bit, name] : kNames)
        if (groups & bit) text += (text.empty() ? "" : ", ") + std::string(name);
    return text.empty() ? "none" : text;
}

std::string_view rejectionName(Rejection rejection) {
    switch (rejection) {
        case Rejection::Invalid: return "invalid";
        case Rejection::Empty: return "empty";
        case Rejection::Dust: return "dust";
        case Rejection::Tiny: return "tiny";
        case Rejection::Ball: return "ball";
        case Rejection::Similar: return "similar";
    }
    return "?";
}

double minimumDistance(double strength) { return 0.01 + 0.1 * strength; }

std::vector<std::uint16_t> thumbnailOf(const Params& params) { return thumbnail(params).pixels; }

double thumbnailDistance(const std::vector<std::uint16_t>& first, const std::vector<std::uint16_t>& second) {
    std::int64_t low = 0, high = 0;
    for (std::size_t i = 0; i < std::min(first.size(), second.size()); ++i) {
        low += std::min(first[i], second[i]);
        high += std::max(first[i], second[i]);
    }
    return high == 0 ? 0.0 : 1.0 - double(low) / double(high);
}

VariationResult vary(const Params& base, const VariationOptions& options, const ProgressCallback& progress) {
    if (!(options.strength >= kMinStrength && options.strength <= kMaxStrength))
        throw ParamError("variations.strength",
                         "strength " + number(options.strength) + " is out of range: give " + number(kMinStrength) +
                             " to " + number(kMaxStrength) +
                             " or tiny (0.05), small (0.15), medium (0.3), large (0.6), huge (1)");
    if (options.count < 1 || options.count > 100)
        throw ParamError("variations.count",
                         "count " + std::to_string(options.count) + " is out of range: give 1 to 100");
    if ((options.locked & kAllVariationGroups) == kAllVariationGroups)
        throw ParamError("variations.locked",
                         "every group is locked (a, b, slice orientation, slice origin, iterations, variant): nothing "
                         "may change; unlock at least one");
    if (!base.animation.empty())
        throw ParamError("animation",
                         "the document is animated: vary a still (the parameters of one frame, "
                         "e.g. from the C ABI at the context's frame, or without \"animation\")");
    validate(base);
    const InspectReport start = inspect(base);  // 32^3 samples: a sparse start is given the benefit of the doubt
    if (!start.emptyReason.empty())
        throw ParamError("fractal",
                         "the starting document is itself empty, so there is nothing to vary: " + start.emptyReason);
    const Thumbnail original = thumbnail(base);
    if (original.inside == 0)
        throw ParamError("fractal",
                         "the starting document is itself empty, so there is nothing to vary: no point of "
                         "its " +
                             std::to_string(kThumbnail) + "^3 thumbnail lattice is inside at N = " +
                             std::to_string(base.fractal.iterations) + "; try fewer iterations or another slice");
    const int limit = options.maxCandidates > 0 ? options.maxCandidates : 60 * options.count;
    VariationResult result = search(base, original.pixels, options, limit, options.count, progress);
    if (int(result.variations.size()) < options.count) {
        std::string counts;
        for (int r = 0; r < kRejectionCount; ++r)
            if (result.rejected[r])
                counts += (counts.empty() ? "" : ", ") + std::to_string(result.rejected[r]) + " " +
                          std::string(rejectionName(Rejection(r)));
        throw ParamError("variations", "found only " + std::to_string(result.variations.size()) + " of " +
                                           std::to_string(options.count) + " variations in " +
                                           std::to_string(result.candidates) + " candidates (rejected: " + counts +
                                           "); loosen the settings: " +
                                           (options.strength < kMaxStrength
                                                ? "raise the strength (now " + strengthText(options.strength) + "), "
                                                : std::string()) +
                                           ((options.locked & kAllVariationGroups)
                                                ? "unlock groups (locked: " + groupNames(options.locked) + "), "
                                                : std::string()) +
                                           "ask for fewer variations, or try another seed");
    }
    if (progress && !progress(1.0)) throw Cancelled();
    return result;
}

VariationResult sampleVariations(const Params& base, const VariationOptions& options, int candidates) {
    return search(base, thumbnail(base).pixels, options, candidates, candidates, {});
}

}  // namespace dqj
