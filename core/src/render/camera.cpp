// The camera (render.hpp): the frame that fits the bounds in view, and the ray through a pixel.
#include "render/camera.hpp"

#include <numbers>

namespace dqj {

glm::dvec3 CameraFrame::rayDirection(double px, double py) const {
    return screenDirection(*this, screenX(*this, px), screenY(*this, py));
}

CameraFrame frameCamera(const Params& params, const Bounds& bounds) {
    const Camera& camera = params.camera;
    CameraFrame frame;
    frame.width = std::max(1, params.render.width);
    frame.height = std::max(1, params.render.height);
    const double halfFov = 0.5 * camera.fovDegrees * std::numbers::pi / 180.0;
    frame.tanHalfFov = std::tan(halfFov);
    const glm::dvec3 target = camera.target.value_or(bounds.center);
    if (camera.position) {
        frame.eye = *camera.position;
    } else {
        // Fit the bounding sphere in the narrower of the two fields of view, with 8% margin.
        const double aspect = static_cast<double>(frame.width) / frame.height;
        const double halfHorizontal = std::atan(frame.tanHalfFov * aspect);
        const double distance = bounds.radius / std::sin(std::min(halfFov, halfHorizontal)) * 1.08;
        const double length = glm::length(camera.direction);
        const glm::dvec3 away = length > 0.0 ? camera.direction / length : glm::dvec3(0.0, 0.0, 1.0);
        frame.eye = target + away * distance;
    }
    const glm::dvec3 view = target - frame.eye;
    frame.forward = glm::length(view) > 0.0 ? glm::normalize(view) : glm::dvec3(0.0, 0.0, -1.0);
    // If `up` is (nearly) along the view, any other up gives a valid frame: take the world
    // axis least aligned with the view.
    glm::dvec3 up = camera.up;
    if (!(glm::length(glm::cross(frame.forward, up)) > 1e-9 * glm::length(up))) {
        const glm::dvec3 f = glm::abs(frame.forward);
        up = f.x <= f.y && f.x <= f.z ? glm::dvec3(1, 0, 0) : (f.y <= f.z ? glm::dvec3(0, 1, 0) : glm::dvec3(0, 0, 1));
    }
    frame.right = glm::normalize(glm::cross(frame.forward, up));
    frame.up = glm::cross(frame.right, frame.forward);
    return frame;
}

}  // namespace dqj
