#include "renderer/gl/ellipsoid_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <future>
#include <limits>
#include <optional>
#include <sstream>
#include <thread>

#include "renderer/gl/ellipsoid_internal.h"
#include "renderer/gl/sky_shaders.h"
#include "renderer/gl/view_uniforms.h"
#include "world/check.h"
#include "world/formations/ellipsoid.h"

namespace nephele {

using namespace ellipsoid_detail;

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
  base.air = airMedia(scene);
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
