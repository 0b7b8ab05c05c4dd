// dqjulia/coloring.hpp - colouring and shading, in one place: the smooth escape count, the
// orbit trap's scale, the palette, the orbit colour of each Coloring and the Phong term.
//
// The renderer, the voxel renderer, the bakes (the "color", "iterations" and "trap" grids and
// the mesh's vertex colours) and the POV-Ray writer use these functions and nothing else. Two
// ports are written from this file and held equal to it by tests: the add-on's viewport preview
// (blender_addon/dqjulia/shaders/dqjulia_shading.glsl, tests/shaders) and the POV-Ray include
// (povray/dqjulia.inc, tests/povray); they keep its names (dqj_orbit_colour, DQJ_Trap_Scale...).
// Cost: two logarithms for the smooth count, one pow a light for Phong.
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>
#include <glm/vec3.hpp>

#include "dqjulia/estimate.hpp"
#include "dqjulia/export.h"
#include "dqjulia/params.hpp"

namespace dqj {

/// The trap colouring divides the orbit trap (the smallest |a| along the orbit) by this times
/// r_K(c_a). The trap ranges over [0, r_K(c_a)] (math.md: an orbit beyond r_K escapes), and on
/// the surface it is mostly below half of r_K; 0.65 r_K spreads the default set's values over
/// the whole palette.
inline constexpr double kTrapScaleFactor = 0.65;

/// The trap value that reaches the palette's last colour: kTrapScaleFactor * r_K(c_a).
DQJ_API double trapScale(const Fractal& fractal);

/// The smooth escape count n + 1 - log2(ln r / ln R): the escape iteration n plus the fraction
/// of an iteration by which the exit norm r overshot the bailout R (in (n - 1, n + 1]). N for a
/// point that did not escape, and for an exit norm not above 1 (whose logarithms are useless).
DQJ_API double smoothIterations(const Fractal& fractal, const Escape& escape);

/// Where a point falls on the palette (0 = first colour, 1 = last; values beyond are clamped by
/// paletteColour): `iterations` the smooth count / N (1 inside), `trap` the trap / trapScale.
/// `solid` uses no palette: 0.
DQJ_API double coloringValue(Coloring coloring, const Fractal& fractal, const Escape& escape);

/// The palette at `value`: its colours evenly spaced over [0, 1] (colour i of n at i / (n - 1)),
/// linear between neighbours; value <= 0 (and NaN) gives the first colour, value >= 1 the last.
/// An empty palette gives material.color.
DQJ_API glm::dvec3 paletteColour(const Material& material, double value);

/// The material's colour (linear RGB) for a point with this escape result: `solid` gives
/// material.color, `iterations` and `trap` the palette at coloringValue().
DQJ_API glm::dvec3 orbitColour(const Material& material, const Fractal& fractal, const Escape& escape);

/// The ambient term of the paper's Phong equation, k_a * open * C, with C the surface's colour
/// (orbitColour) and `open` its ambient occlusion (1 = open, 0 = fully occluded).
inline glm::dvec3 phongAmbient(const Material& material, const glm::dvec3& base, double open) {
    return material.ambient * open * base;
}

/// One directional light's diffuse and specular terms of the paper's Phong equation,
///     (k_d (N.L) (0.7 + 0.3 open) C + k_s max(0, R.V)^s) * radiance,   R = 2 (N.L) N - L,
/// for the unit normal N, the unit direction L towards the light and V towards the eye; 0 when
/// the light is behind the surface (N.L <= 0). Creases (open < 1) lose some direct light too.
/// Shadows multiply the result by the light's visibility.
inline glm::dvec3 phongLight(const Material& material, const glm::dvec3& base, const glm::dvec3& normal,
                             const glm::dvec3& toLight, const glm::dvec3& toEye, const glm::dvec3& radiance,
                             double open) {
    const double facing = glm::dot(normal, toLight);
    if (facing <= 0.0) return glm::dvec3(0.0);
    const double diffuseOcclusion = 0.7 + 0.3 * open;
    const glm::dvec3 reflected = 2.0 * facing * normal - toLight;
    const double highlight = std::pow(std::max(0.0, glm::dot(reflected, toEye)), material.shininess);
    return (material.diffuse * facing * diffuseOcclusion * base + material.specular * highlight) * radiance;
}

}  // namespace dqj
