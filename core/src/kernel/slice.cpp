// Slices: axis names, rotations, stretch, containing bounds and the bounds everything starts from.
#include "dqjulia/slice.hpp"
#include "dqjulia/params.hpp"
#include "files/message_text.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include <glm/mat3x3.hpp>

namespace dqj {
namespace {

constexpr std::array<std::string_view, 8> kAxisNames = {"a.s", "a.i", "a.j", "a.k", "b.s", "b.i", "b.j", "b.k"};

std::string_view trim(std::string_view text) {
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
    while (!text.empty() && std::isspace(static_cast<unsigned char>(text.back()))) text.remove_suffix(1);
    return text;
}

/// Eigenvalues of a symmetric 3x3 matrix by cyclic Jacobi rotations (converges in a few sweeps).
std::array<double, 3> symmetricEigenvalues(glm::dmat3 m) {
    for (int sweep = 0; sweep < 50; ++sweep) {
        const double offDiagonal = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
        if (offDiagonal < 1e-30) break;
        for (int p = 0; p < 2; ++p) {
            for (int q = p + 1; q < 3; ++q) {
                if (std::abs(m[p][q]) < 1e-300) continue;
                const double theta = (m[q][q] - m[p][p]) / (2.0 * m[p][q]);
                const double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1.0));
                const double c = 1.0 / std::sqrt(t * t + 1.0);
                const double s = t * c;
                glm::dmat3 rotation(1.0);
                rotation[p][p] = c;
                rotation[q][q] = c;
                rotation[q][p] = s;   // column q, row p
                rotation[p][q] = -s;  // column p, row q
                m = glm::transpose(rotation) * m * rotation;
            }
        }
    }
    return {m[0][0], m[1][1], m[2][2]};
}

/// The sphere containing { x : |m + M x| <= limit } where M is the slice's axes restricted
/// to `indices` (8-D coordinates) and m the origin restricted likewise. The region is empty
/// when the closest point of the (affine) slice is beyond `limit`. With G = M^T M positive
/// definite the region is an ellipsoid around x* = -G^-1 M^T m, inside the sphere of radius
/// sqrt(limit^2 - |m + M x*|^2) / sigma_min; with G singular it is unbounded (a cylinder).
struct SphereFit {
    bool bounded = false;
    bool empty = false;
    Bounds bounds;
};

SphereFit fitSphere(const Slice& slice, const std::vector<int>& indices, double limit) {
    const int size = static_cast<int>(indices.size());
    std::vector<double> offset(size);
    std::array<std::vector<double>, 3> columns;
    for (int row = 0; row < size; ++row) offset[row] = slice.origin[indices[row]];
    for (int axis = 0; axis < 3; ++axis) {
        columns[axis].resize(size);
        for (int row = 0; row < size; ++row) columns[axis][row] = slice.axes[axis][indices[row]];
    }
    // Distance from the restricted origin to the span of the columns (Gram-Schmidt), whatever the rank.
    std::vector<std::vector<double>> basis;
    for (const auto& column : columns) {
        std::vector<double> v = column;
        for (const auto& e : basis) {
            double projection = 0.0;
            for (int row = 0; row < size; ++row) projection += v[row] * e[row];
            for (int row = 0; row < size; ++row) v[row] -= projection * e[row];
        }
        double length = 0.0;
        for (double value : v) length += value * value;
        length = std::sqrt(length);
        if (length > 1e-9) {
            for (double& value : v) value /= length;
            basis.push_back(std::move(v));
        }
    }
    std::vector<double> residual = offset;
    for (const auto& e : basis) {
        double projection = 0.0;
        for (int row = 0; row < size; ++row) projection += residual[row] * e[row];
        for (int row = 0; row < size; ++row) residual[row] -= projection * e[row];
    }
    double closestSquared = 0.0;
    for (double value : residual) closestSquared += value * value;

    SphereFit fit;
    if (closestSquared > limit * limit) {
        fit.empty = true;
        return fit;
    }
    if (basis.size() < 3) return fit;  // unbounded along the null direction

    glm::dmat3 gram(0.0);
    glm::dvec3 projected(0.0);  // M^T m
    for (int row = 0; row < size; ++row) {
        const glm::dvec3 r(columns[0][row], columns[1][row], columns[2][row]);
        for (int column = 0; column < 3; ++column)
            for (int other = 0; other < 3; ++other) gram[column][other] += r[column] * r[other];
        projected += r * offset[row];
    }
    const auto eigenvalues = symmetricEigenvalues(gram);
    const double smallest = *std::min_element(eigenvalues.begin(), eigenvalues.end());
    fit.bounded = true;
    fit.bounds.center = -(glm::inverse(gram) * projected);
    fit.bounds.radius = std::sqrt(limit * limit - closestSquared) / std::sqrt(smallest);
    return fit;
}

}  // namespace

std::optional<int> parseAxisName(std::string_view name) {
    name = trim(name);
    for (int index = 0; index < 8; ++index)
        if (name == kAxisNames[index]) return index;
    return std::nullopt;
}

std::string axisName(int index) { return index >= 0 && index < 8 ? std::string(kAxisNames[index]) : "?"; }

Slice sliceFromAxisNames(std::string_view shorthand) {
    std::vector<std::string_view> parts;
    std::size_t start = 0;
    while (true) {
        const std::size_t comma = shorthand.find(',', start);
        parts.push_back(shorthand.substr(start, comma == std::string_view::npos ? comma : comma - start));
        if (comma == std::string_view::npos) break;
        start = comma + 1;
    }
    if (parts.size() != 3)
        throw std::invalid_argument("a slice names exactly 3 axes separated by commas (e.g. \"a.s,a.i,a.j\"), got " +
                                    std::to_string(parts.size()) + " in \"" + inputExcerpt(shorthand) + "\"");
    Slice slice;
    std::array<int, 3> used{-1, -1, -1};
    for (int axis = 0; axis < 3; ++axis) {
        const auto index = parseAxisName(parts[axis]);
        if (!index)
            throw std::invalid_argument("unknown axis \"" + inputExcerpt(trim(parts[axis])) +
                                        "\"; axes are a.s a.i a.j a.k (real part) and b.s b.i b.j b.k (dual part)");
        if (std::find(used.begin(), used.end(), *index) != used.end())
            throw std::invalid_argument("axis \"" + axisName(*index) + "\" is named twice in \"" +
                                        inputExcerpt(shorthand) + "\"; the three axes must differ");
        used[axis] = *index;
        slice.axes[axis] = Vec8{};
        slice.axes[axis][*index] = 1.0;
    }
    return slice;
}

std::string axisNamesOf(const Slice& slice) {
    std::string names;
    for (int axis = 0; axis < 3; ++axis) {
        int unit = -1;
        for (int index = 0; index < 8; ++index) {
            const double value = slice.axes[axis][index];
            if (value == 1.0 && unit < 0) {
                unit = index;
            } else if (value != 0.0) {
                return "";
            }
        }
        if (unit < 0) return "";
        if (axis) names += ",";
        names += axisName(unit);  // not "," + name: GCC 12 warns falsely (-Wrestrict) on that
    }
    return names;
}

Slice rotated(Slice slice, const std::vector<PlaneRotation>& rotations) {
    for (const PlaneRotation& rotation : rotations) {
        const double radians = rotation.degrees * std::numbers::pi / 180.0;
        const double c = std::cos(radians);
        const double s = std::sin(radians);
        for (Vec8& axis : slice.axes) {
            const double u = axis[rotation.first];
            const double v = axis[rotation.second];
            axis[rotation.first] = c * u - s * v;
            axis[rotation.second] = s * u + c * v;
        }
    }
    return slice;
}

Stretch stretchOf(const Slice& slice) {
    glm::dmat3 gram(0.0);
    for (int column = 0; column < 3; ++column)
        for (int row = 0; row < 3; ++row)
            for (int index = 0; index < 8; ++index)
                gram[column][row] += slice.axes[column][index] * slice.axes[row][index];
    const auto eigenvalues = symmetricEigenvalues(gram);
    Stretch stretch;
    stretch.max = std::sqrt(std::max(0.0, *std::max_element(eigenvalues.begin(), eigenvalues.end())));
    stretch.min = std::sqrt(std::max(0.0, *std::min_element(eigenvalues.begin(), eigenvalues.end())));
    return stretch;
}

std::optional<Bounds> containingBounds(const Fractal& fractal, const Slice& slice) {
    const std::vector<int> real{0, 1, 2, 3};
    const std::vector<int> dual{4, 5, 6, 7};
    const std::vector<int> all{0, 1, 2, 3, 4, 5, 6, 7};
    const double realRadius = containmentRadius(fractal.c.a);
    const double dualRadius = containmentRadius(fractal.c.b);

    std::vector<SphereFit> fits;
    if (fractal.variant == Variant::Dual) {
        // Only |a| decides escape: the set is K(c_a) x R^4, bounded in the slice only if the
        // slice's real part is. Otherwise it is an extrusion; clip it with the 8-D ball.
        fits.push_back(fitSphere(slice, real, realRadius));
        if (!fits.back().bounded && !fits.back().empty) {
            SphereFit clip = fitSphere(slice, all, realRadius);
            clip.bounds.clipped = true;
            fits.push_back(clip);
        }
    } else {
        // Paper rules: a escapes beyond r_K(c_a), b beyond r_K(c_b); each constraint alone bounds.
        fits.push_back(fitSphere(slice, real, realRadius));
        fits.push_back(fitSphere(slice, dual, dualRadius));
        fits.push_back(fitSphere(slice, all, hypot2(realRadius, dualRadius)));
    }
    std::optional<Bounds> best;
    for (const SphereFit& fit : fits) {
        if (fit.empty) return std::nullopt;
        if (fit.bounded && (!best || fit.bounds.radius < best->radius)) best = fit.bounds;
    }
    return best;
}

Bounds renderBounds(const Params& params) {
    if (params.bounds) return *params.bounds;
    const Slice slice = params.slice.effective();
    const auto bounds = containingBounds(params.fractal, slice);
    if (bounds) return *bounds;
    std::ostringstream message;
    message << std::setprecision(4) << "slice: the slice misses the containment region (every orbit with |a| > r_K = "
            << containmentRadius(params.fractal.c.a) << " escapes";
    if (params.fractal.variant != Variant::Dual)
        message << ", and every orbit with |b| > r_K = " << containmentRadius(params.fractal.c.b);
    message << "), so the set is empty in this slice whatever the iteration count; move the slice origin "
               "closer to 0 or set explicit \"bounds\"";
    throw ParamError("slice", message.str());
}

}  // namespace dqj
