#include "renderer/gl/layer_clipmap.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "renderer/frame_stats.h"
#include "renderer/gl/sky_shaders.h"
#include "world/check.h"
#include "world/textures/gardner_texture.h"

namespace nephele {
namespace {

// Clipmaps kept per texture: views from different eyes (a host's channels) each keep their
// own, up to this many.
constexpr std::size_t kPerTexture = 4;
// Clipmaps kept in all, the least recently read dropped first (up to 16 MiB each).
constexpr std::size_t kKept = 6;

std::int64_t floorMod(std::int64_t a, std::int64_t n) {
  return ((a % n) + n) % n;
}

}  // namespace

void setLayerGardnerUniforms(const GlApi& gl, GLuint p, int slot, const GardnerTexture& g,
                             glm::dvec2 origin) {
  auto location = [&](const char* name, int index) {
    char element[48];
    std::snprintf(element, sizeof element, "%s[%d]", name, index);
    return gl.GetUniformLocation(p, element);
  };
  auto angle = [](double a) { return float(wrapPeriodic(a, kTwoPi)); };
  for (int j = 0; j < g.terms(); ++j) {
    const int t = 8 * slot + j;
    const glm::vec3 term(g.frequencyX(j), g.frequencyY(j), g.componentAmplitude(j));
    gl.ProgramUniform3fv(p, location("u_term", t), 1, &term.x);
    gl.ProgramUniform1i(p, location("u_components", t), g.components(j));
    for (int c = 0; c < g.components(j); ++c) {
      const int k = GardnerTextureParams::kComponents * t + c;
      const glm::dvec2 a = g.axisX(j, c), b = g.axisY(j, c);
      const glm::dvec2 q1(a.x * origin.x + a.y * origin.y, a.x * origin.y - a.y * origin.x);
      const glm::dvec2 q2(b.x * origin.x + b.y * origin.y, b.x * origin.y - b.y * origin.x);
      const glm::vec4 phases(angle(g.frequencyX(j) * q1.x + g.phaseX(j, c)),
                             angle(g.frequencyY(j) * q2.y + g.phaseY(j, c)),
                             angle(0.5 * g.frequencyX(j) * q2.x),
                             angle(0.5 * g.frequencyY(j) * q1.y));
      const glm::vec4 axes(a.x, a.y, b.x, b.y);
      gl.ProgramUniform4fv(p, location("u_phases", k), 1, &phases.x);
      gl.ProgramUniform4fv(p, location("u_axes", k), 1, &axes.x);
    }
  }
  gl.ProgramUniform1f(p, location("u_t0", slot), float(g.params().t0));
  gl.ProgramUniform1f(p, location("u_k", slot), float(g.normalisation()));
}

LayerClipmaps::LayerClipmaps(const GlApi& gl) : gl_(gl) {}
LayerClipmaps::~LayerClipmaps() = default;

int LayerClipmaps::sizeFor(int height) {
  int size = 256;
  while (size < 1024 && size < 2 * height) size *= 2;
  return size;
}

LayerClipmaps::Clipmap& LayerClipmaps::choose(const std::string& key, const GardnerTexture& g,
                                              glm::dvec2 eye, int size) {
  const int rings = g.terms();
  // Ring 0's texel: the footprint at which the term filter keeps every term, 2^-(n+2) periods
  // (term j, 1-based, is whole while 2^j footprint <= 1/4; MODEL.md section 2).
  const glm::dvec2 texel = std::ldexp(1.0, -(rings + 2)) * g.period();
  std::list<Clipmap>& list = clipmaps_[key];
  for (Clipmap& c : list)  // one near enough to be moved by strips
    if (c.placed && c.size == size && c.rings == rings && c.texel_m == texel) {
      const glm::dvec2 a = eye / texel;
      if (std::abs(a.x - double(c.centre[0].x)) < size / 4 &&
          std::abs(a.y - double(c.centre[0].y)) < size / 4)
        return c;
    }
  Clipmap* pick = nullptr;
  if (list.size() < kPerTexture) {
    pick = &list.emplace_back();
  } else {  // the least recently read
    pick = &*std::min_element(list.begin(), list.end(), [](const Clipmap& a, const Clipmap& b) {
      return a.last_frame < b.last_frame;
    });
  }
  Clipmap& c = *pick;
  if (c.size != size || c.rings != rings) c.texture = GlObject();  // made at the first fill
  c.size = size;
  c.rings = rings;
  c.texel_m = texel;
  c.centre.assign(std::size_t(rings), glm::i64vec2(0));
  c.rows.assign(std::size_t(rings), 0);
  c.placed = false;
  return c;
}

void LayerClipmaps::bake(Clipmap& c, const GardnerTexture& g, int ring, glm::ivec4 rect) {
  if (rect.z <= rect.x || rect.w <= rect.y) return;
  const GLuint p = program_.get();
  const glm::dvec2 texel = std::ldexp(1.0, ring) * c.texel_m;
  const glm::i64vec2 first = c.centre[std::size_t(ring)] - std::int64_t(c.size / 2);
  setLayerGardnerUniforms(gl_, p, 0, g, glm::dvec2(first) * texel);
  gl_.ProgramUniform2i(p, gl_.GetUniformLocation(p, "u_bake_first"), int(floorMod(first.x, c.size)),
                       int(floorMod(first.y, c.size)));
  gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, "u_bake_size"), c.size);
  const glm::vec2 texel_f(texel);
  gl_.ProgramUniform2fv(p, gl_.GetUniformLocation(p, "u_bake_texel"), 1, &texel_f.x);
  gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_bake_terms"), float(c.rings - ring));
  gl_.NamedFramebufferTextureLayer(framebuffer_.get(), GL_COLOR_ATTACHMENT0, c.texture.get(), 0,
                                   ring);
  auto ndc = [&](int v) { return 2.0f * float(v) / float(c.size) - 1.0f; };
  const glm::vec2 polygon[4] = {{ndc(rect.x), ndc(rect.y)},
                                {ndc(rect.z), ndc(rect.y)},
                                {ndc(rect.z), ndc(rect.w)},
                                {ndc(rect.x), ndc(rect.w)}};
  gl_.ProgramUniform2fv(p, gl_.GetUniformLocation(p, "u_polygon"), 4, &polygon[0].x);
  gl_.DrawArrays(GL_TRIANGLE_FAN, 0, 4);
  texels_baked_ += std::int64_t(rect.z - rect.x) * (rect.w - rect.y);
}

void LayerClipmaps::bindForBaking(Clipmap& c, int size) {
  if (!program_) {
    std::string error;
    program_ = createProgram(gl_, polygonVertexSource(), clipmapBakeSource(), error);
    NEPHELE_CHECK(program_, "clipmap bake program: " << error);
    framebuffer_ = createFramebuffer(gl_);
  }
  if (!c.texture) {
    c.texture = createTexture(gl_, GL_TEXTURE_2D_ARRAY);
    gl_.TextureStorage3D(c.texture.get(), 1, GL_R16, size, size, c.rings);
    gl_.TextureParameteri(c.texture.get(), GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    gl_.TextureParameteri(c.texture.get(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl_.TextureParameteri(c.texture.get(), GL_TEXTURE_WRAP_S, GL_REPEAT);
    gl_.TextureParameteri(c.texture.get(), GL_TEXTURE_WRAP_T, GL_REPEAT);
  }
  gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffer_.get());
  gl_.Viewport(0, 0, size, size);
  gl_.Disable(GL_BLEND);
  gl_.UseProgram(program_.get());
}

const ClipmapView& LayerClipmaps::prepare(const std::string& key, const GardnerTexture& g,
                                          glm::dvec2 eye, int size, std::int64_t budget, bool wait,
                                          FrameStats& stats) {
  Clipmap& c = choose(key, g, eye, size);
  c.last_frame = frame_;
  const bool placed = c.placed;
  c.placed = true;
  const std::int64_t before = texels_baked_;
  const std::int64_t n = size;
  c.view.offset.assign(std::size_t(c.rings), glm::vec2(0.0f));
  bool bound = false;
  auto bind = [&] {
    if (bound) return;
    bindForBaking(c, size);
    bound = true;
  };
  for (int ring = 0; ring < c.rings; ++ring) {
    const glm::dvec2 a = eye / (std::ldexp(1.0, ring) * c.texel_m);
    const glm::i64vec2 want(std::int64_t(std::floor(a.x)), std::int64_t(std::floor(a.y)));
    // The camera's lattice coordinate modulo N (the storage the sky pass reads through).
    c.view.offset[std::size_t(ring)] = glm::vec2(a - glm::dvec2(n) * glm::floor(a / double(n)));
    glm::i64vec2& centre = c.centre[std::size_t(ring)];
    const glm::i64vec2 moved = want - centre;
    const glm::i64vec2 old = centre;
    centre = want;
    int& rows = c.rows[std::size_t(ring)];
    if (!placed || rows == 0 || moved == glm::i64vec2(0)) continue;
    bind();
    if (std::abs(moved.x) >= n || std::abs(moved.y) >= n) {
      rows = 0;  // nothing left in place: filled again below
      continue;
    }
    // The columns (then rows) the new window holds and the old did not, in storage
    // coordinates, split where they wrap.
    auto strip = [&](std::int64_t from, std::int64_t to, bool columns) {
      const int a0 = int(floorMod(from, n)), count = int(to - from);
      const int a1 = std::min(a0 + count, size), wrapped = a0 + count - a1;
      for (const auto& [lo, hi] : {std::pair{a0, a1}, std::pair{0, wrapped}})
        bake(c, g, ring, columns ? glm::ivec4(lo, 0, hi, size) : glm::ivec4(0, lo, size, hi));
    };
    const std::int64_t half = n / 2;
    if (moved.x > 0) strip(old.x + half, want.x + half, true);
    if (moved.x < 0) strip(want.x - half, old.x - half, true);
    if (moved.y > 0) strip(old.y + half, want.y + half, false);
    if (moved.y < 0) strip(want.y - half, old.y - half, false);
  }
  // Then rows not yet filled, coarsest ring first (it serves the most of a view), within the
  // budget; nothing in the frame that first asks when `wait` is set.
  if (placed || !wait)
    for (int ring = c.rings - 1; ring >= 0 && budget > 0; --ring) {
      int& rows = c.rows[std::size_t(ring)];
      if (rows == size) continue;
      bind();
      const std::int64_t whole = ring == c.rings - 1 ? size : 1;  // the coarsest ring at once
      const int more = int(std::clamp<std::int64_t>(budget / size, whole, size - rows));
      bake(c, g, ring, {0, rows, size, rows + more});
      rows += more;
      budget -= std::int64_t(more) * size;
    }
  c.view.finest = c.rings;
  while (c.view.finest > 0 && c.rows[std::size_t(c.view.finest - 1)] == size) --c.view.finest;
  stats.layer_texels_baked += int(texels_baked_ - before);
  c.view.texture = c.texture.get();
  c.view.size = size;
  c.view.rings = c.rings;
  c.view.texel_m = c.texel_m;
  c.view.constant = g.normalisation() * std::max(g.params().t0, 0.0) * std::max(g.params().t0, 0.0);
  return c.view;
}

void LayerClipmaps::endFrame() {
  for (;;) {
    std::size_t count = 0;
    std::list<Clipmap>* oldest_list = nullptr;
    std::list<Clipmap>::iterator oldest;
    for (auto& [key, list] : clipmaps_)
      for (auto it = list.begin(); it != list.end(); ++it, ++count)
        if (!oldest_list || it->last_frame < oldest->last_frame) oldest_list = &list, oldest = it;
    if (count <= kKept || oldest->last_frame == frame_) break;
    oldest_list->erase(oldest);
  }
  std::erase_if(clipmaps_, [](const auto& entry) { return entry.second.empty(); });
}

}  // namespace nephele
