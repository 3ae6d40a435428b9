#include "renderer/gl/view_uniforms.h"

#include <algorithm>
#include <string>
#include <vector>

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
  auto setSlab = [&](const char* name, const std::optional<Fog>& fog) {
    const std::string n(name);
    const Fog f = fog.value_or(Fog{});
    setUniform3(gl, p, (n + "_slab").c_str(), {f.bottom_m, f.top_m, f.band_m});
    gl.ProgramUniform1f(p, gl.GetUniformLocation(p, (n + "_sigma").c_str()),
                        fog ? float(fogExtinction(*fog)) : 0.0f);
    setUniform3(gl, p, (n + "_colour").c_str(), f.colour);
  };
  setSlab("u_fog", scene.fog);
  setSlab("u_veil", inLayerVeil(scene));
  // The precipitation's slabs, the densest kPrecipitationSlabs (a scene holds at most nine),
  // and its shafts, camera-relative.
  PrecipitationMedia media = precipitationMedia(scene);
  std::vector<Fog>& precipitation = media.slabs;
  std::sort(precipitation.begin(), precipitation.end(),
            [](const Fog& a, const Fog& b) { return a.visibility_m < b.visibility_m; });
  for (int i = 0; i < kPrecipitationSlabs; ++i) {
    std::string element = "[";  // appended, not summed: GCC 12 warns -Wrestrict on the sum
    element.append(std::to_string(i)).append("]");
    const bool present = std::size_t(i) < precipitation.size();
    const Fog f = present ? precipitation[std::size_t(i)] : Fog{};
    setUniform3(gl, p, ("u_precip_slab" + element).c_str(), {f.bottom_m, f.top_m, f.band_m});
    gl.ProgramUniform1f(p, gl.GetUniformLocation(p, ("u_precip_sigma" + element).c_str()),
                        present ? float(fogExtinction(f)) : 0.0f);
    setUniform3(gl, p, ("u_precip_colour" + element).c_str(), f.colour);
  }
  const int shafts = int(std::min(media.shafts.size(), std::size_t(kMaxRainShafts)));
  std::vector<glm::vec4> shaft(std::size_t(shafts) + 1);
  std::vector<float> sigma(std::size_t(shafts) + 1);
  std::vector<glm::vec3> colour(std::size_t(shafts) + 1);
  for (int i = 0; i < shafts; ++i) {
    const RainShaft& s = media.shafts[std::size_t(i)];
    shaft[std::size_t(i)] = glm::vec4(glm::vec2(s.centre - glm::dvec2(camera.position)),
                                      float(s.radius_m), float(s.top_m));
    sigma[std::size_t(i)] = float(s.sigma);
    colour[std::size_t(i)] = glm::vec3(s.colour);
  }
  gl.ProgramUniform1i(p, gl.GetUniformLocation(p, "u_shafts"), shafts);
  if (shafts > 0) {
    gl.ProgramUniform4fv(p, gl.GetUniformLocation(p, "u_shaft"), shafts, &shaft[0].x);
    gl.ProgramUniform1fv(p, gl.GetUniformLocation(p, "u_shaft_sigma"), shafts, sigma.data());
    gl.ProgramUniform3fv(p, gl.GetUniformLocation(p, "u_shaft_colour"), shafts, &colour[0].x);
  }
  const std::optional<Haze>& haze = scene.haze;
  gl.ProgramUniform1f(p, gl.GetUniformLocation(p, "u_haze_sigma"),
                      haze ? float(extinctionForVisibility(haze->visibility_m)) : 0.0f);
  gl.ProgramUniform1f(p, gl.GetUniformLocation(p, "u_haze_height"),
                      haze ? float(haze->scale_height_m) : 1.0f);
  setUniform3(gl, p, "u_haze_colour", scene.sky.horizon);
}

}  // namespace nephele
