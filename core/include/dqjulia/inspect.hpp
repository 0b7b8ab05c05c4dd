// dqjulia/inspect.hpp - what a constant and slice give, and why a slice is empty.
//
// A quaternion constant c is equivalent, up to a rotation of the imaginary axes, to the
// complex number c0 + |c_v| i; outside the Mandelbrot set its Julia set is dust (math.md).
// Under the paper's rule a slice that holds one part fixed is empty as soon as that part's
// own orbit escapes. The renderer and the CLI use this to say why a picture is empty.
// Cost: samplesPerAxis^3 evaluations for the inside fraction.
#pragma once

#include <optional>
#include <string>

#include "dqjulia/export.h"
#include "dqjulia/params.hpp"

namespace dqj {

/// One part (real a or dual b) of the constant.
struct PartReport {
    Quat c;
    double complexReal = 0.0;       ///< c0
    double complexImaginary = 0.0;  ///< |c_v|
    bool inMandelbrot = true;       ///< false only when the orbit of 0 provably escapes
    int mandelbrotEscape = 0;       ///< iteration at which 0 escaped under z^2 + (c0 + |c_v| i); 0 = did not
    double containmentRadius = 0.0;
};

struct InspectReport {
    Fractal fractal;
    PartReport real;
    PartReport dual;
    std::optional<Bounds> bounds;  ///< the render bounds; nullopt when the slice misses the set
    int samples = 0;               ///< points sampled in the cube around the bounds
    double insideFraction = 0.0;   ///< fraction of those inside at N
    /// Why the slice is (or will be) empty, in words a user can act on; empty if it is not.
    std::string emptyReason;
};

/// Iterations used to decide whether an equivalent complex constant is in the Mandelbrot set.
inline constexpr int kMandelbrotIterations = 10000;

DQJ_API PartReport inspectPart(const Quat& c);
/// Cheap proofs of emptiness, without sampling: the slice misses the containment region, or it
/// holds a part fixed whose own orbit escapes within N (the paper's rule; a only for dual).
/// Returns the reason, or "" when neither applies. The renderer draws nothing for such a
/// slice: its distance estimate would still stop rays near the other part's set.
DQJ_API std::string provenEmptyReason(const Params& params);
/// Analyses the parameter set; samplesPerAxis^3 points for the inside fraction.
DQJ_API InspectReport inspect(const Params& params, int samplesPerAxis = 32);
/// The report as the text `dqjulia inspect` prints.
DQJ_API std::string formatReport(const InspectReport& report);
/// The report as a JSON object (for scripts and the Blender add-on).
DQJ_API std::string reportJson(const InspectReport& report);

}  // namespace dqj
