#pragma once
// Uniforms of the view chunk (viewShaderSource) shared by every screen-space pass.
#include <optional>

#include "renderer/gl_api.h"
#include "world/frames.h"
#include "world/sky.h"

namespace nephele {

void setViewUniforms(const GlApi& gl, GLuint program, const Camera& camera,
                     const std::optional<Fog>& fog);

// Sets a vec3 uniform from doubles.
void setUniform3(const GlApi& gl, GLuint program, const char* name, glm::dvec3 value);

}  // namespace nephele
