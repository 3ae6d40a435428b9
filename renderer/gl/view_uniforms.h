#pragma once
// Uniforms of the view chunk (viewShaderSource) shared by every screen-space pass.
#include <optional>

#include "renderer/gl/gl_api.h"
#include "world/camera.h"
#include "world/scene.h"

namespace nephele {
// The precipitation slabs a view's air holds at most (the densest; setViewUniforms).
inline constexpr int kPrecipitationSlabs = 4;
}  // namespace nephele

namespace nephele {

// The altitude band a cloud pass draws, relative to the camera: surfaces at height dz above
// it with slabs.x <= dz < slabs.y or slabs.z <= dz < slabs.w (the view chunk's inBand). The
// default passes everything.
struct AltitudeBand {
  glm::vec4 slabs{-1e38f, 1e38f, 0.0f, 0.0f};
};

// The view from `camera` and the air (fog, haze) of `scene`.
void setViewUniforms(const GlApi& gl, GLuint program, const Camera& camera, const Scene& scene,
                     const AltitudeBand& band = {});

// Sets a vec3 uniform from doubles.
void setUniform3(const GlApi& gl, GLuint program, const char* name, glm::dvec3 value);

}  // namespace nephele
