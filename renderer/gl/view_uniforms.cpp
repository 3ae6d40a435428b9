#include "renderer/gl/view_uniforms.h"

namespace nephele {

void setUniform3(const GlApi& gl, GLuint program, const char* name, glm::dvec3 value) {
  const glm::vec3 f(value);
  gl.ProgramUniform3fv(program, gl.GetUniformLocation(program, name), 1, &f.x);
}

void setViewUniforms(const GlApi& gl, GLuint p, const Camera& camera, const std::optional<Fog>& fog,
                     const AltitudeBand& band) {
  gl.ProgramUniform4fv(p, gl.GetUniformLocation(p, "u_band"), 1, &band.slabs.x);
  const ViewBasis basis = viewBasis(camera);
  setUniform3(gl, p, "u_right", basis.right * basis.tan_half_vfov * basis.aspect);
  setUniform3(gl, p, "u_up", basis.up * basis.tan_half_vfov);
  setUniform3(gl, p, "u_forward", basis.forward);
  const glm::vec2 viewport(camera.width, camera.height);
  gl.ProgramUniform2fv(p, gl.GetUniformLocation(p, "u_viewport"), 1, &viewport.x);
  gl.ProgramUniform1f(p, gl.GetUniformLocation(p, "u_camera_z"), float(camera.position.z));
  if (fog) {
    gl.ProgramUniform1f(p, gl.GetUniformLocation(p, "u_fog_top"), float(fog->top_m));
    gl.ProgramUniform1f(p, gl.GetUniformLocation(p, "u_fog_sigma"), float(fogExtinction(*fog)));
    setUniform3(gl, p, "u_fog_colour", fog->colour);
  }
}

}  // namespace nephele
