// The coloring unit (coloring.hpp) against values worked out by hand: the smooth count and its
// guard, the trap's scale, the palette's ends, stops and clamping, the orbit colour of each
// colouring, and the Phong terms for simple geometry. Its ports (GLSL, POV-Ray) are compared
// with it in tests/shaders and tests/povray.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "dqjulia/coloring.hpp"

using namespace dqj;

namespace {

Escape escaped(int n, double r, double trap = 0.0) {
    Escape e;
    e.n = n;
    e.r = r;
    e.trap = trap;
    return e;
}

void expectColour(const glm::dvec3& got, const glm::dvec3& want) {
    EXPECT_NEAR(got.x, want.x, 1e-15);
    EXPECT_NEAR(got.y, want.y, 1e-15);
    EXPECT_NEAR(got.z, want.z, 1e-15);
}

TEST(Coloring, SmoothIterationsAndItsGuard) {
    Fractal fractal;
    fractal.iterations = 20;
    fractal.bailout = 4.0;
    // r = R: ln r / ln R = 1, so the count is n + 1; r = R^2: log2(2) = 1 less, n.
    EXPECT_DOUBLE_EQ(smoothIterations(fractal, escaped(5, 4.0)), 6.0);
    EXPECT_DOUBLE_EQ(smoothIterations(fractal, escaped(5, 16.0)), 5.0);
    // Not escaped, and exit norms whose logarithms are useless: N.
    EXPECT_EQ(smoothIterations(fractal, escaped(0, 100.0)), 20.0);
    EXPECT_EQ(smoothIterations(fractal, escaped(5, 1.0)), 20.0);
    EXPECT_EQ(smoothIterations(fractal, escaped(5, std::numeric_limits<double>::quiet_NaN())), 20.0);
    EXPECT_DOUBLE_EQ(coloringValue(Coloring::Iterations, fractal, escaped(5, 16.0)), 0.25);
    EXPECT_EQ(coloringValue(Coloring::Iterations, fractal, escaped(0, 0.0)), 1.0);
}

TEST(Coloring, TrapScaleIsTheNamedFractionOfTheContainmentRadius) {
    Fractal fractal;
    fractal.c.a = makeQuat(0.75, 0.0, 0.0, 0.0);  // |c| = 0.75: r_K = (1 + sqrt(4)) / 2 = 1.5
    EXPECT_DOUBLE_EQ(trapScale(fractal), kTrapScaleFactor * 1.5);
    EXPECT_DOUBLE_EQ(coloringValue(Coloring::Trap, fractal, escaped(3, 5.0, 0.5 * trapScale(fractal))), 0.5);
    EXPECT_EQ(coloringValue(Coloring::Solid, fractal, escaped(3, 5.0, 1.0)), 0.0);
}

TEST(Coloring, PaletteIsEvenlySpacedLinearAndClamped) {
    Material material;
    material.palette = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    expectColour(paletteColour(material, 0.0), {1, 0, 0});
    expectColour(paletteColour(material, 0.5), {0, 1, 0});
    expectColour(paletteColour(material, 1.0), {0, 0, 1});
    expectColour(paletteColour(material, 0.25), {0.5, 0.5, 0});
    expectColour(paletteColour(material, 0.875), {0, 0.25, 0.75});
    expectColour(paletteColour(material, -3.0), {1, 0, 0});
    expectColour(paletteColour(material, 7.0), {0, 0, 1});
    expectColour(paletteColour(material, std::numeric_limits<double>::quiet_NaN()), {1, 0, 0});
    material.palette = {{0.2, 0.3, 0.4}};
    expectColour(paletteColour(material, 0.6), {0.2, 0.3, 0.4});
    material.palette.clear();
    expectColour(paletteColour(material, 0.6), material.color);
}

TEST(Coloring, OrbitColourOfEachColouring) {
    Fractal fractal;
    fractal.iterations = 10;
    fractal.bailout = 4.0;
    Material material;
    material.color = {0.1, 0.2, 0.3};
    material.palette = {{0, 0, 0}, {1, 1, 1}};
    material.coloring = Coloring::Solid;
    expectColour(orbitColour(material, fractal, escaped(4, 16.0, 0.1)), {0.1, 0.2, 0.3});
    material.coloring = Coloring::Iterations;
    expectColour(orbitColour(material, fractal, escaped(4, 16.0)), {0.4, 0.4, 0.4});  // smooth count 4 of 10
    expectColour(orbitColour(material, fractal, escaped(0, 0.0)), {1, 1, 1});         // inside: the last colour
    material.coloring = Coloring::Trap;
    const double t = 0.3 * trapScale(fractal);
    expectColour(orbitColour(material, fractal, escaped(0, 0.0, t)), {0.3, 0.3, 0.3});
}

TEST(Coloring, PhongTermsForSimpleGeometry) {
    Material material;
    material.ambient = 0.2;
    material.diffuse = 0.5;
    material.specular = 0.25;
    material.shininess = 2.0;
    const glm::dvec3 base(1.0, 0.5, 0.25);
    const glm::dvec3 radiance(1.0, 1.0, 2.0);
    const glm::dvec3 up(0, 0, 1);
    expectColour(phongAmbient(material, base, 0.5), {0.1, 0.05, 0.025});
    // Light and eye straight above: N.L = 1, R = N, R.V = 1; open, so no diffuse occlusion.
    expectColour(phongLight(material, base, up, up, up, radiance, 1.0), {0.75, 0.5, 0.75});
    // Fully occluded: diffuse times 0.7.
    expectColour(phongLight(material, base, up, up, up, radiance, 0.0), {0.6, 0.425, 0.675});
    // Light at 60 degrees (N.L = 0.5), eye along its reflection: R.V = 1.
    const glm::dvec3 light(std::sqrt(0.75), 0.0, 0.5);
    const glm::dvec3 mirror(-std::sqrt(0.75), 0.0, 0.5);
    const glm::dvec3 got = phongLight(material, base, up, light, mirror, radiance, 1.0);
    EXPECT_NEAR(got.x, 0.5 * 0.5 * 1.0 + 0.25, 1e-14);
    EXPECT_NEAR(got.z, (0.5 * 0.5 * 0.25 + 0.25) * 2.0, 1e-14);
    // Behind the surface: nothing, even with the eye along the reflection.
    expectColour(phongLight(material, base, up, -light, -mirror, radiance, 1.0), {0, 0, 0});
}

}  // namespace
