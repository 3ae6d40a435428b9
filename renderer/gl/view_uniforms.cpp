#include "renderer/gl/view_uniforms.h"

namespace nephele {

void setUniform3(const GlApi& gl, GLuint program, const char* name, glm::dvec3 value) {
  const glm::vec3 f(value);
  gl.ProgramUniform3fv(program, gl.GetUniformLocation(program, name), 1, &f.x);
}

void setViewUniforms(const GlApi& gl, GLuint p, const Camera& camera, const Scene& scene,
                     const AltitudeBand& band) {
  gl.ProgramUniform4fv(p, gl.GetUniformLocation(p, "u_band"), 1, &band.slabs.x);
  const ViewBasis basis = viewBasis(camera);
  setUniform3(gl, p, "u_right", basis.right * basis.tan_half_vfov * basis.aspect);
  setUniform3(gl, p, "u_up", basis.up * basis.tan_half_vfov);
  setUniform3(gl, p, "u_forward", basis.forward);
  const glm::vec2 viewport(camera.width, camera.height);
  gl.ProgramUniform2fv(p, gl.GetUniformLocation(p, "u_viewport"), 1, &viewport.x);
  gl.ProgramUniform1f(p, gl.GetUniformLocation(p, "u_camera_z"), float(camera.position.z));
  // An absent medium has zero extinction (the shaders take the air only when the scene has
  // some: sceneHasAir).
  const std::optional<Fog>& fog = scene.fog;
  gl.ProgramUniform1f(p, gl.GetUniformLocation(p, "u_fog_top"), fog ? float(fog->top_m) : 0.0f);
  gl.ProgramUniform1f(p, gl.GetUniformLocation(p, "u_fog_sigma"),
                      fog ? float(fogExtinction(*fog)) : 0.0f);
  setUniform3(gl, p, "u_fog_colour", fog ? fog->colour : Fog{}.colour);
  const std::optional<Haze>& haze = scene.haze;
  gl.ProgramUniform1f(p, gl.GetUniformLocation(p, "u_haze_sigma"),
                      haze ? float(extinctionForVisibility(haze->visibility_m)) : 0.0f);
  gl.ProgramUniform1f(p, gl.GetUniformLocation(p, "u_haze_height"),
                      haze ? float(haze->scale_height_m) : 1.0f);
  setUniform3(gl, p, "u_haze_colour", scene.sky.horizon);
}

}  // namespace nephele
