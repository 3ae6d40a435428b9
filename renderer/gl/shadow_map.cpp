#include "renderer/gl/shadow_map.h"

#include <algorithm>
#include <cstring>
#include <string>

#include "renderer/gl/gl_platform.h"
#include "renderer/gl/shaders/shadow_map_glsl.h"
#include "renderer/gl/sky_shaders.h"
#include "world/check.h"

namespace nephele {
namespace {

// Caster i is texels 4i to 4i + 3 of u_casters: its centre from the map's centre (x, y) and
// its altitude (z), its reach (w); then the rows of W (xyz), with its extinction (row 1's w)
// and its table's row (row 2's w).
using glsl::shadow_map::kVertex;  // shaders/shadow_map/footprint_vertex.glsl

// casterSunlight (world/formations/cloud_shadow.cpp) at the texel's ground point.
using glsl::shadow_map::kFragment;  // shaders/shadow_map/sunlight.glsl

// FNV-1a over raw bytes.
void hashBytes(std::uint64_t& h, const void* data, std::size_t bytes) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) h = (h ^ p[i]) * 0x100000001b3ull;
}

// The casters as the shader reads them, four rows each: the centre from the map's centre (the
// anchor plus `centre`), its height and reach; the rows of its W, its extinction and table.
std::vector<glm::vec4> casterRecords(const CloudShadows& shadows, glm::dvec2 anchor,
                                     glm::dvec2 centre) {
  std::vector<glm::vec4> records;
  records.reserve(shadows.casters().size() * 4);
  for (const ShadowCaster& c : shadows.casters()) {
    const glm::dmat3 w = glm::transpose(c.to_unit);  // columns of the transpose: rows of W
    records.emplace_back(glm::dvec2(c.centre) - anchor - centre, c.centre.z, c.reach);
    records.emplace_back(w[0], 0.0);
    records.emplace_back(w[1], c.extinction);
    records.emplace_back(w[2], double(c.table));
  }
  return records;
}

}  // namespace

ShadowMap::ShadowMap(const GlApi& gl) : gl_(gl) {}

void ShadowMap::prepare(const CloudShadows& shadows, glm::dvec3 camera, int size, FrameStats& stats,
                        GpuPassTimer& timer) {
  active_ = false;
  if (size <= 0 || shadows.empty()) return;
  // Everything is placed from an anchor, the first caster's centre, so that a world whose
  // clouds only drifted together (a field in the wind) keeps its map, moved with them. The map
  // is the casters' shadows within a square about the camera's ground point (twice shadowRange),
  // its edges on a grid of a sixteenth of that in the anchor's frame: a camera that moves less
  // keeps it too.
  const glm::dvec2 anchor(shadows.casters().front().centre);
  const double side = 2.0 * shadowRange(camera.z), step = side / 16.0;
  const glm::dvec2 eye = glm::round((glm::dvec2(camera) - anchor) / step) * step;
  // A step beyond the casters' shadows, so that the map's faded rim (the sky pass) holds none.
  const glm::dvec2 lo =
      glm::floor(glm::max(shadows.lo() - anchor - step, eye - 0.5 * side) / step) * step;
  const glm::dvec2 hi =
      glm::ceil(glm::min(shadows.hi() - anchor + step, eye + 0.5 * side) / step) * step;
  if (!(lo.x < hi.x && lo.y < hi.y)) return;
  active_ = true;
  const glm::dvec2 centre = 0.5 * (lo + hi);  // from the anchor
  const double half = 0.5 * std::max(hi.x - lo.x, hi.y - lo.y);

  const std::vector<glm::vec4> records = casterRecords(shadows, anchor, centre);
  std::vector<float> tables;
  for (const ShadowTable& t : shadows.tables()) tables.insert(tables.end(), t.begin(), t.end());
  const glm::vec3 to_sun(shadows.toSun());
  std::uint64_t key = 0xcbf29ce484222325ull;
  hashBytes(key, records.data(), records.size() * sizeof(glm::vec4));
  hashBytes(key, tables.data(), tables.size() * sizeof(float));
  hashBytes(key, &to_sun, sizeof to_sun);
  hashBytes(key, &size, sizeof size);
  hashBytes(key, &half, sizeof half);
  centre_ = anchor + centre;
  half_ = half;
  floor_ = shadows.floor();
  if (key == key_ && texture_) return;
  draw(shadows, records, tables, to_sun, size, half, stats, timer);
  key_ = key;
}

std::string ShadowMap::vertexSource() {
  return "#version 450 core\n" + formulaSource() + kVertex;
}

std::string ShadowMap::fragmentSource() {
  return "#version 450 core\nconst int kTableSize = " + std::to_string(kShadowTableSize) + ";\n" +
         formulaSource() + kFragment;
}

void ShadowMap::draw(const CloudShadows& shadows, const std::vector<glm::vec4>& records,
                     const std::vector<float>& tables, glm::vec3 to_sun, int size, double half,
                     FrameStats& stats, GpuPassTimer& timer) {
  StageClock clock(stats.times.cpu(CpuStage::kUploads));
  if (!program_) {
    std::string error;
    program_ = createProgram(gl_, vertexSource(), fragmentSource(), error);
    NEPHELE_CHECK(program_, "shadow map program: " << error);
    vertex_array_ = createVertexArray(gl_);
    framebuffer_ = createFramebuffer(gl_);
    records_buffer_ = createBuffer(gl_);
    records_ = createTexture(gl_, GL_TEXTURE_BUFFER);
  }
  if (size != size_) {
    texture_ = createTexture2D(gl_, GL_R16F, size, size);
    gl_.NamedFramebufferTexture(framebuffer_.get(), GL_COLOR_ATTACHMENT0, texture_.get(), 0);
    size_ = size;
  }
  // The tables, a row each (a fresh texture: their count changes).
  tables_ = createTexture(gl_, GL_TEXTURE_2D);
  const int rows = int(shadows.tables().size());
  gl_.TextureStorage2D(tables_.get(), 1, GL_R32F, kShadowTableSize, rows);
  gl_.TextureSubImage2D(tables_.get(), 0, 0, 0, kShadowTableSize, rows, GL_RED, GL_FLOAT,
                        tables.data());
  gl_.NamedBufferData(records_buffer_.get(), GLsizeiptr(records.size() * sizeof(glm::vec4)),
                      records.data(), GL_STREAM_DRAW);
  gl_.TextureBuffer(records_.get(), GL_RGBA32F, records_buffer_.get());

  GpuPassScope pass(timer, GpuPass::kShadows);
  const GLuint p = program_.get();
  gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffer_.get());
  gl_.Viewport(0, 0, size, size);
  const GLfloat lit[4] = {1.0f, 1.0f, 1.0f, 1.0f};
  gl_.ClearNamedFramebufferfv(framebuffer_.get(), GL_COLOR, 0, lit);
  gl_.UseProgram(p);
  gl_.BindVertexArray(vertex_array_.get());
  gl_.ProgramUniform3fv(p, gl_.GetUniformLocation(p, "u_to_sun"), 1, &to_sun.x);
  gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_half"), float(half));
  gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_size"), float(size));
  gl_.BindTextureUnit(13, records_.get());
  gl_.BindTextureUnit(12, tables_.get());
  // The product of every caster's share: dst = dst * src, in any order.
  gl_.Disable(GL_FRAMEBUFFER_SRGB);
  gl_.Enable(GL_BLEND);
  gl_.BlendFuncSeparate(GL_ZERO, GL_SRC_COLOR, GL_ZERO, GL_SRC_ALPHA);
  gl_.DrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, GLsizei(shadows.casters().size()));
  gl_.Disable(GL_BLEND);
  ++draws_;
  ++stats.shadow_maps;
}

void ShadowMap::bind(GLuint program, GLuint unit, glm::dvec3 camera) const {
  gl_.BindTextureUnit(unit, texture_.get());
  gl_.ProgramUniform1i(program, gl_.GetUniformLocation(program, "u_shadow_map"), GLint(unit));
  const glm::vec2 centre(centre_ - glm::dvec2(camera));
  gl_.ProgramUniform2fv(program, gl_.GetUniformLocation(program, "u_shadow_centre"), 1, &centre.x);
  gl_.ProgramUniform1f(program, gl_.GetUniformLocation(program, "u_shadow_half"), float(half_));
  gl_.ProgramUniform1f(program, gl_.GetUniformLocation(program, "u_shadow_floor"),
                       float(floor_ - camera.z));
}

}  // namespace nephele
