// The prelude of the formulas that the GL renderer and the CPU reference share, each header of
// world/formulas/ written once in the common ground of C++ and GLSL and compiled as both:
//   - in C++ (world/sky.cpp, world/shading.cpp, ...), in double precision over glm types in
//     namespace nephele::formulas, where the public functions of world/ keep their guards for
//     infinities and call these;
//   - in GLSL, in float, pasted by the build ahead of the shaders' own code
//     (renderer/gl/shaders/glsl.cmake), where the shaders call these with their uniforms.
// So a header holds plain functions only: scalars and vectors (real, vec2, vec3, vec4) in, one
// out, the built-ins both sides know (those declared below), literals without suffix, and no
// references, containers or overloads. Each side keeps the operation order it had, so that
// the GPU's float results and the reference's double ones are those of its own formula.
// FORMULA marks each function (inline in C++, nothing in GLSL), CONSTANT each constant
// (constexpr in C++, const in GLSL).
#ifdef __cplusplus
#pragma once
#include <glm/glm.hpp>

#include <cmath>

namespace nephele::formulas {
// GLSL's built-ins, declared here so that no function of an enclosing namespace hides them.
using glm::abs, glm::acos, glm::clamp, glm::cos, glm::cross, glm::dot, glm::exp, glm::floor,
    glm::length, glm::log2, glm::max, glm::min, glm::mix, glm::normalize, glm::pow, glm::sin,
    glm::sqrt;
using real = double;
using vec2 = glm::dvec2;
using vec3 = glm::dvec3;
using vec4 = glm::dvec4;
}  // namespace nephele::formulas
#define FORMULA inline
#define CONSTANT constexpr
#else
#define real float
#define FORMULA
#define CONSTANT const
#endif
