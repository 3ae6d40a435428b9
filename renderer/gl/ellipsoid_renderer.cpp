#include "renderer/gl/ellipsoid_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <future>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <thread>

#include "image/image_encoding.h"
#include "renderer/gl/sky_shaders.h"
#include "renderer/gl/view_uniforms.h"
#include "world/automaton/cloud_density.h"
#include "world/check.h"
#include "world/formations/ellipsoid.h"
#include "world/formations/heap_light.h"

namespace nephele {
namespace {

// A continuous view's samples stand rate pixels apart (heap_refresh = rate^2).
int refreshRate(int refresh) {
  return refresh >= 16 ? 4 : refresh >= 4 ? 2 : 1;
}

// How far the scene's heaps have drifted with the wind (its first field's drift; explicit
// clouds' drift is not known to a frame and counts as none): what a continuous view's history
// moves by between frames besides the camera.
glm::dvec2 heapDrift(const Scene& scene) {
  return scene.fields.empty() ? glm::dvec2(0.0) : scene.fields.front().drift_m;
}

// Frame k's sample offset within the rate x rate block: the ordered-dither (Bayer) order, so
// that the offsets of consecutive frames lie far apart and rate^2 frames visit every pixel.
glm::ivec2 sampleOffset(std::uint64_t k, int rate) {
  static constexpr int kBayer2[4][2] = {{0, 0}, {1, 1}, {1, 0}, {0, 1}};
  static constexpr int kBayer4[16][2] = {{0, 0}, {2, 2}, {2, 0}, {0, 2}, {1, 1}, {3, 3},
                                         {3, 1}, {1, 3}, {1, 0}, {3, 2}, {3, 0}, {1, 2},
                                         {0, 1}, {2, 3}, {2, 1}, {0, 3}};
  if (rate == 2) return {kBayer2[k % 4][0], kBayer2[k % 4][1]};
  if (rate == 4) return {kBayer4[k % 16][0], kBayer4[k % 16][1]};
  return glm::ivec2(0);
}

constexpr int kAtlasSize = 2048;
constexpr int kMaxTileSize = 1024;
constexpr int kSpotlightSize = 64;
constexpr std::int64_t kMaxListed = std::int64_t(1) << 24;  // per-pixel bin entries per batch
constexpr double kTileNear = 1.0e-3;                        // metres: the tile frusta's near plane

int nextPowerOfTwo(double x) {
  int p = 1;
  while (p < x && p < (1 << 20)) p *= 2;
  return p;
}

glm::vec4 row(glm::dvec3 v, double w = 0.0) {
  return glm::vec4(glm::dvec4(v, w));
}

// The ellipsoid's screen rectangle in NDC (x0, y0, x1, y1), widened by a pixel; false when
// off screen.
bool screenRectangle(const Ellipsoid& e, const Camera& camera, const ViewBasis& basis,
                     glm::dvec4& rect) {
  rect = screenBounds(e, camera.position, basis);
  const double mx = 2.0 / camera.width, my = 2.0 / camera.height;
  rect = {std::max(rect.x - mx, -1.0), std::max(rect.y - my, -1.0), std::min(rect.z + mx, 1.0),
          std::min(rect.w + my, 1.0)};
  return rect.x < rect.z && rect.y < rect.w;
}

// The tile's off-axis frustum: clip coordinates of camera-relative points for the part
// `rect` of the camera's image, with the near plane at kTileNear.
glm::mat4 tileProjection(const ViewBasis& basis, glm::dvec4 rect) {
  const glm::dvec3 x = basis.right / (basis.tan_half_vfov * basis.aspect);
  const glm::dvec3 y = basis.up / basis.tan_half_vfov;
  const glm::dvec3 w = basis.forward;
  const glm::dvec3 tile_x = (2.0 * x - (rect.x + rect.z) * w) / (rect.z - rect.x);
  const glm::dvec3 tile_y = (2.0 * y - (rect.y + rect.w) * w) / (rect.w - rect.y);
  glm::dmat4 m(0.0);  // m[column][row]
  for (int c = 0; c < 3; ++c) {
    m[c][0] = tile_x[c];
    m[c][1] = tile_y[c];
    m[c][2] = w[c];
    m[c][3] = w[c];
  }
  m[3][2] = -2.0 * kTileNear;  // z = w - 2 near: clipped where w < near
  return glm::mat4(m);
}

std::string textureKey(const SolidTextureSpec& spec, const RenderSettings& settings) {
  std::ostringstream key;
  key.precision(17);
  const GardnerTextureParams& g = spec.gardner;
  key << int(spec.source) << '/' << spec.seed << '/';
  if (spec.source == SolidTextureSource::kGardner)
    key << g.terms << '/' << g.fx1 << '/' << g.fy1 << '/' << g.t0 << '/' << g.seeded_phases << '/'
        << g.rotation_deg << '/' << g.amplitude_ratio << '/' << int(settings.texture_evaluation);
  else
    key << spec.perlin_period_m << '/' << spec.perlin_size_log2 << '/' << spec.perlin_cells << '/'
        << spec.perlin_octaves << '/' << spec.perlin_persistence;
  return key.str();
}

// The spec whose table a baked texture of `spec` is: the same texture at unit scale. Every
// Gardner term runs at 2^i cycles per period whatever the base frequencies (MODEL.md section
// 2), and a Perlin table is tiled over its period, so the table does not depend on the scale;
// baking it at a fixed one makes it a function of its key alone, not of which cloud asked first.
SolidTextureSpec bakedTableSpec(SolidTextureSpec spec) {
  spec.gardner.fx1 = spec.gardner.fy1 = 1.0;
  spec.perlin_period_m = 1.0;
  return spec;
}

// Baked solid Gardner (MODEL.md section 2, "baked solid texture"): the sums SX - T0 and
// SY - T0 of the lower floor(n / 2) terms in one table over the period, of the upper terms in
// a second over the period of its lowest term, 2^m times shorter (m the lower count), each at
// 16 texels per cycle of its highest term (8 for a table of four terms, held to 128 a side).
// A table of t texels per cycle holds all its c terms on its first log2(t) - 1 levels and one
// fewer on each level above: GL's trilinear LOD then fades each term over the octave below its
// limit (the fade of section 2), and the upper table's terms are gone before the lower
// table's begin to fade. The shader adds the two tables' sums to T0 and takes
// T = k max(SX, 0) max(SY, 0). Five terms: 64^3 and 128^3 RG16F; six or seven: 128^3 twice,
// 18 MiB with their levels.
struct BakedSolidLayout {
  int coarse_terms, fine_terms;
  double fine_periods;  // periods of the fine table per period of the texture
};
BakedSolidLayout bakedSolidLayout(const GardnerTexture& gardner) {
  const int n = gardner.terms(), coarse = n / 2;
  return {coarse, n - coarse, std::exp2(coarse)};
}

// One table's levels as half floats, the texture's own format (llvmpipe converts floats a
// texel at a time, longer than the bake itself). CPU only: any thread.
// Each level is converted row by row as it is summed, into storage that is written once and
// never cleared: a float table between, and zeroed storage, cost more than the sums in
// first-touch page faults (a fresh process bakes each table into memory it has not used).
struct BakedLevels {
  int base = 0;
  std::vector<std::unique_ptr<std::uint16_t[]>> levels;
};
BakedLevels bakeSumLevels(const GardnerTexture& gardner, int first, int count) {
  BakedLevels out;
  out.base = std::min(16 << count, 128);
  const int levels = int(std::log2(out.base)) + 1, full = int(std::log2(out.base >> count)) - 1;
  for (int level = 0; level < levels; ++level) {
    const std::size_t n = std::size_t(out.base >> level);
    std::uint16_t* halves =
        out.levels.emplace_back(std::make_unique_for_overwrite<std::uint16_t[]>(2 * n * n * n))
            .get();
    bakeGardnerSums(gardner, int(n), first, count - std::max(0, level + 1 - full),
                    [&](std::size_t z, std::size_t y, const float* sx, const float* sy) {
                      std::uint16_t* texel = halves + 2 * (z * n + y) * n;
                      for (std::size_t x = 0; x < n; ++x) {
                        texel[2 * x] = halfFloatBits(sx[x]);
                        texel[2 * x + 1] = halfFloatBits(sy[x]);
                      }
                    });
  }
  return out;
}

void uploadBakedSums(const GlApi& gl, GLuint texture, const BakedLevels& baked) {
  const int levels = int(baked.levels.size());
  gl.TextureStorage3D(texture, levels, GL_RG16F, baked.base, baked.base, baked.base);
  for (int level = 0; level < levels; ++level) {
    const int size = baked.base >> level;
    gl.TextureSubImage3D(texture, level, 0, 0, 0, size, size, size, GL_RG, GL_HALF_FLOAT,
                         baked.levels[std::size_t(level)].get());
  }
  gl.TextureParameteri(texture, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
}

void uploadVolume(const GlApi& gl, GLuint texture, const VolumeTable& table) {
  const int levels = int(std::log2(table.size)) + 1;
  gl.TextureStorage3D(texture, levels, GL_R16, table.size, table.size, table.size);
  gl.TextureSubImage3D(texture, 0, 0, 0, 0, table.size, table.size, table.size, GL_RED, GL_FLOAT,
                       table.values.data());
  gl.GenerateTextureMipmap(texture);
  gl.TextureParameteri(texture, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
}

// A colour texture of `format` and `size`, sampled bilinearly and clamped at its edges, and a
// framebuffer that draws into it (the atlas, an impostor, the per-pixel pass's samples).
void createColourTarget(const GlApi& gl, GLenum format, glm::ivec2 size, const char* what,
                        GlObject& texture, GlObject& framebuffer) {
  texture = createTexture(gl, GL_TEXTURE_2D);
  gl.TextureStorage2D(texture.get(), 1, format, size.x, size.y);
  for (GLenum filter : {GL_TEXTURE_MIN_FILTER, GL_TEXTURE_MAG_FILTER})
    gl.TextureParameteri(texture.get(), filter, GL_LINEAR);
  for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T})
    gl.TextureParameteri(texture.get(), wrap, GL_CLAMP_TO_EDGE);
  framebuffer = createFramebuffer(gl);
  gl.NamedFramebufferTexture(framebuffer.get(), GL_COLOR_ATTACHMENT0, texture.get(), 0);
  const GLenum status = gl.CheckNamedFramebufferStatus(framebuffer.get(), GL_FRAMEBUFFER);
  NEPHELE_CHECK(status == GL_FRAMEBUFFER_COMPLETE, what << " status 0x" << std::hex << status);
}

// Slices for a silhouette within half a pixel of the true one: a polygon of n sides around
// a circle of r pixels strays by r (1 - cos(pi / n)).
int adaptiveSlices(double radius_px) {
  if (radius_px <= 1.0) return 8;
  const double n = std::numbers::pi / std::acos(std::max(1.0 - 0.5 / radius_px, -1.0));
  return std::clamp(4 * int(std::ceil(n / 4.0)), 8, 128);
}

}  // namespace

bool makeEllipsoidRecord(const Ellipsoid& e, const Camera& camera, bool spotlight,
                         EllipsoidRecord& out, double& centre_distance) {
  const EllipsoidView view(e, camera.position);
  if (view.eyeInside()) return false;  // MODEL.md section 4: the in-cloud veil shows it
  const double fade = surfaceFade(view.eyeRadius());
  if (fade <= 0.0) return false;
  const ViewBasis basis = viewBasis(camera);
  glm::dvec4 rect;
  if (!screenRectangle(e, camera, basis, rect)) return false;

  const glm::dmat3& w = view.toUnitSphere();
  for (int i = 0; i < 3; ++i) out.v[i] = row(glm::dvec3(w[0][i], w[1][i], w[2][i]));
  const double c = glm::dot(view.eyeInUnitSphere(), view.eyeInUnitSphere()) - 1.0;
  out.v[3] = row(view.eyeInUnitSphere(), c);
  out.v[4] = row(view.limbAxis(), fade);
  const glm::dmat3& p = view.limbForm();
  for (int i = 0; i < 3; ++i) out.v[5 + i] = row(glm::dvec3(p[0][i], p[1][i], p[2][i]));
  // Spotlight coordinates: P = L^T L from P's two non-negative eigenpairs.
  if (spotlight) {
    const SymmetricEigen eigen = symmetricEigen(p);
    for (int i = 0; i < 2; ++i)
      out.v[8 + i] = row(std::sqrt(std::max(eigen.values[2 - i], 0.0)) * eigen.vectors[2 - i]);
  } else {
    out.v[8] = out.v[9] = glm::vec4(0.0f);
  }
  out.v[10] = glm::vec4(rect);
  const glm::dmat3 body = unitSphereToWorld(e);
  for (int i = 0; i < 3; ++i) out.v[11 + i] = row(body[i]);
  out.v[14] = row(e.centre - camera.position);
  out.v[15] = glm::vec4(0.0f);
  centre_distance = glm::length(e.centre - camera.position);
  const double near_bound = centre_distance - std::max({e.radii.x, e.radii.y, e.radii.z});
  out.v[16] = glm::vec4(0.0f, 0.0f, float(near_bound), 0.0f);
  out.v[17] = glm::vec4(0.0f);  // no heap envelope: eq. 8 unchanged (MODEL.md section 14)
  out.v[18] = glm::vec4(1.0f, 1.0f, 1.0f, 0.0f);  // w: no shadow from other clouds
  return true;
}

EllipsoidRenderer::EllipsoidRenderer(const GlApi& gl)
    : gl_(gl), vertex_array_(createVertexArray(gl)) {
  gl_.GetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels_);
}

EllipsoidRenderer::~EllipsoidRenderer() {
  dropPartFence();
}

void EllipsoidRenderer::paceQueued() {
  const GLsync queued = gl_.FenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
  if (part_fence_)
    while (gl_.ClientWaitSync(part_fence_, GL_SYNC_FLUSH_COMMANDS_BIT,
                              std::numeric_limits<GLuint64>::max()) == GL_TIMEOUT_EXPIRED) {
    }
  dropPartFence();
  part_fence_ = queued;
  queued_work_ = 0;
}

void EllipsoidRenderer::dropPartFence() {
  if (part_fence_) gl_.DeleteSync(part_fence_);
  part_fence_ = nullptr;
}

void EllipsoidRenderer::beginFrame(FrameStats& stats, GpuPassTimer& timer,
                                   const std::string& continuous_view) {
  stats_ = &stats;
  timer_ = &timer;
  continuous_view_ = continuous_view;
  next_history_ = 0;
  cancelled_ = false;
  for (auto& [key, cached] : textures_) cached.used = false;
  ++frame_;
  next_buffer_ = 0;
  queued_work_ = 0;
}

void EllipsoidRenderer::bindFrameTexture(int unit, GLenum format, const void* data,
                                         std::size_t bytes) {
  StageClock clock(stats_->times.cpu(CpuStage::kUploads));
  // A fresh buffer for every upload in a frame: llvmpipe may still be drawing from the last
  // one (it defers rasterisation), and rewriting it in place would change earlier draws.
  if (next_buffer_ == buffer_pool_.size())
    buffer_pool_.push_back({createBuffer(gl_), createTexture(gl_, GL_TEXTURE_BUFFER)});
  const FrameTexture& entry = buffer_pool_[next_buffer_++];
  const GLuint buffer = entry.buffer.get();
  if (bytes >= 16) {
    gl_.NamedBufferData(buffer, GLsizeiptr(bytes), data, GL_STREAM_DRAW);
  } else {  // never bind an empty store
    const std::uint8_t zeros[16] = {};
    gl_.NamedBufferData(buffer, 16, zeros, GL_STREAM_DRAW);
    if (bytes > 0) gl_.NamedBufferSubData(buffer, 0, GLsizeiptr(bytes), data);
  }
  gl_.TextureBuffer(entry.texture.get(), format, buffer);
  gl_.BindTextureUnit(GLuint(unit), entry.texture.get());
}

void EllipsoidRenderer::endFrame() {
  dropPartFence();  // the readback waits for the whole frame
  std::erase_if(textures_, [](const auto& entry) { return !entry.second.used; });
  keepMostRecent(tables_, kKeptTables, frame_);
  std::erase_if(impostors_, [](const auto& entry) { return !entry.second.used; });
  for (auto& [index, impostor] : impostors_) impostor.used = false;
  // A view's histories go once it has drawn none for kKeptHistoryFrames frames, and the
  // batches past those this frame drew with them.
  std::erase_if(histories_, [&](auto& entry) {
    return std::none_of(entry.second.begin(), entry.second.end(),
                        [&](const HeapHistory& h) { return h.used + kKeptHistoryFrames > frame_; });
  });
  if (auto found = histories_.find(continuous_view_); found != histories_.end())
    found->second.resize(std::min(found->second.size(), next_history_));
}

EllipsoidRenderer::HeapHistory& EllipsoidRenderer::heapHistory(const Scene& scene,
                                                               const std::string& key,
                                                               glm::ivec2 size) {
  std::vector<HeapHistory>& view = histories_[continuous_view_];
  if (view.size() <= next_history_) view.resize(next_history_ + 1);
  HeapHistory& h = view[next_history_++];
  if (h.size != size) {
    h = HeapHistory{};
    h.size = size;
    for (int k = 0; k < 2; ++k)
      createColourTarget(gl_, GL_RGBA16F, size, "heap history", h.colour[k], h.framebuffer[k]);
  }
  // A cut: other batches, a camera moved or turned further than a stream of frames moves it,
  // another lens, or time gone back or far on. The frame after it is the exact one.
  const Camera& now = scene.camera;
  const Camera& then = h.camera;
  const ViewBasis a = viewBasis(now), b = viewBasis(then);
  const double dt = scene.time_s - h.time_s;
  h.valid =
      h.valid && h.key == key && h.used + kKeptHistoryFrames > frame_ &&
      now.vfov_deg == then.vfov_deg && glm::length(now.position - then.position) <= kCutStep_m &&
      glm::dot(a.forward, b.forward) >= std::cos(glm::radians(kCutTurn_deg)) &&
      glm::dot(a.up, b.up) >= std::cos(glm::radians(kCutTurn_deg)) && dt >= 0.0 && dt <= kCutTime_s;
  h.key = key;
  h.used = frame_;
  return h;
}

GLuint EllipsoidRenderer::program(const EllipsoidPassLayout& layout) {
  const std::string key = layout.key();
  auto found = programs_.find(key);
  if (found != programs_.end()) return found->second.get();
  std::string error;
  GlObject compiled =
      createProgram(gl_, ellipsoidVertexSource(layout), ellipsoidFragmentSource(layout), error);
  NEPHELE_CHECK(compiled, key << ": " << error);
  return programs_.emplace(key, std::move(compiled)).first->second.get();
}

EllipsoidRenderer::CachedTexture& EllipsoidRenderer::cachedTexture(const SolidTextureSpec& spec,
                                                                   const RenderSettings& settings) {
  auto [entry, inserted] = textures_.try_emplace(textureKey(spec, settings));
  if (inserted) {
    entry->second.source = std::make_unique<SolidTexture>(spec);
    entry->second.table_key = textureKey(bakedTableSpec(spec), RenderSettings{});
  }
  entry->second.used = true;
  return entry->second;
}

void EllipsoidRenderer::bindTables(CachedTexture& cached) {
  BakedTable& table = tables_[cached.table_key];
  table.last_frame = frame_;
  if (!table.texture) {
    StageClock clock(stats_->times.cpu(CpuStage::kUploads));
    table.texture = createTexture(gl_, GL_TEXTURE_3D);
    const SolidTexture unit(bakedTableSpec(cached.source->spec()));
    if (const GardnerTexture* gardner = unit.gardner()) {
      table.fine = createTexture(gl_, GL_TEXTURE_3D);
      const BakedSolidLayout layout = bakedSolidLayout(*gardner);
      // The two tables baked side by side: GL waits for them either way.
      std::future<BakedLevels> fine = std::async(std::launch::async, [&] {
        return bakeSumLevels(*gardner, layout.coarse_terms, layout.fine_terms);
      });
      uploadBakedSums(gl_, table.texture.get(), bakeSumLevels(*gardner, 0, layout.coarse_terms));
      uploadBakedSums(gl_, table.fine.get(), fine.get());
    } else {
      uploadVolume(gl_, table.texture.get(), *unit.volume());
    }
    for (const GlObject* t : {&table.texture, &table.fine}) {
      if (!*t) continue;
      for (GLenum wrap : {GL_TEXTURE_WRAP_S, GL_TEXTURE_WRAP_T, GL_TEXTURE_WRAP_R})
        gl_.TextureParameteri(t->get(), wrap, GL_REPEAT);
      gl_.TextureParameteri(t->get(), GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    }
  }
  gl_.BindTextureUnit(kVolumeTextureUnit, table.texture.get());
  if (table.fine) gl_.BindTextureUnit(kFineVolumeTextureUnit, table.fine.get());
}

GLuint EllipsoidRenderer::spotlightTexture() {
  if (spotlight_) return spotlight_.get();
  // Elinas' radial spotlight: 1 - rho^2 inside the unit disc, 0 outside.
  std::vector<float> values(kSpotlightSize * kSpotlightSize);
  for (int y = 0; y < kSpotlightSize; ++y)
    for (int x = 0; x < kSpotlightSize; ++x) {
      const double u = 2.0 * (x + 0.5) / kSpotlightSize - 1.0;
      const double v = 2.0 * (y + 0.5) / kSpotlightSize - 1.0;
      values[y * kSpotlightSize + x] = float(std::max(0.0, 1.0 - u * u - v * v));
    }
  spotlight_ = createTexture2D(gl_, GL_R16, kSpotlightSize, kSpotlightSize);
  const GLuint t = spotlight_.get();
  gl_.TextureSubImage2D(t, 0, 0, 0, kSpotlightSize, kSpotlightSize, GL_RED, GL_FLOAT,
                        values.data());
  return t;
}

const IndexedMesh& EllipsoidRenderer::sphereMesh(int slices) {
  auto found = meshes_.find(slices);
  if (found != meshes_.end()) return found->second;
  std::vector<glm::vec3> vertices;
  std::vector<GLuint> indices;
  unitSphere(slices, vertices, indices);
  return meshes_.emplace(slices, uploadMesh(gl_, vertices, indices)).first->second;
}

void EllipsoidRenderer::setCloudUniforms(GLuint p, const Scene& scene, const EllipsoidCloud& cloud,
                                         const CachedTexture& cached, SolidTextureKind kind,
                                         const AltitudeBand& band) {
  setViewUniforms(gl_, p, scene.camera, scene, band);
  setUniform3(gl_, p, "u_cloud_colour", cloud.colour * scene.sun.colour);
  const ShadingParams& sh = cloud.shading;
  const glm::vec4 shading(sh.ambient, sh.texture_fraction, sh.specular, sh.shininess);
  gl_.ProgramUniform4fv(p, gl_.GetUniformLocation(p, "u_shading"), 1, &shading.x);
  setUniform3(gl_, p, "u_thresholds",
              {cloud.threshold_centre, cloud.threshold_limb, cloud.transition});
  setUniform3(gl_, p, "u_to_sun", sunDirection(scene.sun));
  const bool heap_lit = cloud.light_extinction > 0.0;
  const glm::vec4 scatter(heap_lit ? 1.0 : 0.0, kDiffuseAsymmetry, heap_lit ? kSkinWrap : 0.0,
                          heap_lit ? kHeapNormalBend : 0.0);
  gl_.ProgramUniform4fv(p, gl_.GetUniformLocation(p, "u_scatter"), 1, &scatter.x);
  // The precision rule of MODEL.md section 2: the texture's local origin is the eye, reduced modulo
  // the period in double; shaders see camera-relative offsets only.
  const SolidTexture& texture = *cached.source;
  const glm::dvec3 origin_uvw = texture.periodicCoordinate(scene.camera.position - cloud.drift_m);
  setUniform3(gl_, p, "u_tex_origin", origin_uvw);
  setUniform3(gl_, p, "u_inv_period", 1.0 / texture.period());
  if (kind == SolidTextureKind::kTable) return;
  const GardnerTexture& g = *texture.gardner();
  gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_t0"), float(g.params().t0));
  gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_k"), float(g.normalisation()));
  if (kind == SolidTextureKind::kBakedGardner) {
    const double periods = bakedSolidLayout(g).fine_periods;
    const glm::dvec3 fine_origin = origin_uvw * periods;
    setUniform3(gl_, p, "u_fine_origin", fine_origin - glm::floor(fine_origin));
    gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_fine_periods"), float(periods));
    return;
  }
  const glm::dvec3 eye = origin_uvw * texture.period();
  auto set = [&](const char* name, int j, double v) {
    char element[32];
    std::snprintf(element, sizeof element, "%s[%d]", name, j);
    gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, element), float(v));
  };
  for (int j = 0; j < g.terms(); ++j) {
    set("u_fx", j, g.frequencyX(j));
    set("u_fy", j, g.frequencyY(j));
    set("u_amplitude", j, g.amplitude(j));
    set("u_phase_x", j, wrapPeriodic(g.frequencyX(j) * eye.x + g.phaseX(j), kTwoPi));
    set("u_phase_y", j, wrapPeriodic(g.frequencyY(j) * eye.y + g.phaseY(j), kTwoPi));
    set("u_half_x", j, wrapPeriodic(0.5 * g.frequencyX(j) * eye.x, kTwoPi));
    set("u_half_y", j, wrapPeriodic(0.5 * g.frequencyY(j) * eye.y, kTwoPi));
    set("u_half_z", j, wrapPeriodic(0.5 * g.frequencyX(j) * eye.z, kTwoPi));
  }
  gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_terms"), float(g.terms()));
}

void EllipsoidRenderer::uploadRecords(const std::vector<EllipsoidRecord>& records) {
  bindFrameTexture(kRecordTextureUnit, GL_RGBA32F, records.data(),
                   records.size() * sizeof(EllipsoidRecord));
}

namespace {

// What a cloud's pass takes besides its ellipsoids and the scene: clouds with the same key
// can share one pass.
std::string cloudLookKey(const EllipsoidCloud& cloud, const RenderSettings& settings) {
  std::ostringstream key;
  key.precision(17);
  key << cloud.colour.x << ',' << cloud.colour.y << ',' << cloud.colour.z << '/'
      << cloud.threshold_centre << '/' << cloud.threshold_limb << '/' << cloud.transition << '/'
      << cloud.shading.ambient << '/' << cloud.shading.texture_fraction << '/'
      << cloud.shading.specular << '/' << cloud.shading.shininess << '/' << cloud.light_extinction
      << '/' << cloud.drift_m.x << ',' << cloud.drift_m.y << ',' << cloud.drift_m.z << '/'
      << textureKey(cloud.texture, settings);
  return key.str();
}

// Everything an impostor's picture depends on besides the eye.
std::string impostorKey(const Scene& scene, const EllipsoidCloud& cloud,
                        const RenderSettings& settings) {
  std::ostringstream key;
  key.precision(17);
  key << cloudLookKey(cloud, settings) << '/' << int(settings.ellipsoid_passes)
      << int(settings.ellipsoid_order) << int(settings.limb) << int(settings.term_filter) << '/'
      << scene.sun.azimuth_deg << '/' << scene.sun.elevation_deg << '/' << scene.sun.colour.x
      << scene.sun.colour.y << scene.sun.colour.z << '/' << scene.fog.has_value();
  if (scene.fog)
    key << scene.fog->top_m << '/' << scene.fog->visibility_m << '/' << scene.fog->colour.x << ','
        << scene.fog->colour.y << ',' << scene.fog->colour.z;
  key << '/' << scene.haze.has_value();
  if (scene.haze)
    key << scene.haze->visibility_m << '/' << scene.haze->scale_height_m << '/'
        << scene.sky.horizon.x << ',' << scene.sky.horizon.y << ',' << scene.sky.horizon.z;
  for (const Ellipsoid& e : cloud.ellipsoids)
    key << '|' << e.radii.x << ',' << e.radii.y << ',' << e.radii.z << ',' << e.centre.x << ','
        << e.centre.y << ',' << e.centre.z << ',' << e.orientation.heading_deg << ','
        << e.orientation.pitch_deg << ',' << e.orientation.roll_deg;
  return key.str();
}

}  // namespace

void EllipsoidRenderer::drawClouds(const ViewPlan& view, const std::vector<std::size_t>& indices,
                                   const RenderSettings& settings, const PassTarget& target,
                                   bool targets_drawn, const AltitudeBand& band) {
  // Batches in the order of their farthest cloud; impostors first, being far.
  std::vector<std::pair<std::string, std::vector<std::size_t>>> batches;
  for (std::size_t index : indices) {
    if (settings.impostor_tolerance_px > 0.0 &&
        drawImpostor(view, index, settings, target, targets_drawn, band))
      continue;
    const std::string key = cloudLookKey(view.cloud(index), settings);
    auto batch = std::find_if(batches.begin(), batches.end(),
                              [&](const auto& entry) { return entry.first == key; });
    if (batch == batches.end()) batch = batches.insert(batches.end(), {key, {}});
    batch->second.push_back(index);
  }
  if (batches.empty()) return;
  // A continuous view's batches share one history, keyed by all of them and the band.
  if (!continuous_view_.empty() && !targets_drawn && settings.heap_refresh > 1 &&
      settings.ellipsoid_passes == EllipsoidPasses::kFused &&
      settings.ellipsoid_order == EllipsoidOrder::kPerPixel) {
    std::ostringstream key;
    for (const auto& entry : batches) key << entry.first << '|';
    key << band.slabs.x << ',' << band.slabs.y << ',' << band.slabs.z << ',' << band.slabs.w;
    beginBand(*view.scene, key.str(), target, settings);
  }
  for (const auto& [key, members] : batches) {
    // Light batches queue their draws without waiting for them; once about kCancelWork has
    // gathered it is paced (paceQueued) before the flag is read, so that a cancelled frame
    // waits for at most twice that much (a world of many small clouds queued all its frame's work
    // before the first read).
    if (cancel_ && queued_work_ > kCancelWork) paceQueued();
    if (stopNow()) {
      band_.cancelled = true;
      break;
    }
    drawDirect(view, members, settings, target, targets_drawn, band, key);
  }
  if (band_.history) finishBand(*view.scene, target);
  band_ = BandReuse{};
}

void EllipsoidRenderer::beginBand(const Scene& scene, const std::string& key,
                                  const PassTarget& target, const RenderSettings& settings) {
  const glm::ivec2 frame_size(target.width, target.height);
  HeapHistory& h = heapHistory(scene, key, frame_size);
  band_ = BandReuse{};
  band_.history = &h;
  band_.reuse = h.valid;
  band_.bins_x = (target.width + kPerPixelBinSize - 1) / kPerPixelBinSize;
  band_.bins.assign(
      std::size_t(band_.bins_x) * ((target.height + kPerPixelBinSize - 1) / kPerPixelBinSize), 0);
  const GLfloat nothing[4] = {0.0f, 0.0f, 0.0f, 0.0f};
  gl_.ClearNamedFramebufferfv(h.framebuffer[1 - h.last].get(), GL_COLOR, 0, nothing);
  if (!band_.reuse) return;  // the exact frame: each batch walks every pixel into the history
  // Behind a thick veil (the frame shows half or less of what lies behind it), the band walks
  // one pixel in kVeiledShadingRate^2 whatever heap_refresh asks, as the veiled walk does.
  const bool veiled = kVeiledTolerance / std::max(target.seen, 1e-6) >= kVeiledSamplingFrom;
  band_.rate = std::max(refreshRate(settings.heap_refresh), veiled ? kVeiledShadingRate : 1);
  // Sample c stands at pixel r c + offset - r, one sample further back than the frame needs
  // and one more on each axis, so that every pixel has samples on both sides; the offset goes
  // round the r x r block frame by frame (sampleOffset).
  band_.origin = sampleOffset(h.frames + 1, band_.rate) - band_.rate;
  band_.size = (frame_size - 1) / band_.rate + 3;
  prepareSamples(band_.size);
  // No sample yet: no colour, and the largest distance, which the batches' nearest replace.
  const GLfloat far[4] = {kNoSampleDistance, 0.0f, 0.0f, 0.0f};
  gl_.ClearNamedFramebufferfv(samples_framebuffer_.get(), GL_COLOR, 0, nothing);
  gl_.ClearNamedFramebufferfv(samples_framebuffer_.get(), GL_COLOR, 1, far);
}

void EllipsoidRenderer::finishBand(const Scene& scene, const PassTarget& target) {
  HeapHistory& h = *band_.history;
  h.valid = !band_.cancelled && !band_.broken;
  if (band_.cancelled) return;
  if (band_.reuse) {
    // This frame's samples and the last frame between them, into the next history, then over
    // the frame, over the bins any batch overlaps, as runs along each row of bins: elsewhere
    // the band has nothing, which the cleared history already holds.
    timer_->settle();  // the samples are read next
    std::vector<glm::ivec4> runs;
    const int bins_y = int(band_.bins.size()) / band_.bins_x;
    for (int y = 0; y < bins_y; ++y)
      for (int x = 0; x < band_.bins_x; ++x) {
        if (!band_.bins[std::size_t(y) * band_.bins_x + x]) continue;
        int to = x + 1;
        while (to < band_.bins_x && band_.bins[std::size_t(y) * band_.bins_x + to]) ++to;
        runs.push_back(glm::ivec4(x, y, to, y + 1) * kPerPixelBinSize);
        x = to;
      }
    if (!runs.empty()) {
      EllipsoidPassLayout layout;
      layout.program = EllipsoidProgram::kFusedResolve;
      layout.shading_rate = band_.rate;
      const GLuint p = program(layout);
      setViewUniforms(gl_, p, scene.camera, scene);
      const ViewBasis last = viewBasis(h.camera);
      setUniform3(gl_, p, "u_prev_x", last.right / (last.tan_half_vfov * last.aspect));
      setUniform3(gl_, p, "u_prev_y", last.up / last.tan_half_vfov);
      setUniform3(gl_, p, "u_prev_w", last.forward);
      const glm::dvec2 drift = heapDrift(scene) - h.drift;
      setUniform3(gl_, p, "u_prev_shift",
                  scene.camera.position - h.camera.position - glm::dvec3(drift, 0.0));
      gl_.ProgramUniform2i(p, gl_.GetUniformLocation(p, "u_sample_origin"), band_.origin.x,
                           band_.origin.y);
      gl_.BindTextureUnit(kSamplesTextureUnit, samples_.get());
      gl_.BindTextureUnit(kSampleDistanceTextureUnit, sample_distance_.get());
      gl_.BindTextureUnit(kHistoryTextureUnit, h.colour[h.last].get());
      bindFrameTexture(kRectTextureUnit, GL_RGBA32I, runs.data(), runs.size() * sizeof(runs[0]));
      GpuPassScope pass(*timer_, GpuPass::kReuse);
      drawWithHistory(target, false, [&] {
        gl_.UseProgram(p);
        gl_.BindVertexArray(vertex_array_.get());
        gl_.DrawArrays(GL_TRIANGLES, 0, GLsizei(6 * runs.size()));
        return true;
      });
      ++stats_->reused_passes;
    }
  }
  h.frames = band_.reuse ? h.frames + 1 : 0;
  h.last = 1 - h.last;
  h.camera = scene.camera;
  h.time_s = scene.time_s;
  h.drift = heapDrift(scene);
}

void EllipsoidRenderer::renderImpostor(const ViewPlan& plan, std::size_t index, int size,
                                       const RenderSettings& settings, const PassTarget& target,
                                       Impostor& impostor) {
  // The cloud alone from here, looking at its centre, into a square texture: the plan's clouds,
  // borrowed, seen from that camera.
  const Camera& camera = plan.camera();
  const auto [centre, radius] = boundingSphere(plan.cloud(index));
  const double distance = glm::length(centre - camera.position);
  auto own = std::make_unique<Scene>(withClouds(*plan.scene, {}));
  Camera& looking = own->camera;
  const glm::dvec3 d = glm::normalize(centre - camera.position);
  looking.position = camera.position;
  looking.orientation = {glm::degrees(std::atan2(d.x, d.y)),
                         glm::degrees(std::asin(std::clamp(d.z, -1.0, 1.0))), 0.0};
  const double half_angle = std::asin(std::min(1.0, radius / distance)) * 1.02;
  looking.vfov_deg = glm::degrees(2.0 * half_angle);
  looking.width = looking.height = size;
  ViewPlan view;
  view.scene = own.get();
  view.own = std::move(own);
  view.clouds = plan.clouds;
  if (impostor.size != size || !impostor.texture) {
    createColourTarget(gl_, GL_RGBA16F, glm::ivec2(size), "impostor", impostor.texture,
                       impostor.framebuffer);
  }
  const float clear[4] = {0, 0, 0, 0};
  gl_.ClearNamedFramebufferfv(impostor.framebuffer.get(), GL_COLOR, 0, clear);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, impostor.framebuffer.get());
  gl_.Viewport(0, 0, size, size);
  const PassTarget impostor_target{impostor.framebuffer.get(), size, size};
  drawDirect(view, {index}, settings, impostor_target, false, AltitudeBand{}, "");
  gl_.BindFramebuffer(GL_FRAMEBUFFER, target.framebuffer);
  gl_.Viewport(0, 0, target.width, target.height);
  const ViewBasis basis = viewBasis(view.camera());
  impostor.eye = camera.position;
  impostor.centre = centre;
  impostor.right = basis.right;
  impostor.up = basis.up;
  impostor.half_size = distance * std::tan(half_angle);
  impostor.size = size;
  ++impostor_renders_;
  ++stats_->impostors_rendered;
}

bool EllipsoidRenderer::drawImpostor(const ViewPlan& plan, std::size_t index,
                                     const RenderSettings& settings, const PassTarget& target,
                                     bool targets_drawn, const AltitudeBand& band) {
  const Scene& scene = *plan.scene;
  const EllipsoidCloud& cloud = plan.cloud(index);
  const Camera& camera = scene.camera;
  const auto [centre, radius] = boundingSphere(cloud);
  const double distance = glm::length(centre - camera.position);
  // Only far clouds: the sphere well away from the eye and small on screen.
  const double pixels_per_radian = camera.height / glm::radians(camera.vfov_deg);
  const double diameter_px = 2.0 * radius / distance * pixels_per_radian;
  if (distance < 4.0 * radius || diameter_px > 512.0) return false;
  const int size = std::clamp(nextPowerOfTwo(diameter_px), 16, 512);

  Impostor& impostor = impostors_[index];
  impostor.used = true;
  const std::string key = impostorKey(scene, cloud, settings);
  // Reuse while the billboard's parallax, about R theta / distance in pixels for a change
  // theta in the direction to the centre, stays within the tolerance.
  const double theta = std::acos(std::clamp(
      glm::dot(glm::normalize(centre - impostor.eye), glm::normalize(centre - camera.position)),
      -1.0, 1.0));
  const double parallax_px =
      pixels_per_radian * radius *
      (theta + std::abs(glm::length(centre - impostor.eye) - distance) / distance) / distance;
  const bool fresh = impostor.key == key && glm::distance(impostor.centre, centre) == 0.0 &&
                     impostor.size >= size && parallax_px <= settings.impostor_tolerance_px;
  if (!fresh) {
    renderImpostor(plan, index, size, settings, target, impostor);
    impostor.key = key;
  }

  EllipsoidPassLayout layout;
  layout.program = EllipsoidProgram::kImpostor;
  layout.targets = targets_drawn;
  const GLuint p = program(layout);
  gl_.UseProgram(p);
  setViewUniforms(gl_, p, camera, scene, band);
  const ViewBasis basis = viewBasis(camera);
  setUniform3(gl_, p, "u_clip_x", basis.right / (basis.tan_half_vfov * basis.aspect));
  setUniform3(gl_, p, "u_clip_y", basis.up / basis.tan_half_vfov);
  setUniform3(gl_, p, "u_clip_w", basis.forward);
  glm::vec3 corners[4];
  for (int k = 0; k < 4; ++k)
    corners[k] = glm::vec3(centre - camera.position +
                           impostor.half_size * ((k & 1 ? 1.0 : -1.0) * impostor.right +
                                                 (k & 2 ? 1.0 : -1.0) * impostor.up));
  gl_.ProgramUniform3fv(p, gl_.GetUniformLocation(p, "u_corner"), 4, &corners[0].x);
  gl_.BindTextureUnit(kImpostorTextureUnit, impostor.texture.get());
  gl_.Enable(GL_BLEND);
  gl_.BlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  gl_.BindVertexArray(vertex_array_.get());
  gl_.DrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  ++stats_->ellipsoid_passes;
  ++stats_->impostors_drawn;
  return true;
}

bool EllipsoidRenderer::drawWithHistory(const PassTarget& target, bool accumulate,
                                        const std::function<bool()>& draw) {
  // Drawn over the frame and, as it is, into the band's next history in the same pass:
  // blended "over" what the band's batches before left there (a batch's exact walk), or
  // written as it is (the resolve, the whole band at once).
  HeapHistory& h = *band_.history;
  const GLuint f = target.framebuffer;
  gl_.NamedFramebufferTexture(f, GL_COLOR_ATTACHMENT1, h.colour[1 - h.last].get(), 0);
  const GLenum both[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  gl_.NamedFramebufferDrawBuffers(f, 2, both);
  if (!accumulate) gl_.Disablei(GL_BLEND, 1);
  const bool done = draw();
  gl_.Enable(GL_BLEND);
  const GLenum colour = GL_COLOR_ATTACHMENT0;
  gl_.NamedFramebufferDrawBuffers(f, 1, &colour);
  gl_.NamedFramebufferTexture(f, GL_COLOR_ATTACHMENT1, 0, 0);
  return done;
}

std::vector<EllipsoidRenderer::Visible> EllipsoidRenderer::visibleRecords(
    const ViewPlan& view, const std::vector<std::size_t>& indices, bool spotlight, int& total) {
  // The records of members [from, to) in order; each ellipsoid's is its own, so a batch of many
  // is split over up to kRecordThreads threads by members and joined in order: the same
  // records whatever the split.
  const Camera& camera = view.camera();
  const bool shadowed = sunlight_ && !sunlight_->empty();
  auto recordsOf = [&](std::size_t from, std::size_t to, bool watch) {
    std::vector<Visible> out;
    std::size_t seen = 0;
    for (std::size_t m = from; m < to; ++m) {
      const EllipsoidCloud& member = view.cloud(indices[m]);
      const std::vector<HeapEnvelope> envelopes = heapEnvelopes(member);
      for (std::size_t i = 0; i < member.ellipsoids.size(); ++i) {
        if (++seen % kCancelRecords == 0 &&
            (watch ? stopNow() : cancel_ && cancel_->load(std::memory_order_relaxed)))
          return out;
        Visible v;
        if (!makeEllipsoidRecord(member.ellipsoids[i], camera, spotlight, v.record,
                                 v.centre_distance))
          continue;
        const HeapEnvelope& e = envelopes[i];
        v.record.v[17] = glm::vec4(row(e.centre - camera.position, e.extinction));
        // The share of the sunlight the other clouds take, at the lobe's centre (MODEL.md
        // section 16, "heaps under clouds").
        const Ellipsoid& lobe = member.ellipsoids[i];
        const double shadow =
            shadowed
                ? 1.0 - sunlight_->at(lobe.centre, &e, lobe.centre.z + verticalHalfExtent(lobe))
                : 0.0;
        v.record.v[18] = glm::vec4(glm::dvec4(1.0 / e.radii, shadow));
        out.push_back(v);
      }
    }
    return out;
  };
  total = 0;
  for (std::size_t index : indices) total += int(view.cloud(index).ellipsoids.size());
  const int threads =
      std::clamp(std::min(int(std::thread::hardware_concurrency()), total / kRecordsPerThread), 1,
                 std::min(kRecordThreads, int(indices.size())));
  std::vector<std::future<std::vector<Visible>>> parts;
  for (int t = 1; t < threads; ++t)
    parts.push_back(std::async(std::launch::async, recordsOf, indices.size() * t / threads,
                               indices.size() * (t + 1) / threads, false));
  std::vector<Visible> visible = recordsOf(0, indices.size() / threads, true);
  for (auto& part : parts) {
    const std::vector<Visible> more = part.get();
    visible.insert(visible.end(), more.begin(), more.end());
  }
  return visible;
}

std::vector<EllipsoidRecord> EllipsoidRenderer::orderedRecords(std::vector<Visible>& visible,
                                                               bool front_to_back) {
  StageClock clock(stats_->times.cpu(CpuStage::kRecords));
  if (front_to_back)  // nearest bound first: the per-pixel pass composites front to back
    std::stable_sort(visible.begin(), visible.end(), [](const Visible& a, const Visible& b) {
      return a.record.v[16].z < b.record.v[16].z;
    });
  else
    std::stable_sort(visible.begin(), visible.end(), [](const Visible& a, const Visible& b) {
      return a.centre_distance > b.centre_distance;
    });
  std::vector<EllipsoidRecord> out;
  out.reserve(visible.size());
  for (const Visible& v : visible) out.push_back(v.record);
  return out;
}

void EllipsoidRenderer::drawDirect(const ViewPlan& view, const std::vector<std::size_t>& indices,
                                   const RenderSettings& settings, const PassTarget& target,
                                   bool targets_drawn, const AltitudeBand& band,
                                   const std::string& batch) {
  // The clouds look alike: the first one's texture and shading stand for all of them.
  const EllipsoidCloud& cloud = view.cloud(indices.front());
  // One of a continuous view's band of batches (an impostor's picture, `batch` empty, is not).
  HeapHistory* history = batch.empty() ? nullptr : band_.history;
  const bool spotlight = settings.limb == LimbEvaluation::kSpotlight;
  int total = 0;
  std::vector<Visible> visible;
  {
    StageClock clock(stats_->times.cpu(CpuStage::kRecords));
    visible = visibleRecords(view, indices, spotlight, total);
  }
  if (stopNow()) return;
  stats_->ellipsoids_drawn += int(visible.size());
  stats_->ellipsoids_culled += total - int(visible.size());
  if (visible.empty()) return;

  CachedTexture& texture = cachedTexture(cloud.texture, settings);
  const Batch b{*view.scene,
                cloud,
                texture,
                settings,
                target,
                band,
                batchLayout(*view.scene, cloud, texture, settings, spotlight, targets_drawn),
                history,
                targets_drawn};
  // The per-pixel pass orders every hit of the batch: its records and bin lists must fit in
  // buffer textures. Otherwise, and when asked, ellipsoids are blended back to front by
  // their centres.
  const std::size_t max_records = std::size_t(max_texels_) / kEllipsoidRecordVec4s;
  const bool per_pixel = settings.ellipsoid_passes == EllipsoidPasses::kFused &&
                         settings.ellipsoid_order == EllipsoidOrder::kPerPixel &&
                         visible.size() <= max_records;
  if (settings.ellipsoid_passes == EllipsoidPasses::kMultipass) {
    std::vector<EllipsoidRecord> ordered = orderedRecords(visible, false);
    drawTiles(b.scene, cloud, texture, b.base, settings, ordered, target, band);
    return;
  }
  gl_.BindVertexArray(vertex_array_.get());
  if (!per_pixel) {
    if (history) band_.broken = true;
    return drawByCentre(b, orderedRecords(visible, false));
  }
  const std::vector<EllipsoidRecord> ordered = orderedRecords(visible, true);
  std::optional<BinLists> bins;
  {
    StageClock clock(stats_->times.cpu(CpuStage::kRecords));  // the bins, to the items' fill
    bins = binLists(ordered, target, history != nullptr);
  }
  if (!bins) {
    if (history) band_.broken = true;
    return drawByCentre(b, orderedRecords(visible, false));
  }
  // Where no two ellipsoids share a bin, no pixel has two hits to order: the centre pass
  // draws the same image, faster; but for a continuous view's, which go into its history.
  if (bins->centre_suffices) return drawByCentre(b, ordered);
  drawPerPixel(b, ordered, *bins);
}

EllipsoidPassLayout EllipsoidRenderer::batchLayout(const Scene& scene, const EllipsoidCloud& cloud,
                                                   CachedTexture& texture,
                                                   const RenderSettings& settings, bool spotlight,
                                                   bool targets_drawn) {
  EllipsoidPassLayout base;
  // kAuto is the baked sums: with 16 texels per cycle of every term they come within 3 dB of
  // the sines against the reference however magnified (docs/ACCURACY.md, "Baked solid
  // texture").
  const bool gardner = texture.source->gardner() != nullptr;
  base.texture = !gardner ? SolidTextureKind::kTable
                 : settings.texture_evaluation == TextureEvaluation::kProcedural
                     ? SolidTextureKind::kProcedural
                     : SolidTextureKind::kBakedGardner;
  base.term_filter = settings.term_filter;
  base.spotlight = spotlight;
  base.air = sceneHasAir(scene);
  base.specular = cloud.shading.specular > 0.0;
  base.targets = targets_drawn;
  if (base.texture != SolidTextureKind::kProcedural) bindTables(texture);
  if (base.spotlight) gl_.BindTextureUnit(kSpotlightTextureUnit, spotlightTexture());
  gl_.Enable(GL_BLEND);
  gl_.BlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  return base;
}

void EllipsoidRenderer::drawByCentre(const Batch& b, const std::vector<EllipsoidRecord>& ordered) {
  EllipsoidPassLayout layout = b.base;
  layout.program = EllipsoidProgram::kFusedCentre;
  const GLuint p = program(layout);
  gl_.UseProgram(p);
  setCloudUniforms(p, b.scene, b.cloud, b.texture, layout.texture, b.band);
  gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, "u_first"), 0);
  // Instances blend in order, so drawing them in groups changes nothing but where a
  // cancellation can land.
  const std::size_t max_records = std::size_t(max_texels_) / kEllipsoidRecordVec4s;
  const bool cancellable = cancel_ && ordered.size() > kCancelInstances;
  const std::size_t group = cancellable ? std::min(max_records, kCancelInstances) : max_records;
  for (std::size_t first = 0; first < ordered.size(); first += group) {
    if (cancellable && first > 0) {
      paceQueued();
      if (stopNow()) return;
    }
    const std::size_t count = std::min(group, ordered.size() - first);
    bindFrameTexture(kRecordTextureUnit, GL_RGBA32F, ordered.data() + first,
                     count * sizeof(EllipsoidRecord));
    gl_.DrawArraysInstanced(GL_TRIANGLE_STRIP, 0, 4, GLsizei(count));
    for (std::size_t i = first; i < first + count; ++i) {  // a fragment per pixel of its rect
      const glm::vec4 rect = ordered[i].v[10];
      queued_work_ += std::int64_t(0.25 * (rect.z - rect.x) * (rect.w - rect.y) * b.target.width *
                                   b.target.height) +
                      1;
    }
    ++stats_->ellipsoid_passes;
  }
}

std::optional<EllipsoidRenderer::BinLists> EllipsoidRenderer::binLists(
    const std::vector<EllipsoidRecord>& ordered, const PassTarget& target, bool history) const {
  // Screen bins over the batch's rectangle, each listing the ellipsoids whose rectangles
  // overlap it, in the records' order (two passes: count, then fill).
  auto bin = [&](float ndc, int size) {
    return std::clamp(int((double(ndc) + 1.0) * 0.5 * size) / kPerPixelBinSize, 0,
                      (size - 1) / kPerPixelBinSize);
  };
  BinLists out;
  glm::ivec4& area = out.area;
  area = {std::numeric_limits<int>::max(), std::numeric_limits<int>::max(), -1, -1};
  std::vector<glm::ivec4> spans(ordered.size());
  for (std::size_t i = 0; i < ordered.size(); ++i) {
    const glm::vec4 rect = ordered[i].v[10];
    spans[i] = {bin(rect.x, target.width), bin(rect.y, target.height), bin(rect.z, target.width),
                bin(rect.w, target.height)};
    area = {std::min(area.x, spans[i].x), std::min(area.y, spans[i].y),
            std::max(area.z, spans[i].z), std::max(area.w, spans[i].w)};
    out.listed += std::int64_t(spans[i].z - spans[i].x + 1) * (spans[i].w - spans[i].y + 1);
  }
  out.bins_x = area.z - area.x + 1, out.bins_y = area.w - area.y + 1;
  // Bin lists beyond kMaxListed entries (64 MiB) fall back to the centre pass as well.
  const std::int64_t max_listed = std::min<std::int64_t>(max_texels_, kMaxListed);
  if (out.listed > max_listed || std::int64_t(out.bins_x) * out.bins_y > max_listed)
    return std::nullopt;
  // A bin is first item and count.
  out.bins.assign(std::size_t(out.bins_x) * out.bins_y, glm::ivec2(0));
  for (const glm::ivec4& span : spans)
    for (int y = span.y; y <= span.w; ++y)
      for (int x = span.x; x <= span.z; ++x) ++out.at(x, y).y;
  int deepest = 0, first = 0;
  for (glm::ivec2& b : out.bins) {
    deepest = std::max(deepest, b.y);
    b.x = first;
    first += b.y;
    b.y = 0;
  }
  if (deepest <= 1 && !history) {
    out.centre_suffices = true;
    return out;
  }
  out.items.resize(static_cast<std::size_t>(first));
  for (std::size_t i = 0; i < spans.size(); ++i)
    for (int y = spans[i].y; y <= spans[i].w; ++y)
      for (int x = spans[i].x; x <= spans[i].z; ++x) {
        glm::ivec2& b = out.at(x, y);
        out.items[std::size_t(b.x + b.y++)] = GLint(i);
      }
  return out;
}

GLuint EllipsoidRenderer::perPixelProgram(const Batch& b, const BinLists& bins,
                                          EllipsoidProgram which, int rate, bool history_too) {
  EllipsoidPassLayout layout = b.base;
  layout.program = which;
  layout.shading_rate = rate;
  layout.history = history_too;
  const GLuint p = program(layout);
  setCloudUniforms(p, b.scene, b.cloud, b.texture, layout.texture, b.band);
  gl_.ProgramUniform2i(p, gl_.GetUniformLocation(p, "u_bin_origin"), bins.area.x, bins.area.y);
  gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, "u_bins_x"), bins.bins_x);
  gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, "u_bin_size"), kPerPixelBinSize);
  const double shown = std::max(b.target.seen, 1e-6);
  gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_opaque"),
                       float(std::max(0.0, 1.0 - (1.0 - kOpaqueCoverage) / shown)));
  return p;
}

void EllipsoidRenderer::drawBinRect(GLuint program, glm::ivec2 size, int step, glm::ivec4 rect,
                                    int extra) {
  auto ndc = [&](int bins, int axis, int more) {
    return float(2.0 * std::min(double(bins * kPerPixelBinSize) / step + more, double(size[axis])) /
                     size[axis] -
                 1.0);
  };
  const float x0 = ndc(rect.x, 0, 0), y0 = ndc(rect.y, 1, 0), x1 = ndc(rect.z + 1, 0, extra),
              y1 = ndc(rect.w + 1, 1, extra);
  const glm::vec2 polygon[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  gl_.UseProgram(program);
  gl_.ProgramUniform2fv(program, gl_.GetUniformLocation(program, "u_polygon"), 4, &polygon[0].x);
  gl_.DrawArrays(GL_TRIANGLE_FAN, 0, 4);
}

bool EllipsoidRenderer::drawArea(const BinLists& bins,
                                 const std::function<void(glm::ivec4)>& draw) {
  constexpr std::int64_t kBinPixels = std::int64_t(kPerPixelBinSize) * kPerPixelBinSize;
  const glm::ivec4 area = bins.area;
  if (!cancel_ || bins.listed * kBinPixels <= kCancelWork) {
    draw(area);
    queued_work_ += bins.listed * kBinPixels;
    return true;
  }
  // Heavy: bands of whole bin rows of about kCancelWork hit tests (a row heavier than that
  // alone in runs of its bins), each paced (paceQueued) before the flag is read.
  auto finished = [&] {
    paceQueued();
    return stopNow();
  };
  int band_from = area.y;
  std::int64_t band_work = 0;
  for (int y = area.y; y <= area.w; ++y) {
    std::int64_t row_work = 0;
    for (int x = area.x; x <= area.z; ++x) row_work += bins.at(x, y).y * kBinPixels;
    if (band_work > 0 && band_work + row_work > kCancelWork) {
      draw({area.x, band_from, area.z, y - 1});
      if (finished()) return false;
      band_from = y, band_work = 0;
    }
    if (row_work <= kCancelWork) {
      band_work += row_work;
      continue;
    }
    int run_from = area.x;
    std::int64_t run_work = 0;
    for (int x = area.x; x <= area.z; ++x) {
      const std::int64_t work = bins.at(x, y).y * kBinPixels;
      if (run_work > 0 && run_work + work > kCancelWork) {
        draw({run_from, y, x - 1, y});
        if (finished()) return false;
        run_from = x, run_work = 0;
      }
      run_work += work;
    }
    draw({run_from, y, area.z, y});
    if (finished()) return false;
    band_from = y + 1;
  }
  if (band_from <= area.w) draw({area.x, band_from, area.z, area.w});
  return true;
}

void EllipsoidRenderer::drawPerPixel(const Batch& b, const std::vector<EllipsoidRecord>& ordered,
                                     const BinLists& bins) {
  // Behind a thick veil the walk may err by what the veil hides (MODEL.md section 15, "behind
  // the veil"): it ends at a lower coverage, and where the error allowed is large enough it
  // runs first at one pixel in rate^2 into the samples texture, then over every pixel, which
  // blends its samples where they agree.
  // Elsewhere it runs so at the heaps' own shading rate when one is asked (RenderSettings::
  // heap_shading_rate), and the samples are blended everywhere (MODEL.md section 15, "reduced
  // rate").
  const double tolerance = kVeiledTolerance / std::max(b.target.seen, 1e-6);
  const bool veiled = tolerance >= kVeiledSamplingFrom;
  const bool reduced = !veiled && b.settings.heap_shading_rate > 1;
  // A continuous view walks one pixel in heap_refresh each frame, at a sample offset that goes
  // round them all, and reuses its last frame for the others; the first frame after a cut is
  // the exact one (MODEL.md section 15, "reuse across frames"; beginBand). Behind a veil too:
  // there the reuse takes the place of the veiled sampling, with the veil's lower opacity cut.
  const bool reuse = b.history && band_.reuse;
  const int rate = b.targets_drawn ? 1
                   : reuse         ? band_.rate
                   : b.history     ? 1
                   : veiled        ? kVeiledShadingRate
                   : reduced       ? b.settings.heap_shading_rate
                                   : 1;
  bindFrameTexture(kRecordTextureUnit, GL_RGBA32F, ordered.data(),
                   ordered.size() * sizeof(EllipsoidRecord));
  bindFrameTexture(kBinTextureUnit, GL_RG32I, bins.bins.data(),
                   bins.bins.size() * sizeof(glm::ivec2));
  bindFrameTexture(kBinItemTextureUnit, GL_R32I, bins.items.data(),
                   bins.items.size() * sizeof(GLint));
  ++stats_->ellipsoid_passes;
  if (rate != 1) return drawSampled(b, bins, rate, reduced, tolerance);
  const GLuint p = perPixelProgram(b, bins, EllipsoidProgram::kFusedPerPixel, 1, b.history);
  const glm::ivec2 frame_size(b.target.width, b.target.height);
  auto draw = [&] {
    return drawArea(bins, [&](glm::ivec4 rect) { drawBinRect(p, frame_size, 1, rect); });
  };
  if (!b.history)
    draw();
  else if (!drawWithHistory(b.target, true, draw))
    band_.cancelled = true;
}

void EllipsoidRenderer::drawSampled(const Batch& b, const BinLists& bins, int rate, bool reduced,
                                    double tolerance) {
  // Sample c stands at pixel c * rate; one more than the frame needs on each axis, so that
  // every pixel has samples on both sides. Those outside the area stay 0: nothing of the batch
  // is there. A continuous view's grid is its band's (beginBand), which every batch of the band
  // samples over the others.
  const bool reuse = b.history && band_.reuse;
  const glm::ivec2 frame_size(b.target.width, b.target.height);
  const glm::ivec2 origin = reuse ? band_.origin : glm::ivec2(0);
  const glm::ivec2 size = reuse ? band_.size : (frame_size - 1) / rate + 2;
  if (!reuse) {  // only the colours are read: the distances are a continuous view's
    prepareSamples(size);
    const GLfloat nothing[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    gl_.ClearNamedFramebufferfv(samples_framebuffer_.get(), GL_COLOR, 0, nothing);
  }
  const GLuint s = perPixelProgram(b, bins, EllipsoidProgram::kFusedSamples, rate);
  gl_.ProgramUniform2i(s, gl_.GetUniformLocation(s, "u_sample_origin"), origin.x, origin.y);
  gl_.ProgramUniform1i(s, gl_.GetUniformLocation(s, "u_bins_y"), bins.bins_y);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, samples_framebuffer_.get());
  gl_.Viewport(0, 0, size.x, size.y);
  if (reuse) {
    // Over the samples of the band's batches drawn before (farther): "over" in colour, the
    // nearest of the distances.
    gl_.Enable(GL_BLEND);
    gl_.BlendEquationi(1, GL_MIN);
  } else {
    gl_.Disable(GL_BLEND);
  }
  const bool done =
      drawArea(bins, [&](glm::ivec4 rect) { drawBinRect(s, size, rate, rect, reuse ? 2 : 0); });
  gl_.BlendEquationi(1, GL_FUNC_ADD);
  gl_.Enable(GL_BLEND);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, b.target.framebuffer);
  gl_.Viewport(0, 0, b.target.width, b.target.height);
  if (reuse) {
    if (!done) band_.cancelled = true;
    const glm::ivec4 area = bins.area;
    for (int y = area.y; y <= area.w; ++y)
      for (int x = area.x; x <= area.z; ++x)
        if (bins.at(x, y).y > 0) band_.bins[std::size_t(y) * band_.bins_x + x] = 1;
    ++stats_->sampled_passes;
    return;
  }
  if (!done) return;
  timer_->settle();  // the samples are read next
  resolveSamples(b, bins, rate, size, reduced, tolerance);
}

void EllipsoidRenderer::resolveSamples(const Batch& b, const BinLists& bins, int rate,
                                       glm::ivec2 size, bool reduced, double tolerance) {
  const glm::ivec4 area = bins.area;
  const glm::ivec2 from = glm::ivec2(area.x, area.y) * kPerPixelBinSize / rate;
  const glm::ivec2 end = (glm::ivec2(area.z, area.w) + 1) * kPerPixelBinSize / rate;  // samples
  gl_.BindTextureUnit(kSamplesTextureUnit, samples_.get());
  if (reduced) {
    // The samples are brought to full size by their bilinear blend over the whole area, with
    // no readback (MODEL.md section 15, "reduced rate").
    drawRuns(b, bins, EllipsoidProgram::kFusedBlend, rate, {glm::ivec4(from * rate, end * rate)});
    ++stats_->sampled_passes;
    return;
  }
  // The blocks of rate x rate pixels over the area: blended where their four corner samples
  // agree to within the tolerance, walked elsewhere, as runs along each row of blocks. A
  // block whose far samples were not drawn (past the area) is walked.
  std::vector<float> values(std::size_t(size.x) * size.y * 4);
  gl_.GetTextureImage(samples_.get(), 0, GL_RGBA, GL_FLOAT, GLsizei(values.size() * sizeof(float)),
                      values.data());
  auto sample = [&](int x, int y) { return &values[(std::size_t(y) * size.x + x) * 4]; };
  auto blends = [&](int x, int y) {
    if (x + 1 >= end.x || y + 1 >= end.y) return false;
    const float *a = sample(x, y), *b = sample(x + 1, y), *c = sample(x, y + 1),
                *d = sample(x + 1, y + 1);
    for (int k = 0; k < 4; ++k) {
      const float lo = std::min({a[k], b[k], c[k], d[k]}), hi = std::max({a[k], b[k], c[k], d[k]});
      if (hi - lo > tolerance) return false;
    }
    return true;
  };
  std::vector<glm::ivec4> blended, walked;  // pixel rectangles
  for (int y = from.y; y < end.y; ++y)
    for (int x = from.x; x < end.x;) {
      const bool blend = blends(x, y);
      int to = x + 1;
      while (to < end.x && blends(to, y) == blend) ++to;
      (blend ? blended : walked).push_back(glm::ivec4(x, y, to, y + 1) * rate);
      x = to;
    }
  if (!blended.empty()) drawRuns(b, bins, EllipsoidProgram::kFusedBlend, rate, blended);
  if (!walked.empty()) drawRuns(b, bins, EllipsoidProgram::kFusedRest, rate, walked);
  ++stats_->sampled_passes;
}

void EllipsoidRenderer::drawRuns(const Batch& b, const BinLists& bins, EllipsoidProgram which,
                                 int rate, const std::vector<glm::ivec4>& runs) {
  // The blended runs in one draw; the walked ones, when the frame can be cancelled, in groups
  // of about kCancelWork hit tests.
  const GLuint q = perPixelProgram(b, bins, which, rate);
  const bool chunked = cancel_ && which == EllipsoidProgram::kFusedRest;
  std::size_t first = 0;
  std::int64_t work = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const glm::ivec4 r = runs[i];
    for (int bx = r.x / kPerPixelBinSize; chunked && bx * kPerPixelBinSize < r.z; ++bx)
      work += std::int64_t(bins.at(bx, r.y / kPerPixelBinSize).y) * rate *
              (std::min(r.z, (bx + 1) * kPerPixelBinSize) - std::max(r.x, bx * kPerPixelBinSize));
    const bool last = i + 1 == runs.size();
    if (!last && work <= kCancelWork) continue;
    bindFrameTexture(kRectTextureUnit, GL_RGBA32I, runs.data() + first,
                     (i + 1 - first) * sizeof(glm::ivec4));
    gl_.UseProgram(q);
    gl_.DrawArrays(GL_TRIANGLES, 0, GLsizei(6 * (i + 1 - first)));
    if (last) break;
    paceQueued();
    if (stopNow()) return;
    first = i + 1, work = 0;
  }
}

void EllipsoidRenderer::prepareSamples(glm::ivec2 size) {
  if (samples_ && samples_size_ == size) return;
  createColourTarget(gl_, GL_RGBA16F, size, "samples", samples_, samples_framebuffer_);
  sample_distance_ = createTexture(gl_, GL_TEXTURE_2D);
  gl_.TextureStorage2D(sample_distance_.get(), 1, GL_R32F, size.x, size.y);
  gl_.NamedFramebufferTexture(samples_framebuffer_.get(), GL_COLOR_ATTACHMENT1,
                              sample_distance_.get(), 0);
  const GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  gl_.NamedFramebufferDrawBuffers(samples_framebuffer_.get(), 2, buffers);
  samples_size_ = size;
}

void EllipsoidRenderer::prepareAtlas(TileFormat format) {
  if (atlas_ && atlas_format_ == format) return;
  createColourTarget(gl_, format == TileFormat::kFloat ? GL_RGBA16F : GL_RGBA8,
                     glm::ivec2(kAtlasSize), "atlas", atlas_, atlas_framebuffer_);
  atlas_format_ = format;
}

void EllipsoidRenderer::drawTiles(const Scene& scene, const EllipsoidCloud& cloud,
                                  CachedTexture& texture, const EllipsoidPassLayout& base,
                                  const RenderSettings& settings,
                                  std::vector<EllipsoidRecord>& records, const PassTarget& target,
                                  const AltitudeBand& band) {
  prepareAtlas(settings.tile_format);
  // Tile sizes: the screen rectangle rounded up to powers of two, or the fixed knob.
  std::vector<Tile> all;
  for (int i = 0; i < int(records.size()); ++i) {
    const glm::vec4 rect = records[i].v[10];
    const double w = 0.5 * (rect.z - rect.x) * target.width;
    const double h = 0.5 * (rect.w - rect.y) * target.height;
    Tile tile{i, settings.tile_resolution, settings.tile_resolution};
    if (settings.tile_resolution == 0)
      tile = {i, std::clamp(nextPowerOfTwo(w), 8, kMaxTileSize),
              std::clamp(nextPowerOfTwo(h), 8, kMaxTileSize)};
    all.push_back(tile);
  }
  // Batches in back-to-front order, each as many tiles as the atlas holds, packed first-fit
  // by decreasing size onto shelves.
  std::size_t next = 0;
  while (next < all.size()) {
    std::vector<Tile> batch;
    std::vector<Tile> trial;
    for (std::size_t i = next; i < all.size(); ++i) {
      trial.push_back(all[i]);
      std::vector<Tile> packed = trial;
      std::stable_sort(packed.begin(), packed.end(), [](const Tile& a, const Tile& b) {
        return a.height != b.height ? a.height > b.height : a.width > b.width;
      });
      int x = 0, y = 0, shelf = 0;
      bool fits = true;
      for (Tile& t : packed) {
        if (x + t.width > kAtlasSize) x = 0, y += shelf, shelf = 0;
        if (y + t.height > kAtlasSize) {
          fits = false;
          break;
        }
        t.x = x, t.y = y;
        x += t.width;
        shelf = std::max(shelf, t.height);
      }
      if (!fits) break;
      batch = packed;
    }
    NEPHELE_CHECK(!batch.empty(), "tile larger than the atlas");
    next += batch.size();
    renderAtlasBatch(scene, cloud, texture, base, settings, records, batch, target, band);
  }
}

void EllipsoidRenderer::renderAtlasBatch(const Scene& scene, const EllipsoidCloud& cloud,
                                         const CachedTexture& texture,
                                         const EllipsoidPassLayout& base,
                                         const RenderSettings& settings,
                                         std::vector<EllipsoidRecord>& records,
                                         std::vector<Tile>& tiles, const PassTarget& target,
                                         const AltitudeBand& band) {
  for (const Tile& t : tiles) records[t.record].v[15] = glm::vec4(t.x, t.y, t.width, t.height);
  uploadRecords(records);
  const ViewBasis basis = viewBasis(scene.camera);

  // The tile passes, into the atlas.
  gl_.BindFramebuffer(GL_FRAMEBUFFER, atlas_framebuffer_.get());
  gl_.Enable(GL_SCISSOR_TEST);
  const float zero[4] = {0, 0, 0, 0};
  for (const Tile& t : tiles) {
    gl_.Scissor(t.x, t.y, t.width, t.height);
    gl_.ClearNamedFramebufferfv(atlas_framebuffer_.get(), GL_COLOR, 0, zero);
  }
  gl_.Disable(GL_SCISSOR_TEST);
  gl_.Enable(GL_CULL_FACE);
  gl_.CullFace(GL_BACK);
  gl_.FrontFace(GL_CCW);
  for (EllipsoidProgram pass : {EllipsoidProgram::kTileThreshold, EllipsoidProgram::kTileLimb,
                                EllipsoidProgram::kTileColour}) {
    EllipsoidPassLayout layout = base;
    layout.program = pass;
    layout.targets = false;  // tiles are not in screen space; the composite tests targets
    const GLuint p = program(layout);
    gl_.UseProgram(p);
    setCloudUniforms(p, scene, cloud, texture, layout.texture, band);
    if (pass == EllipsoidProgram::kTileThreshold) {
      gl_.Disable(GL_BLEND);
    } else if (pass == EllipsoidProgram::kTileLimb) {
      // alpha -= (T2 - T1)(1 - g): reverse subtraction, alpha only.
      gl_.Enable(GL_BLEND);
      gl_.BlendEquationSeparate(GL_FUNC_ADD, GL_FUNC_REVERSE_SUBTRACT);
      gl_.BlendFuncSeparate(GL_ONE, GL_ONE, GL_ONE, GL_ONE);
      gl_.ColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_TRUE);
    } else {
      gl_.Disable(GL_BLEND);
      gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_FALSE);
    }
    for (const Tile& t : tiles) {
      const EllipsoidRecord& r = records[t.record];
      gl_.Viewport(t.x, t.y, t.width, t.height);
      const glm::mat4 projection = tileProjection(basis, glm::dvec4(r.v[10]));
      gl_.ProgramUniformMatrix4fv(p, gl_.GetUniformLocation(p, "u_projection"), 1, GL_FALSE,
                                  &projection[0][0]);
      gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, "u_index"), t.record);
      const double radius_px = 0.25 * std::max((r.v[10].z - r.v[10].x) * target.width,
                                               (r.v[10].w - r.v[10].y) * target.height);
      const IndexedMesh& mesh =
          sphereMesh(settings.tessellation > 0 ? settings.tessellation : adaptiveSlices(radius_px));
      gl_.BindVertexArray(mesh.vertex_array.get());
      gl_.DrawElements(GL_TRIANGLES, mesh.index_count, GL_UNSIGNED_INT, nullptr);
      ++stats_->atlas_passes;
    }
  }
  gl_.ColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  gl_.BlendEquationSeparate(GL_FUNC_ADD, GL_FUNC_ADD);
  gl_.Disable(GL_CULL_FACE);
  compositeAtlasTiles(scene, cloud, texture, base, records, tiles, target, band);
}

void EllipsoidRenderer::compositeAtlasTiles(const Scene& scene, const EllipsoidCloud& cloud,
                                            const CachedTexture& texture,
                                            const EllipsoidPassLayout& base,
                                            const std::vector<EllipsoidRecord>& records,
                                            const std::vector<Tile>& tiles,
                                            const PassTarget& target, const AltitudeBand& band) {
  // Every tile as a screen rectangle, back to front (records are in that order).
  gl_.BindFramebuffer(GL_FRAMEBUFFER, target.framebuffer);
  gl_.Viewport(0, 0, target.width, target.height);
  gl_.Enable(GL_BLEND);
  gl_.BlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  EllipsoidPassLayout layout = base;
  layout.program = EllipsoidProgram::kTileComposite;
  const GLuint p = program(layout);
  gl_.UseProgram(p);
  setCloudUniforms(p, scene, cloud, texture, layout.texture, band);
  const glm::vec2 atlas_size(kAtlasSize, kAtlasSize);
  gl_.ProgramUniform2fv(p, gl_.GetUniformLocation(p, "u_atlas_size"), 1, &atlas_size.x);
  gl_.BindTextureUnit(kAtlasTextureUnit, atlas_.get());
  gl_.BindVertexArray(vertex_array_.get());
  std::vector<int> order;
  for (const Tile& t : tiles) order.push_back(t.record);
  std::sort(order.begin(), order.end());
  for (int i : order) {
    const glm::vec4 rect = records[i].v[10];
    const glm::vec2 polygon[4] = {
        {rect.x, rect.y}, {rect.z, rect.y}, {rect.z, rect.w}, {rect.x, rect.w}};
    gl_.ProgramUniform2fv(p, gl_.GetUniformLocation(p, "u_polygon"), 4, &polygon[0].x);
    gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, "u_index"), i);
    gl_.DrawArrays(GL_TRIANGLE_FAN, 0, 4);
    ++stats_->ellipsoid_passes;
  }
}

Veil EllipsoidRenderer::veil(const ViewPlan& view, const RenderSettings& settings) {
  if (view.clouds.empty()) return {};
  return inCloudVeil(
      view.clouds,
      [&](std::size_t c) -> const SolidTexture& {
        return *cachedTexture(view.cloud(c).texture, settings).source;
      },
      view.camera().position, view.scene->sun);
}

void EllipsoidRenderer::drawVeil(const Veil& veil) {
  if (veil.opacity <= 0.0) return;
  EllipsoidPassLayout layout;
  layout.program = EllipsoidProgram::kVeil;
  const GLuint p = program(layout);
  gl_.UseProgram(p);
  const glm::vec4 premultiplied(glm::dvec4(veil.colour * veil.opacity, veil.opacity));
  gl_.ProgramUniform4fv(p, gl_.GetUniformLocation(p, "u_veil"), 1, &premultiplied.x);
  const glm::vec2 polygon[3] = {{-1, -1}, {3, -1}, {-1, 3}};
  gl_.ProgramUniform2fv(p, gl_.GetUniformLocation(p, "u_polygon"), 3, &polygon[0].x);
  gl_.Enable(GL_BLEND);
  gl_.BlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  gl_.BindVertexArray(vertex_array_.get());
  gl_.DrawArrays(GL_TRIANGLE_FAN, 0, 3);
  ++stats_->veil_passes;
}

}  // namespace nephele
