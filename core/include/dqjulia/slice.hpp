// dqjulia/slice.hpp - the affine map from 3-D to the 8-D space, and the 3-D bounds it gives.
//
// A slice is an origin (8 numbers) and three axis vectors (8 numbers each):
// p = (x, y, z) goes to origin + x*axes[0] + y*axes[1] + z*axes[2]. Axis names are
// "a.s a.i a.j a.k b.s b.i b.j b.k" (real part a, dual part b). The default slice maps
// x, y, z to a.s, a.i, a.j with everything else 0. Rotations turn the three axes in a
// plane of the 8-D space (the origin stays where it is), so an artist can turn the slice.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/vec3.hpp>

#include "dqjulia/algebra.hpp"
#include "dqjulia/estimate.hpp"
#include "dqjulia/export.h"

namespace dqj {

/// A rotation by `degrees` in the plane spanned by two 8-D coordinate axes (first -> second).
struct PlaneRotation {
    int first = 0;   ///< 8-D index 0..7
    int second = 1;  ///< 8-D index 0..7, different from first
    double degrees = 0.0;
};

struct Slice {
    Vec8 origin{};
    std::array<Vec8, 3> axes{Vec8{1, 0, 0, 0, 0, 0, 0, 0}, Vec8{0, 1, 0, 0, 0, 0, 0, 0}, Vec8{0, 0, 1, 0, 0, 0, 0, 0}};

    DualQuat map(const glm::dvec3& p) const {
        Vec8 z;  // an array, not component(z, index): a loop without a branch per coordinate
        for (int index = 0; index < 8; ++index) z[index] = coordinate(index, p);
        return toDualQuat(z);
    }
    /// Coordinate `index` (0..7) of map(p).
    double coordinate(int index, const glm::dvec3& p) const {
        return origin[index] + p.x * axes[0][index] + p.y * axes[1][index] + p.z * axes[2][index];
    }
};

/// "a.s" -> 0, ..., "b.k" -> 7; std::nullopt for anything else.
DQJ_API std::optional<int> parseAxisName(std::string_view name);
DQJ_API std::string axisName(int index);
/// "a.s,a.i,a.j" -> unit axes along those coordinates (origin 0). Throws std::invalid_argument
/// naming the bad part (unknown name, wrong count, repeated axis).
DQJ_API Slice sliceFromAxisNames(std::string_view shorthand);
/// The shorthand if every axis is a unit coordinate vector, else an empty string.
DQJ_API std::string axisNamesOf(const Slice& slice);

/// The slice with its axes turned by each rotation in order.
DQJ_API Slice rotated(Slice slice, const std::vector<PlaneRotation>& rotations);

/// Singular values of the 8x3 axis matrix: how much the map stretches 3-D lengths.
/// A 3-D step of length t moves at most stretchMax * t in 8-D, so the 8-D distance
/// estimate divided by stretchMax is a safe 3-D step. stretchMin = 0 means the axes
/// are zero or parallel (a degenerate slice).
struct Stretch {
    double max = 1.0;
    double min = 1.0;
};
DQJ_API Stretch stretchOf(const Slice& slice);

/// A sphere in slice (3-D) coordinates.
struct Bounds {
    glm::dvec3 center{0.0};
    double radius = 1.0;
    /// True when the set is unbounded in the slice (dual variant, slice along a dual axis:
    /// an extrusion) and the sphere clips it.
    bool clipped = false;
};

/// The smallest sphere that contains the slice's share of the containment region
/// (math.md: every orbit with |q| > r_K escapes). std::nullopt when the slice misses
/// that region entirely, so the slice is empty whatever N is.
DQJ_API std::optional<Bounds> containingBounds(const Fractal& fractal, const Slice& slice);

struct Params;  // params.hpp

/// The bounds everything that draws or samples the set starts from (the renderer, the bakes,
/// the POV-Ray scene, the add-on's preview): params.bounds if set, else containingBounds() of
/// the effective slice. Throws ParamError (params.hpp) if the slice misses the containment
/// region and no bounds are set.
DQJ_API Bounds renderBounds(const Params& params);

}  // namespace dqj
