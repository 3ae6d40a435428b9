#include "renderer/gl/automaton_renderer.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "renderer/gl/shaders/automaton_glsl.h"
#include "renderer/gl/sky_shaders.h"
#include "renderer/gl/view_uniforms.h"
#include "world/check.h"

namespace nephele {
namespace {

constexpr int kLatticeTextureUnit = 13;
constexpr int kSkyTextureUnit = 8;
constexpr int kMaxMarchSteps = 2048;

using glsl::automaton::kVolumePass;  // shaders/automaton/volume_pass.glsl

// The screen rectangle (NDC) covering the box, or the whole screen when the box reaches
// behind the camera.
std::vector<glm::vec2> screenRectangle(const Camera& camera, glm::dvec3 lo, glm::dvec3 hi) {
  const ViewBasis b = viewBasis(camera);
  const std::vector<glm::vec2> full{{-1, -1}, {3, -1}, {-1, 3}};
  glm::dvec2 min_ndc(1e30), max_ndc(-1e30);
  for (int corner = 0; corner < 8; ++corner) {
    const glm::dvec3 p =
        glm::dvec3(corner & 1 ? hi.x : lo.x, corner & 2 ? hi.y : lo.y, corner & 4 ? hi.z : lo.z) -
        camera.position;
    const double depth = glm::dot(p, b.forward);
    if (depth <= 1e-3 * glm::length(p) + 1e-6) return full;
    const glm::dvec2 ndc(glm::dot(p, b.right) / (depth * b.tan_half_vfov * b.aspect),
                         glm::dot(p, b.up) / (depth * b.tan_half_vfov));
    min_ndc = glm::min(min_ndc, ndc);
    max_ndc = glm::max(max_ndc, ndc);
  }
  // One pixel of margin; the shader discards what misses the box.
  const glm::dvec2 pixel(2.0 / camera.width, 2.0 / camera.height);
  min_ndc = glm::clamp(min_ndc - pixel, -1.0, 1.0);
  max_ndc = glm::clamp(max_ndc + pixel, -1.0, 1.0);
  if (min_ndc.x >= max_ndc.x || min_ndc.y >= max_ndc.y) return {};
  return {glm::vec2(min_ndc), {max_ndc.x, min_ndc.y}, glm::vec2(max_ndc), {min_ndc.x, max_ndc.y}};
}

}  // namespace

AutomatonRenderer::AutomatonRenderer(const GlApi& gl)
    : gl_(gl), vertex_array_(createVertexArray(gl)) {}

void AutomatonRenderer::beginFrame(FrameStats& stats) {
  stats_ = &stats;
  for (auto& [key, volume] : volumes_) volume.used = false;
}

void AutomatonRenderer::endFrame() {
  std::erase_if(volumes_, [](const auto& entry) { return !entry.second.used; });
}

GLuint AutomatonRenderer::program(unsigned air, bool targets, PhaseFunction phase) {
  std::string defines = airDefines(air);
  if (targets) defines += "#define TARGETS\n";
  if (phase == PhaseFunction::kCornetteShanks) defines += "#define CORNETTE_SHANKS\n";
  auto found = programs_.find(defines);
  if (found != programs_.end()) return found->second.get();
  const std::string fragment = "#version 450 core\n" + defines + "#define MAX_STEPS " +
                               std::to_string(kMaxMarchSteps) + "\n" + viewShaderSource() +
                               kVolumePass;
  std::string error;
  GlObject compiled = createProgram(gl_, polygonVertexSource(), fragment, error);
  NEPHELE_CHECK(compiled, "automaton cloud pass: " << error);
  return programs_.emplace(defines, std::move(compiled)).first->second.get();
}

AutomatonRenderer::Volume& AutomatonRenderer::volume(const Scene& scene, std::size_t index) {
  const AutomatonCloudView& cloud = scene.automata[index];
  Volume& v = volumes_[std::to_string(index) + "/" + cloud.name];
  v.used = true;
  if (v.texture && v.from == cloud.from && v.to == cloud.to) return v;
  // New keyframes: interleave both into two RGBA textures (density, sunlight, density,
  // sunlight) and (skylight, skylight, sun_diffuse, sun_diffuse).
  const DensityLattice& a = cloud.from->lattice;
  const DensityLattice& b = cloud.to->lattice;
  NEPHELE_CHECK(a.dims == b.dims, "keyframes on different lattices");
  StageClock clock(stats_->times.cpu(CpuStage::kUploads));
  std::vector<float> texels(a.density.size() * 4), sky(a.density.size() * 4);
  for (std::size_t i = 0; i < a.density.size(); ++i) {
    texels[4 * i + 0] = a.density[i];
    texels[4 * i + 1] = a.sunlight[i];
    texels[4 * i + 2] = b.density[i];
    texels[4 * i + 3] = b.sunlight[i];
    sky[4 * i + 0] = a.skylight[i];
    sky[4 * i + 1] = b.skylight[i];
    sky[4 * i + 2] = a.sun_diffuse[i];
    sky[4 * i + 3] = b.sun_diffuse[i];
  }
  if (!v.texture || !v.from || v.from->lattice.dims != a.dims) {
    auto make = [&](GLenum format) {
      GlObject texture = createTexture(gl_, GL_TEXTURE_3D);
      gl_.TextureStorage3D(texture.get(), 1, format, a.dims.x, a.dims.y, a.dims.z);
      gl_.TextureParameteri(texture.get(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
      gl_.TextureParameteri(texture.get(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
        gl_.TextureParameteri(texture.get(), wrap, GL_CLAMP_TO_EDGE);
      return texture;
    };
    v.texture = make(GL_RGBA32F);
    v.sky = make(GL_RGBA32F);
  }
  gl_.TextureSubImage3D(v.texture.get(), 0, 0, 0, 0, a.dims.x, a.dims.y, a.dims.z, GL_RGBA,
                        GL_FLOAT, texels.data());
  gl_.TextureSubImage3D(v.sky.get(), 0, 0, 0, 0, a.dims.x, a.dims.y, a.dims.z, GL_RGBA, GL_FLOAT,
                        sky.data());
  v.from = cloud.from;
  v.to = cloud.to;
  ++uploads_;
  ++stats_->volume_uploads;
  return v;
}

void AutomatonRenderer::drawCloud(const Scene& scene, std::size_t index,
                                  const RenderSettings& settings, bool targets_drawn,
                                  const AltitudeBand& band) {
  const AutomatonCloudView& cloud = scene.automata[index];
  // March only where either keyframe has density: the lattice samples that bound it.
  const DensityLattice& a = cloud.from->lattice;
  const DensityLattice& b = cloud.to->lattice;
  const glm::ivec3 lo = glm::min(a.occupied_lo, b.occupied_lo);
  const glm::ivec3 hi = glm::max(a.occupied_hi, b.occupied_hi);
  if (glm::any(glm::greaterThan(lo, hi))) return;  // no cloud in either keyframe
  const glm::dvec3 box_lo = cloud.corner + a.position(lo.x, lo.y, lo.z);
  const glm::dvec3 box_hi = cloud.corner + a.position(hi.x, hi.y, hi.z);
  const std::vector<glm::vec2> polygon = screenRectangle(scene.camera, box_lo, box_hi);
  if (polygon.empty()) return;
  const Volume& v = volume(scene, index);
  const GLuint p = program(airMedia(scene), targets_drawn, cloud.phase);
  gl_.UseProgram(p);
  setViewUniforms(gl_, p, scene.camera, scene, band);
  const glm::dvec3 eye = scene.camera.position;
  const DensityLattice& lattice = cloud.from->lattice;
  setUniform3(gl_, p, "u_box_min", box_lo - eye);
  setUniform3(gl_, p, "u_box_max", box_hi - eye);
  setUniform3(gl_, p, "u_lattice_origin", cloud.corner + lattice.origin - eye);
  setUniform3(gl_, p, "u_inv_dims", 1.0 / glm::dvec3(lattice.dims));
  setUniform3(gl_, p, "u_light", cloud.colour * scene.sun.colour);
  setUniform3(gl_, p, "u_to_sun", sunDirection(scene.sun));
  auto set = [&](const char* name, double value) {
    gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, name), float(value));
  };
  set("u_inv_spacing", 1.0 / lattice.spacing);
  set("u_blend", cloud.blend);
  set("u_step", lattice.spacing * settings.volume_step);
  set("u_extinction", kCloudExtinctionPerMetre);
  set("u_ambient", cloud.ambient);
  set("u_phase_g", cloud.phase_g);
  gl_.BindTextureUnit(kLatticeTextureUnit, v.texture.get());
  gl_.BindTextureUnit(kSkyTextureUnit, v.sky.get());
  gl_.ProgramUniform2fv(p, gl_.GetUniformLocation(p, "u_polygon"), GLsizei(polygon.size()),
                        &polygon[0].x);
  gl_.Enable(GL_BLEND);
  gl_.BlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  gl_.BindVertexArray(vertex_array_.get());
  gl_.DrawArrays(GL_TRIANGLE_FAN, 0, GLsizei(polygon.size()));
  ++stats_->automaton_passes;
}

}  // namespace nephele
