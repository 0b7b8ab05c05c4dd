// Colouring and shading (coloring.hpp): the smooth count, the trap's scale, the palette and the
// orbit colour. The Phong terms are inline in the header (one call a ray and light).
#include "dqjulia/coloring.hpp"

#include <cmath>

namespace dqj {

double trapScale(const Fractal& fractal) { return kTrapScaleFactor * containmentRadius(fractal.c.a); }

double smoothIterations(const Fractal& fractal, const Escape& escape) {
    if (escape.n == 0 || !(escape.r > 1.0)) return fractal.iterations;
    return escape.n + 1.0 - std::log2(std::log(escape.r) / std::log(fractal.bailout));
}

double coloringValue(Coloring coloring, const Fractal& fractal, const Escape& escape) {
    switch (coloring) {
        case Coloring::Solid: return 0.0;
        case Coloring::Iterations: return smoothIterations(fractal, escape) / fractal.iterations;
        case Coloring::Trap: return escape.trap / trapScale(fractal);
    }
    return 0.0;
}

glm::dvec3 paletteColour(const Material& material, double value) {
    const auto& colours = material.palette;
    if (colours.empty()) return material.color;
    if (colours.size() == 1 || !(value > 0.0)) return colours.front();
    if (value >= 1.0) return colours.back();
    const double position = value * static_cast<double>(colours.size() - 1);
    const auto index = static_cast<std::size_t>(position);
    const double fraction = position - static_cast<double>(index);
    return colours[index] * (1.0 - fraction) + colours[index + 1] * fraction;
}

glm::dvec3 orbitColour(const Material& material, const Fractal& fractal, const Escape& escape) {
    if (material.coloring == Coloring::Solid) return material.color;
    return paletteColour(material, coloringValue(material.coloring, fractal, escape));
}

}  // namespace dqj
