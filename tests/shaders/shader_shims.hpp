// shader_shims.hpp - compiles the add-on's shader sources as C++ against GLM, so the test
// suite can hold them equal to the core: the GLSL distance estimate and sphere tracer
// (dqjulia_de.glsl), the GLSL colouring and Phong terms (dqjulia_shading.glsl), the OSL density.
//
// GLM mirrors GLSL's types and functions, so the GLSL needs nothing but names in scope; the
// OSL code writes a quaternion as float + vector and marks output parameters with DQJ_OUT,
// which becomes a reference here. Both compute in float, as on the GPU and in OSL.
#pragma once

#include <glm/glm.hpp>

namespace glsl {
using glm::dot;
using glm::length;
using glm::log;
using glm::log2;
using glm::mat4;
using glm::max;
using glm::min;
using glm::normalize;
using glm::pow;
using glm::sqrt;
using glm::vec2;
using glm::vec3;
using glm::vec4;
#include DQJ_GLSL_DE_SOURCE
#include DQJ_GLSL_SHADING_SOURCE
}  // namespace glsl

namespace osl {
using vector = glm::vec3;
using glm::dot;
using glm::log;
using glm::max;
using glm::min;
using glm::sqrt;
#define DQJ_OUT(type) type&
#define DQJ_OSL_FUNCTIONS_ONLY
#include DQJ_OSL_SOURCE
#undef DQJ_OUT
#undef DQJ_OSL_FUNCTIONS_ONLY
}  // namespace osl
