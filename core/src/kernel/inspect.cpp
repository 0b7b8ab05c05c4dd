// Inspection: equivalent complex constants, Mandelbrot membership, inside fraction, and the
// reason a slice is empty.
#include "dqjulia/inspect.hpp"

#include <cmath>
#include <complex>
#include <sstream>

#include <nlohmann/json.hpp>


namespace dqj {
namespace {

std::string number(double value, int precision = 4) {
    std::ostringstream out;
    out.precision(precision);
    out << (value == 0.0 ? 0.0 : value);  // no "-0"
    return out.str();
}

std::string quatText(const Quat& q) {
    // "(" added to a named string: to a temporary, GCC 12 warns (-Wrestrict, a false positive).
    const std::string parts = number(q.w) + ", " + number(q.x) + ", " + number(q.y) + ", " + number(q.z);
    return "(" + parts + ")";
}

std::string complexText(const PartReport& part) {
    return number(part.complexReal) + (part.complexImaginary < 0 ? " - " : " + ") +
           number(std::abs(part.complexImaginary)) + "i";
}

/// Iteration at which the quaternion orbit of `start` under q^2 + c passes `bailout`; 0 if not within `limit`.
int quaternionEscape(Quat q, const Quat& c, double bailout, int limit) {
    for (int k = 1; k <= limit; ++k) {
        q = square(q) + c;
        if (norm(q) > bailout) return k;
    }
    return 0;
}

bool holdsFixed(const Slice& slice, int firstIndex) {
    for (const Vec8& axis : slice.axes)
        for (int index = firstIndex; index < firstIndex + 4; ++index)
            if (axis[index] != 0.0) return false;
    return true;
}

std::string partName(bool real) { return real ? "real part a" : "dual part b"; }

/// "The slice holds the dual part fixed at b = (...); its orbit under c_b escapes at iteration k..."
std::string fixedPartReason(const Fractal& fractal, const Slice& slice, bool real) {
    const int first = real ? 0 : 4;
    const Quat fixed =
        makeQuat(slice.origin[first], slice.origin[first + 1], slice.origin[first + 2], slice.origin[first + 3]);
    const Quat c = real ? fractal.c.a : fractal.c.b;
    const int escape = quaternionEscape(fixed, c, fractal.bailout, fractal.iterations);
    if (escape == 0) return "";
    const PartReport part = inspectPart(c);
    const char* letter = real ? "a" : "b";
    std::string reason =
        "the slice holds the " + partName(real) + " fixed at " + letter + " = " + quatText(fixed) +
        ", and that orbit escapes under c_" + letter + " = " + quatText(c) + " at iteration " + std::to_string(escape) +
        ", so every point of the slice escapes: the slice is empty for N >= " + std::to_string(escape) + " (N is " +
        std::to_string(fractal.iterations) + ").";
    if (!part.inMandelbrot)
        reason += " The " + partName(real) + "'s equivalent complex constant " + complexText(part) +
                  " lies outside the Mandelbrot set, so K(c_" + letter + ") is dust and no fixed " + letter +
                  " stays bounded; choose a constant whose " + partName(real) +
                  " is inside the Mandelbrot set, or a slice along " + letter + "'s axes.";
    else
        reason +=
            " Choose a slice origin whose " + partName(real) + " lies in K(c_" + std::string(letter) + "), e.g. 0.";
    return reason;
}

}  // namespace

PartReport inspectPart(const Quat& c) {
    PartReport part;
    part.c = c;
    part.complexReal = c.w;
    part.complexImaginary = std::sqrt(c.x * c.x + c.y * c.y + c.z * c.z);
    part.containmentRadius = containmentRadius(c);
    const std::complex<double> constant(part.complexReal, part.complexImaginary);
    std::complex<double> z = 0.0;
    for (int k = 1; k <= kMandelbrotIterations; ++k) {
        z = z * z + constant;
        if (std::norm(z) > 4.0) {
            part.inMandelbrot = false;
            part.mandelbrotEscape = k;
            break;
        }
    }
    return part;
}

std::string provenEmptyReason(const Params& params) {
    const Fractal& fractal = params.fractal;
    const Slice slice = params.slice.effective();
    if (!containingBounds(fractal, slice)) {
        return "the slice misses the containment region: every orbit with |a| > r_K(c_a) = " +
               number(containmentRadius(fractal.c.a)) +
               (fractal.variant == Variant::Dual ? std::string()
                                                 : " or |b| > r_K(c_b) = " + number(containmentRadius(fractal.c.b))) +
               " escapes, and no point of this slice is that close to the origin, so the slice is empty for every N."
               " Move slice.origin towards 0.";
    }
    std::string reason;
    if (holdsFixed(slice, 0)) reason = fixedPartReason(fractal, slice, true);
    if (reason.empty() && fractal.variant != Variant::Dual && holdsFixed(slice, 4))
        reason = fixedPartReason(fractal, slice, false);
    return reason;
}

InspectReport inspect(const Params& params, int samplesPerAxis) {
    InspectReport report;
    report.fractal = params.fractal;
    report.real = inspectPart(params.fractal.c.a);
    report.dual = inspectPart(params.fractal.c.b);
    const Slice slice = params.slice.effective();
    const Fractal& fractal = params.fractal;

    const std::optional<Bounds> contained = containingBounds(fractal, slice);
    report.bounds = params.bounds ? params.bounds : contained;
    report.emptyReason = provenEmptyReason(params);
    if (!report.bounds) return report;

    // Sample the cube around the bounds.
    const Bounds& bounds = *report.bounds;
    const int count = std::max(2, samplesPerAxis);
    std::size_t inside = 0;
    for (int iz = 0; iz < count; ++iz)
        for (int iy = 0; iy < count; ++iy)
            for (int ix = 0; ix < count; ++ix) {
                const glm::dvec3 offset = (glm::dvec3(ix, iy, iz) + 0.5) / double(count) * 2.0 - 1.0;
                if (evaluate(fractal, slice.map(bounds.center + offset * bounds.radius)).n == 0) ++inside;
            }
    report.samples = count * count * count;
    report.insideFraction = double(inside) / report.samples;

    if (report.emptyReason.empty() && inside == 0) {
        std::string reason =
            "no sampled point of the slice's bounds is inside the set at N = " + std::to_string(fractal.iterations) +
            " (" + std::to_string(report.samples) + " samples).";
        for (bool real : {true, false}) {
            if (!real && fractal.variant == Variant::Dual) continue;
            const PartReport& part = real ? report.real : report.dual;
            if (!part.inMandelbrot)
                reason += " The " + partName(real) + "'s equivalent complex constant " + complexText(part) +
                          " lies outside the Mandelbrot set, so its Julia set is dust: too thin for rays to hit.";
        }
        reason += " Try fewer iterations, another constant, or another slice.";
        report.emptyReason = reason;
    }
    return report;
}

std::string formatReport(const InspectReport& report) {
    std::ostringstream out;
    const Fractal& fractal = report.fractal;
    out << "variant:             " << variantName(fractal.variant) << "\n";
    out << "iterations N:        " << fractal.iterations << "\n";
    out << "bailout R:           " << number(fractal.bailout, 6) << " (at least " << number(minimumBailout(fractal), 6)
        << ")\n";
    for (bool real : {true, false}) {
        const PartReport& part = real ? report.real : report.dual;
        out << (real ? "real part c_a:       " : "dual part c_b:       ") << quatText(part.c) << "\n";
        out << "  equivalent complex " << complexText(part) << ": "
            << (part.inMandelbrot ? "inside the Mandelbrot set (did not escape in " +
                                        std::to_string(kMandelbrotIterations) + " iterations)"
                                  : "OUTSIDE the Mandelbrot set (escapes at iteration " +
                                        std::to_string(part.mandelbrotEscape) + "): its Julia set is dust")
            << "\n";
        out << "  containment radius r_K: " << number(part.containmentRadius, 6) << "\n";
    }
    if (fractal.variant == Variant::Dual)
        out << "note:                under variant dual only |a| decides escape; b is the derivative of a\n";
    if (report.bounds) {
        out << "bounds:              centre (" << number(report.bounds->center.x) << ", "
            << number(report.bounds->center.y) << ", " << number(report.bounds->center.z) << "), radius "
            << number(report.bounds->radius, 6)
            << (report.bounds->clipped ? " (clipped: the set is an extrusion along a dual axis)" : "") << "\n";
        out << "inside fraction:     " << number(100.0 * report.insideFraction, 4) << "% of " << report.samples
            << " samples in the bounds' cube\n";
    } else {
        out << "bounds:              none (the slice misses the containment region)\n";
    }
    out << "slice:               " << (report.emptyReason.empty() ? "not empty" : "EMPTY: " + report.emptyReason)
        << "\n";
    return out.str();
}

std::string reportJson(const InspectReport& report) {
    nlohmann::ordered_json document;
    document["variant"] = variantName(report.fractal.variant);
    document["iterations"] = report.fractal.iterations;
    document["bailout"] = report.fractal.bailout;
    for (bool real : {true, false}) {
        const PartReport& part = real ? report.real : report.dual;
        document[real ? "real" : "dual"] = {{"complex", {part.complexReal, part.complexImaginary}},
                                            {"in_mandelbrot", part.inMandelbrot},
                                            {"mandelbrot_escape", part.mandelbrotEscape},
                                            {"containment_radius", part.containmentRadius}};
    }
    if (report.bounds)
        document["bounds"] = {{"center", {report.bounds->center.x, report.bounds->center.y, report.bounds->center.z}},
                              {"radius", report.bounds->radius},
                              {"clipped", report.bounds->clipped}};
    else
        document["bounds"] = nullptr;
    document["samples"] = report.samples;
    document["inside_fraction"] = report.insideFraction;
    document["empty"] = !report.emptyReason.empty();
    document["empty_reason"] = report.emptyReason;
    return document.dump(2) + "\n";
}

}  // namespace dqj
