// camera.hpp - rays through the image: the image plane's coordinates of a pixel and the
// direction through them (CameraFrame::rayDirection in parts), and where a ray meets the bounding
// sphere (internal to libdqjulia; frameCamera and rayDirection in camera.cpp). Cost: a few
// operations, inline: the renderer's tiles call them per sub-pixel column, row and cone.
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

#include "dqjulia/render.hpp"

namespace dqj {

/// CameraFrame::rayDirection in parts: the image plane's x of a pixel column, its y of a row,
/// and the direction through (x, y). A tile works its columns and rows out once; the same
/// expressions give the same directions, bit for bit.
inline double screenX(const CameraFrame& camera, double px) {
    const double aspect = static_cast<double>(camera.width) / camera.height;
    return (2.0 * px / camera.width - 1.0) * camera.tanHalfFov * aspect;
}
inline double screenY(const CameraFrame& camera, double py) {
    return (1.0 - 2.0 * py / camera.height) * camera.tanHalfFov;  // image rows go down, `up` goes up
}
inline glm::dvec3 screenDirection(const CameraFrame& camera, double x, double y) {
    return glm::normalize(camera.forward + x * camera.right + y * camera.up);
}

/// Where a ray meets a sphere: [near, far] along the ray, or nothing.
struct Interval {
    bool valid = false;
    double near = 0.0;
    double far = 0.0;
};

inline Interval intersectSphere(const glm::dvec3& origin, const glm::dvec3& direction, const Bounds& bounds) {
    const glm::dvec3 offset = origin - bounds.center;
    const double b = glm::dot(offset, direction);
    const double c = glm::dot(offset, offset) - bounds.radius * bounds.radius;
    const double discriminant = b * b - c;
    if (discriminant < 0.0) return {};
    const double root = std::sqrt(discriminant);
    if (-b + root < 0.0) return {};  // the sphere is behind the origin
    return {true, std::max(0.0, -b - root), -b + root};
}

}  // namespace dqj
