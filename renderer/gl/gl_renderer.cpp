#include "renderer/gl/gl_renderer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>
#include <vector>

#include "renderer/gl/shaders/floor_glsl.h"
#include "renderer/gl/sky_shaders.h"
#include "renderer/gl/view_uniforms.h"
#include "renderer/reference/reference_renderer.h"
#include "renderer/renderer.h"
#include "world/check.h"
#include "world/formations/cloud_shadow.h"
#include "world/shading.h"
#include "world/textures/layer_texture.h"
#include "world/textures/texture_table.h"

namespace nephele {
namespace {

// The part of convex polygon `in` where a * x + b * y + c >= 0 (Sutherland-Hodgman against one
// line). Empty when nothing is left. The two sides of one line share their new vertices
// exactly (negating a, b and c negates every f below, and the quotient with it).
std::vector<glm::vec2> clipPolygon(const std::vector<glm::vec2>& in, double a, double b, double c) {
  std::vector<glm::vec2> out;
  for (std::size_t i = 0; i < in.size(); ++i) {
    const glm::dvec2 p = in[i], q = in[(i + 1) % in.size()];
    const double fp = a * p.x + b * p.y + c, fq = a * q.x + b * q.y + c;
    if (fp >= 0.0) out.emplace_back(p);
    if ((fp >= 0.0) != (fq >= 0.0)) out.emplace_back(p + (q - p) * (fp / (fp - fq)));
  }
  return out.size() >= 3 ? out : std::vector<glm::vec2>{};
}

// The part of the screen square [-1, 1]^2 where a * x + b * y + c >= 0.
std::vector<glm::vec2> clipScreenToHalfPlane(double a, double b, double c) {
  return clipPolygon({{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}, a, b, c);
}

// The Gardner terms the sky shader's termCount lets a pixel of this layer evaluate at most:
// at the finest footprint it can show, straight above or below the camera, where a pixel
// spans the layer's distance times 2 tan(vfov / 2) / height (MODEL.md section 2's filter).
int layerTermsAtMost(const CloudLayer& layer, const LayerTexture& texture, const Camera& camera,
                     TermFilter filter) {
  const glm::dvec2 period = texture.period();
  const double footprint_m = std::abs(layer.altitude_m - camera.position.z) * 2.0 *
                             std::tan(glm::radians(camera.vfov_deg) / 2.0) / camera.height;
  // A fractional count evaluates one more term, faded.
  return int(std::ceil(texture.gardner()->termCountForFootprint(
      footprint_m / std::min(period.x, period.y), filter)));
}

// Cache key: every parameter of a layer texture and the settings its GPU form depends on.
std::string textureKey(const LayerTextureSpec& spec, const RenderSettings& settings) {
  std::ostringstream key;
  key.precision(17);
  // Drift is left out: it only moves the texture's origin, which the uniforms carry from each
  // layer's own spec (a far deck's offset changes every frame).
  key << int(spec.source) << '/' << spec.seed << '/';
  if (spec.source == TextureSource::kGardner) {
    const GardnerTextureParams& g = spec.gardner;
    key << g.terms << '/' << g.fx1 << '/' << g.fy1 << '/' << g.t0 << '/' << g.seeded_phases << '/'
        << g.rotation_deg << '/' << g.jitter_octaves << '/' << g.amplitude_ratio << '/'
        << settings.bake_texels_per_cycle;
  } else {
    const NoiseTableParams& t = spec.table;
    key << t.tile_size_m.x << '/' << t.tile_size_m.y << '/' << t.size_log2 << '/' << t.roughness
        << '/' << t.cells << '/' << t.octaves << '/' << t.persistence;
  }
  return key.str();
}

// Baked Gardner chain: level l holds the truncations to n - l terms (red) and n - l - 1
// terms (green) at (texels_per_cycle * 2^n) >> l texels a side.
void uploadBakedGardner(const GlApi& gl, GLuint texture, const GardnerTexture& gardner,
                        int texels_per_cycle) {
  const int base = gardnerBakeSize(gardner.terms(), texels_per_cycle);
  const int levels = int(std::log2(base)) + 1;
  gl.TextureStorage2D(texture, levels, GL_RG16, base, base);
  for (int level = 0; level < levels; ++level) {
    const int size = base >> level, terms = gardner.terms() - level;
    const GardnerTruncations baked = bakeGardner(gardner, size, terms);
    std::vector<float> rg(baked.with_terms.values.size() * 2);
    for (std::size_t i = 0; i < baked.with_terms.values.size(); ++i) {
      rg[2 * i] = baked.with_terms.values[i];
      rg[2 * i + 1] = baked.one_fewer.values[i];
    }
    gl.TextureSubImage2D(texture, level, 0, 0, size, size, GL_RG, GL_FLOAT, rg.data());
  }
  gl.TextureParameteri(texture, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
}

void uploadTable(const GlApi& gl, GLuint texture, const TextureTable& table) {
  const int levels = int(std::log2(std::max(table.width, table.height))) + 1;
  gl.TextureStorage2D(texture, levels, GL_R16, table.width, table.height);
  gl.TextureSubImage2D(texture, 0, 0, 0, table.width, table.height, GL_RED, GL_FLOAT,
                       table.values.data());
  gl.GenerateTextureMipmap(texture);
  gl.TextureParameteri(texture, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
}

// The layer bands of the per-ray depth order of MODEL.md section 4. Along any ray altitude changes
// monotonically, so the surfaces between the k-th and (k+1)-th layers on one side of the
// camera are those between their altitudes. Heights are relative to the camera; band b on
// the rising side is [A(b-1), A(b)) with A(-1) = 0 and A(n) = +inf, on the falling side
// [B(b), B(b-1)) with B(-1) = 0 and B(n) = -inf.
class CloudBands {
 public:
  struct Piece {
    int band;
    AltitudeBand window;
  };

  template <typename Slots>
  CloudBands(const Slots& above, const Slots& below, double camera_z) : camera_z_(camera_z) {
    // `above` runs farthest first; rank 0 is the nearest layer.
    for (auto it = above.rbegin(); it != above.rend(); ++it)
      rising_.push_back(it->layer->altitude_m - camera_z);
    for (auto it = below.rbegin(); it != below.rend(); ++it)
      falling_.push_back(it->layer->altitude_m - camera_z);
  }

  // One piece per band that altitudes [z_lo, z_hi] reach, each with the band's whole window
  // (both sides of the camera): a cloud has no surfaces in the part of the window it does not
  // reach, so every cloud of a band shares one window and the band's clouds are drawn in one
  // run, batched by look, instead of in runs broken wherever a cut cloud and a whole one alternate
  // in distance (two heap layers each cut by the other's deck: 120 runs a frame, measured).
  std::vector<Piece> pieces(double z_lo, double z_hi) const {
    const double lo = z_lo - camera_z_, hi = z_hi - camera_z_;
    int rise_first = -1, rise_last = -2, fall_first = -1, fall_last = -2;
    if (hi >= 0.0) rise_first = risingBand(std::max(lo, 0.0)), rise_last = risingBand(hi);
    if (lo < 0.0) fall_first = fallingBand(std::min(hi, -0.0)), fall_last = fallingBand(lo);
    std::vector<Piece> out;
    const int top = std::max(rise_last, fall_last);
    for (int b = 0; b <= top; ++b) {
      const bool rising = b >= rise_first && b <= rise_last;
      const bool falling = b >= fall_first && b <= fall_last;
      if (!rising && !falling) continue;
      glm::vec4 slabs(0.0f);
      if (std::size_t(b) <= rising_.size())
        slabs.x = bound(rising_, b - 1, 0.0), slabs.y = bound(rising_, b, 1e38);
      if (std::size_t(b) <= falling_.size())
        slabs.z = bound(falling_, b, -1e38), slabs.w = bound(falling_, b - 1, 0.0);
      out.push_back({b, {slabs}});
    }
    return out;
  }

 private:
  // Layers crossed before reaching height dz >= 0 (resp. dz < 0).
  int risingBand(double dz) const {
    return int(std::count_if(rising_.begin(), rising_.end(), [&](double a) { return a <= dz; }));
  }
  int fallingBand(double dz) const {
    return int(std::count_if(falling_.begin(), falling_.end(), [&](double b) { return b > dz; }));
  }
  static float bound(const std::vector<double>& heights, int rank, double beyond) {
    if (rank < 0) return 0.0f;
    return float(std::size_t(rank) < heights.size() ? heights[rank] : beyond);
  }

  double camera_z_;
  std::vector<double> rising_, falling_;  // nearest first
};

// How a layer's sky passes read its texture. A rotated Gardner texture never repeats, so no
// periodic table can hold it: it is read from a clipmap around the camera, or its sines are
// summed per pixel when asked (and with a term filter other than the fade, which the rings are
// built for).
LayerKind layerKind(const LayerTexture& texture, const RenderSettings& settings) {
  const bool sines = settings.texture_evaluation == TextureEvaluation::kProcedural;
  return !texture.gardner()   ? LayerKind::kTable
         : texture.periodic() ? (sines ? LayerKind::kProceduralGardner : LayerKind::kBakedGardner)
         : sines || settings.term_filter != TermFilter::kFade ? LayerKind::kProceduralGardner
                                                              : LayerKind::kClipmapGardner;
}

// Whether the GL rasterises on the CPU (Mesa's llvmpipe or softpipe).
bool softwareGl(const std::string& renderer) {
  return renderer.find("llvmpipe") != std::string::npos ||
         renderer.find("softpipe") != std::string::npos;
}

}  // namespace

// Lines across a camera's screen, as a x + b y + c >= 0 over [-1, 1]^2.
class ScreenLines {
 public:
  explicit ScreenLines(const Camera& camera) : camera_(camera), basis_(viewBasis(camera)) {}

  // How far the line a x + b y + c = 0 moves over `pixels` pixels, in c.
  double pixelsOf(double a, double b, double pixels) const {
    return pixels * (std::abs(a) * 2.0 / camera_.width + std::abs(b) * 2.0 / camera_.height);
  }
  // The screen region whose rays climb (sign = 1) or descend (sign = -1), widened by
  // `margin_pixels`: ray.z is linear across the image, so the horizon is a straight line.
  std::vector<glm::vec2> sideOfHorizon(double sign, double margin_pixels) const {
    const ViewBasis& basis = basis_;
    const double a = sign * basis.right.z * basis.tan_half_vfov * basis.aspect;
    const double b = sign * basis.up.z * basis.tan_half_vfov;
    return clipScreenToHalfPlane(a, b, sign * basis.forward.z + pixelsOf(a, b, margin_pixels));
  }
  // A far deck is clear within its hole (CloudLayer::hole_radius_m of horizontal distance from
  // the camera), so a ray steeper than |h| / radius never shows it. With r = forward +
  // x right' + y up' (right' and up' scaled to the screen's half extents), |r.xy| <= |r| <=
  // r_max over the screen, so every ray that can reach the deck beyond its hole satisfies
  // sign r.z <= r_max |h| / radius: a half-plane of the screen along the horizon. This is the
  // strip of `layer` on side `sign`, as the line (a, b, c); none for a layer without a hole.
  std::optional<glm::dvec3> strip(const CloudLayer& l, double sign) const {
    if (l.hole_radius_m <= 0.0) return std::nullopt;
    const ViewBasis& basis = basis_;
    const double r_max = std::sqrt(1.0 + basis.tan_half_vfov * basis.tan_half_vfov *
                                             (1.0 + basis.aspect * basis.aspect));
    const double reach = r_max * std::abs(l.altitude_m - camera_.position.z) / l.hole_radius_m;
    return glm::dvec3(-sign * basis.right.z * basis.tan_half_vfov * basis.aspect,
                      -sign * basis.up.z * basis.tan_half_vfov, reach - sign * basis.forward.z);
  }

 private:
  const Camera& camera_;
  ViewBasis basis_;
};

GlRenderer::GlRenderer(const GlPlatform& platform)
    : gl_(platform.gl()),
      vertex_array_(createVertexArray(gl_)),
      framebuffer_(createFramebuffer(gl_)),
      timer_(gl_, softwareGl(platform.renderer())),
      ellipsoids_(gl_),
      automata_(gl_),
      clipmaps_(gl_),
      targets_(gl_),
      shadow_map_(gl_) {}

GlRenderer::~GlRenderer() = default;

// Reads the bound framebuffer's w x h RGBA pixels of `type` into `out`, rows bottom-up, in
// bands of at most 256 MiB: llvmpipe's readback of 2 GiB or more in one call overflows a
// 32-bit size and writes out of bounds (a 16384x8192 float frame, issue 26).
void GlRenderer::readPixels(int w, int h, GLenum type, void* out) const {
  const std::size_t row_bytes = std::size_t(w) * 4 * (type == GL_FLOAT ? sizeof(float) : 1);
  const int band = int(std::max<std::size_t>(1, (std::size_t(256) << 20) / row_bytes));
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
  for (int y = 0; y < h; y += band)
    gl_.ReadPixels(0, y, w, std::min(band, h - y), GL_RGBA, type,
                   static_cast<char*>(out) + std::size_t(y) * row_bytes);
}

void GlRenderer::finishAndRead(int w, int h, GLenum type, void* out) {
  {
    StageClock wait(stats_.times.wait_ms);
    gl_.Finish();
  }
  timer_.collect(stats_.times);
  StageClock readback(stats_.times.readback_ms);
  readPixels(w, h, type, out);
}

FloatImage GlRenderer::renderFloat(const Scene& scene, const RenderSettings& settings) {
  drawFrame(scene, settings, TargetFormat::kFloat);
  return readFloat(scene.camera.width, scene.camera.height);
}

FloatImage GlRenderer::readFloat(int w, int h) {
  FloatImage image{w, h, std::vector<float>(std::size_t(w) * h * 4)};
  finishAndRead(w, h, GL_FLOAT, image.rgba.data());
  // GL rows run bottom-up; FloatImage rows run top-down.
  StageClock flip(stats_.times.readback_ms);
  const std::size_t row = std::size_t(w) * 4;
  for (int y = 0; y < h / 2; ++y)
    std::swap_ranges(image.rgba.begin() + y * row, image.rgba.begin() + (y + 1) * row,
                     image.rgba.begin() + (h - 1 - y) * row);
  return image;
}

Frame GlRenderer::renderFrame(const Scene& scene, const RenderSettings& settings,
                              const FrameRequest& request) {
  const Camera& camera = scene.camera;
  const int w = camera.width, h = camera.height;
  const std::size_t pixels = std::size_t(w) * h;
  const ChannelSet& asked = request.channels;
  Frame frame = frameFor(camera, scene.time_s, request);
  const bool composite = compositeAsked(asked);
  const bool traced =
      asked.has(Channel::kCloudDepth) || asked.has(Channel::kLwir) || asked.has(Channel::kGlint);
  // One plan for every channel: the colour's passes, the visibility's rain and the traced labels
  // see the same clouds, heaps and shafts.
  std::unique_ptr<FramePlan> plan;
  if (composite) {
    plan = drawFrame(scene, settings, TargetFormat::kFloat, traced);
    frame.colour = readFloat(w, h);
  } else if (traced || asked.has(Channel::kVisibility)) {
    plan = std::make_unique<FramePlan>(scene, planRequest(settings, traced));
  }
  if (asked.has(Channel::kVisibility)) {
    frame.visibilityFromCoverage();
    dimVisibilityByPrecipitation(frame, plan->view);
  }
  // The channels beyond the composite are read back and converted on the CPU.
  StageClock channels(stats_.times.readback_ms);
  if (asked.has(Channel::kDepth) || asked.has(Channel::kObjectId)) {
    // The composite pass drew the targets already; otherwise they are drawn alone.
    std::vector<float> distance, id;
    if (!scene.targets.empty() && (composite || targets_.draw(scene)))
      targets_.read(&distance, &id);
    const ViewBasis basis = viewBasis(camera);
    if (asked.has(Channel::kDepth)) frame.depth.resize(pixels);
    if (asked.has(Channel::kObjectId)) frame.object_id.resize(pixels);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::size_t gl = std::size_t(h - 1 - y) * w + x;  // GL rows run bottom-up
        const bool on_target = !distance.empty() && distance[gl] < 1e29f;
        // The ray's ground distance, wanted for depth and where a target may stand in front
        // of the ground: object ids alone (a dataset's masks) skip it elsewhere.
        if (frame.depth.empty() && !on_target && !scene.sea) continue;  // object_id stays 0
        const glm::dvec3 d = glm::normalize(rayDirection(basis, camera, x + 0.5, y + 0.5));
        const double ground =
            d.z < 0.0 ? camera.position.z / -d.z : std::numeric_limits<double>::infinity();
        const bool target = on_target && distance[gl] < ground;
        const std::size_t i = std::size_t(y) * w + x;
        if (!frame.depth.empty()) frame.depth[i] = target ? distance[gl] : float(ground);
        if (!frame.object_id.empty())
          frame.object_id[i] = target                               ? id[gl]
                               : scene.sea && std::isfinite(ground) ? kSeaObjectId
                                                                    : 0.0f;
      }
  }
  if (traced) {
    ReferenceSettings trace;
    trace.samples_per_axis = 1;
    trace.sea_waves = settings.sea_waves;
    trace.label_divisor = settings.channel_divisor;
    FrameRequest traced_request = request;
    traced_request.channels = {};
    for (Channel c : {Channel::kCloudDepth, Channel::kLwir, Channel::kGlint})
      if (asked.has(c)) traced_request.channels.add(c);
    Frame cpu = renderReferenceFrame(*plan, trace, traced_request);
    frame.cloud_depth = std::move(cpu.cloud_depth);
    frame.lwir = std::move(cpu.lwir);
    frame.glint = std::move(cpu.glint);
  }
  return frame;
}

Srgb8Image GlRenderer::renderSrgb8(const Scene& scene, const RenderSettings& settings) {
  drawFrame(scene, settings, TargetFormat::kSrgb8);
  const int w = scene.camera.width, h = scene.camera.height;
  Srgb8Image image{w, h, /*bottom_up=*/true, std::vector<std::uint8_t>(std::size_t(w) * h * 4)};
  finishAndRead(w, h, GL_UNSIGNED_BYTE, image.rgba.data());
  return image;
}

Srgb8Image GlRenderer::renderFloor(int width, int height) {
  prepareTarget(width, height, TargetFormat::kSrgb8);
  if (!floor_program_) {
    std::string error;
    floor_program_ =
        createProgram(gl_, polygonVertexSource(), glsl::floor_pass::kFloorFragment, error);
    NEPHELE_CHECK(floor_program_, "floor program: " << error);
  }
  const GLuint p = floor_program_.get();
  gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffer_.get());
  gl_.Viewport(0, 0, width, height);
  gl_.BindVertexArray(vertex_array_.get());
  gl_.Enable(GL_FRAMEBUFFER_SRGB);
  gl_.UseProgram(p);
  const glm::vec4 colour(0.25f, 0.3f, 0.4f, 0.5f);
  gl_.ProgramUniform4fv(p, gl_.GetUniformLocation(p, "u_colour"), 1, &colour.x);
  const glm::vec2 triangle[3] = {{-1, -1}, {3, -1}, {-1, 3}};
  gl_.ProgramUniform2fv(p, gl_.GetUniformLocation(p, "u_polygon"), 3, &triangle[0].x);
  gl_.Enable(GL_BLEND);
  gl_.BlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  gl_.DrawArrays(GL_TRIANGLE_FAN, 0, 3);
  gl_.Disable(GL_BLEND);
  Srgb8Image image{width, height, /*bottom_up=*/true,
                   std::vector<std::uint8_t>(std::size_t(width) * height * 4)};
  readPixels(width, height, GL_UNSIGNED_BYTE, image.rgba.data());
  return image;
}

std::string GlRenderer::reserveTarget(int width, int height, bool linear, bool targets) {
  const TargetFormat format = linear ? TargetFormat::kFloat : TargetFormat::kSrgb8;
  const bool frame = allocateTarget(width, height, format);
  if (frame && (!targets || targets_.allocate(width, height))) return {};
  const double mib = double(width) * height / double(1 << 20);
  std::ostringstream out;
  out.precision(3);
  if (frame)
    out << width << "x" << height << " target layers (" << mib * 20.0
        << " MiB: RGBA16F, two R32F and a 32-bit depth buffer, for the scene's targets)";
  else
    out << width << "x" << height << (linear ? " float (EXR)" : " 8-bit") << " target of "
        << mib * (linear ? 16.0 : 4.0) << " MiB";
  out << ": this OpenGL cannot allocate it (llvmpipe: at most 2 GiB per buffer, so 16384x16384 "
         "8-bit and 16384x8192 float); use a smaller size"
      << (linear ? " or an 8-bit format" : "");
  return out.str();
}

bool GlRenderer::allocateTarget(int width, int height, TargetFormat format) {
  if (colour_buffer_ && width == target_width_ && height == target_height_ &&
      format == target_format_)
    return true;
  target_width_ = target_height_ = 0;
  clearGlErrors(gl_);
  colour_buffer_ = createRenderbuffer(gl_);
  gl_.NamedRenderbufferStorage(colour_buffer_.get(),
                               format == TargetFormat::kFloat ? GL_RGBA32F : GL_SRGB8_ALPHA8, width,
                               height);
  gl_.NamedFramebufferRenderbuffer(framebuffer_.get(), GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                                   colour_buffer_.get());
  if (!framebufferUsable(gl_, framebuffer_.get())) {
    colour_buffer_ = GlObject();
    return false;
  }
  target_width_ = width;
  target_height_ = height;
  target_format_ = format;
  return true;
}

void GlRenderer::prepareTarget(int width, int height, TargetFormat format) {
  NEPHELE_CHECK(allocateTarget(width, height, format),
                "framebuffer " << width << "x" << height << " incomplete (reserveTarget first)");
}

GLuint GlRenderer::program(const SkyPassLayout& layout) {
  const std::string key = layout.key();
  auto found = programs_.find(key);
  if (found != programs_.end()) return found->second.get();
  std::string error;
  GlObject compiled = createProgram(gl_, polygonVertexSource(), skyFragmentSource(layout), error);
  NEPHELE_CHECK(compiled, key << ": " << error);
  return programs_.emplace(key, std::move(compiled)).first->second.get();
}

GlRenderer::CachedTexture& GlRenderer::cachedTexture(const LayerTextureSpec& spec,
                                                     const RenderSettings& settings) {
  auto [entry, inserted] = textures_.try_emplace(textureKey(spec, settings));
  if (inserted) {
    entry->second.source = std::make_unique<LayerTexture>(spec);
    entry->second.key = entry->first;
  }
  entry->second.last_frame = frame_;
  return entry->second;
}

GLuint GlRenderer::gpuTexture(CachedTexture& cached, const RenderSettings& settings) {
  if (cached.texture) return cached.texture.get();
  StageClock clock(stats_.times.cpu(CpuStage::kUploads));
  cached.texture = createTexture(gl_, GL_TEXTURE_2D);
  const GLuint t = cached.texture.get();
  if (const GardnerTexture* gardner = cached.source->gardner())
    uploadBakedGardner(gl_, t, *gardner, settings.bake_texels_per_cycle);
  else
    uploadTable(gl_, t, *cached.source->table());
  gl_.TextureParameteri(t, GL_TEXTURE_WRAP_S, GL_REPEAT);
  gl_.TextureParameteri(t, GL_TEXTURE_WRAP_T, GL_REPEAT);
  gl_.TextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  return t;
}

void GlRenderer::setSlotUniforms(GLuint p, int slot, int unit, const LayerSlot& entry,
                                 const Scene& scene, const RenderSettings& settings) {
  const CloudLayer& layer = *entry.layer;
  const LayerTexture& texture = *entry.texture->source;
  const Camera& camera = scene.camera;
  auto location = [&](const char* name, int index) {
    char element[48];
    std::snprintf(element, sizeof element, "%s[%d]", name, index);
    return gl_.GetUniformLocation(p, element);
  };
  gl_.ProgramUniform1f(p, location("u_height", slot), float(layer.altitude_m - camera.position.z));
  const glm::vec3 colour(layer.colour * scene.sun.colour);
  gl_.ProgramUniform3fv(p, location("u_colour", slot), 1, &colour.x);
  const ShadingParams& sh = layer.shading;
  const glm::vec4 shading(sh.ambient, sh.texture_fraction, sh.specular, sh.shininess);
  gl_.ProgramUniform4fv(p, location("u_shading", slot), 1, &shading.x);
  gl_.ProgramUniform1f(p, location("u_threshold", slot), float(layer.threshold));
  gl_.ProgramUniform1f(p, location("u_transition", slot), float(layer.transition));
  if (GLint where = location("u_region", slot); where >= 0) {
    // The region's centre, drifted with the layer, from the camera in double.
    const Region& r = layer.region;
    const LayerTextureSpec& t = layer.texture;
    const glm::dvec2 centre =
        r.centre + t.drift_offset_m + t.drift_velocity * scene.time_s - glm::dvec2(camera.position);
    const double h = glm::radians(r.heading_deg);
    const glm::vec4 frame(centre.x, centre.y, std::cos(h), std::sin(h));
    auto finite = [](double half) { return float(std::min(half, 1.0e30)); };
    const glm::vec4 size(finite(r.half_size.x), finite(r.half_size.y), r.edge_m, r.transition_m);
    gl_.ProgramUniform4fv(p, where, 1, &frame.x);
    gl_.ProgramUniform4fv(p, location("u_region_size", slot), 1, &size.x);
    gl_.ProgramUniform1f(p, location("u_region_side", slot), float(r.side));
    const glm::vec2 hole(layer.hole_radius_m, layer.hole_band_m);
    gl_.ProgramUniform2fv(p, location("u_hole", slot), 1, &hole.x);
    const glm::vec2 far(layer.far.coverage, layer.far.side_ratio);
    gl_.ProgramUniform2fv(p, location("u_far", slot), 1, &far.x);
    float table[FarCover::kSteps + 1];
    for (int k = 0; k <= FarCover::kSteps; ++k) table[k] = float(layer.far.threshold[k]);
    gl_.ProgramUniform1fv(p, location("u_far_threshold", (FarCover::kSteps + 1) * slot),
                          FarCover::kSteps + 1, table);
  }

  // The precision rule of MODEL.md section 2: the texture's local origin is the point under the
  // camera, reduced modulo the period in double; the shader only sees offsets from it.
  const glm::dvec2 period = texture.period();
  const glm::dvec2 camera_xy(camera.position.x, camera.position.y);
  const glm::dvec2 origin_uv =
      texture.periodic() ? texture.periodicCoordinate(camera_xy, scene.time_s, layer.texture)
                         : glm::dvec2(0.0);
  const glm::vec2 origin_f(origin_uv), inv_period(1.0 / period);
  gl_.ProgramUniform2fv(p, location("u_origin", slot), 1, &origin_f.x);
  gl_.ProgramUniform2fv(p, location("u_inv_period", slot), 1, &inv_period.x);

  if (const GardnerTexture* g = texture.gardner()) {
    gl_.ProgramUniform1f(p, location("u_terms", slot), float(g->terms()));
    if (entry.kind == LayerKind::kProceduralGardner)
      // Metres inside one period; a rotated texture has none, so its phases at the point under
      // the camera are taken from the whole drifted position, in double, term by term.
      setLayerGardnerUniforms(gl_, p, slot, *g,
                              texture.periodic()
                                  ? origin_uv * period
                                  : camera_xy - texture.driftOffset(scene.time_s, layer.texture));
  }
  if (entry.kind == LayerKind::kClipmapGardner) {
    const ClipmapView& c = entry.clipmap;
    const glm::vec2 texel(c.texel_m);
    gl_.ProgramUniform2fv(p, location("u_clip_texel", slot), 1, &texel.x);
    gl_.ProgramUniform2fv(p, location("u_clip_offset", 8 * slot), GLsizei(c.offset.size()),
                          &c.offset[0].x);
    gl_.ProgramUniform1f(p, location("u_clip_size", slot), float(c.size));
    gl_.ProgramUniform1f(p, location("u_clip_rings", slot), float(c.rings));
    gl_.ProgramUniform1f(p, location("u_clip_constant", slot), float(c.constant));
    gl_.ProgramUniform1f(p, location("u_clip_finest", slot), float(c.finest));
  }
  if (entry.kind != LayerKind::kProceduralGardner) {
    gl_.BindTextureUnit(GLuint(unit), entry.kind == LayerKind::kClipmapGardner
                                          ? entry.clipmap.texture
                                          : gpuTexture(*entry.texture, settings));
    const std::string sampler = "u_table" + std::to_string(slot);
    gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, sampler.c_str()), unit);
  }
}

void GlRenderer::drawSkyPass(const Scene& scene, const RenderSettings& settings,
                             const SkyPassLayout& drawn, const std::vector<LayerSlot>& slots,
                             const std::vector<glm::vec2>& polygon) {
  // The casting planes above the lowest plane the pass draws (the ground, where the background
  // reaches below the horizon).
  SkyPassLayout layout = drawn;
  layout.ground = layout.ground && layout.background;
  double lowest = layout.ground ? 0.0 : std::numeric_limits<double>::infinity();
  for (const LayerSlot& slot : slots) lowest = std::min(lowest, slot.layer->altitude_m);
  std::vector<const LayerSlot*> casting;
  for (const LayerSlot& caster : casters_)
    if (caster.layer->altitude_m > lowest) {
      casting.push_back(&caster);
      layout.casters.push_back(caster.kind);
    }
  for (const LayerSlot& slot : slots)
    layout.shaded_by.push_back(
        int(std::count_if(casting.begin(), casting.end(), [&](const LayerSlot* c) {
          return c->layer->altitude_m > slot.layer->altitude_m;
        })));
  const GLuint p = program(layout);
  gl_.UseProgram(p);
  const Camera& camera = scene.camera;
  const ViewBasis basis = viewBasis(camera);
  auto uniform3 = [&](const char* name, glm::dvec3 v) { setUniform3(gl_, p, name, v); };
  setViewUniforms(gl_, p, camera, scene);
  if (layout.background) {
    uniform3("u_zenith", scene.sky.zenith);
    uniform3("u_horizon", scene.sky.horizon);
    uniform3("u_ground", scene.sky.ground);
    const double slope =
        std::hypot(basis.right.z * basis.tan_half_vfov * basis.aspect * 2.0 / camera.width,
                   basis.up.z * basis.tan_half_vfov * 2.0 / camera.height);
    gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_horizon_slope"),
                         float(std::max(slope, 1e-12)));
  }
  if (layout.shadows) shadow_map_.bind(p, 11, camera.position);
  if (layout.sea) setSeaUniforms(p, scene, settings);
  if (!slots.empty() || !casting.empty()) uniform3("u_to_sun", sunDirection(scene.sun));
  for (std::size_t i = 0; i < slots.size(); ++i)
    setSlotUniforms(p, int(i), int(i), slots[i], scene, settings);
  for (std::size_t c = 0; c < casting.size(); ++c)
    setSlotUniforms(p, int(slots.size() + c), kCasterUnit + int(c), *casting[c], scene, settings);
  gl_.ProgramUniform2fv(p, gl_.GetUniformLocation(p, "u_polygon"), GLsizei(polygon.size()),
                        &polygon[0].x);
  gl_.DrawArrays(GL_TRIANGLE_FAN, 0, GLsizei(polygon.size()));
  ++stats_.sky_passes;
}

void GlRenderer::drawSkyGroup(const Scene& scene, const RenderSettings& settings,
                              const std::vector<LayerSlot>& above,
                              const std::vector<LayerSlot>& below, bool background, bool targets) {
  SkyPassLayout base;
  base.air = airMedia(scene);
  base.term_filter = settings.term_filter;
  base.targets = targets;
  base.shadows = shadow_map_.active();
  base.sea = background && scene.sea && sea_probe_;
  for (const CloudLayer& layer : scene.layers) {
    base.specular |= layer.shading.specular > 0.0;
    base.regions |= layerHasRegion(layer);
  }
  const bool fused = settings.sky_passes == SkyPasses::kFused &&
                     int(std::max(above.size(), below.size())) <= kMaxLayerSlots;
  // Every pass writes premultiplied colour and coverage; a pass with the background
  // overwrites, the others blend "over".
  gl_.BlendFuncSeparate(GL_ONE, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  if (background)
    gl_.Disable(GL_BLEND);
  else
    gl_.Enable(GL_BLEND);
  const ScreenLines lines(scene.camera);
  if (fused) return drawFusedSky(scene, settings, base, lines, above, below, background);
  if (background) {
    // One triangle covering the screen: no diagonal edge for the rasteriser to split tiles on.
    drawSkyPass(scene, settings, base, {}, {{-1, -1}, {3, -1}, {-1, 3}});
    gl_.Enable(GL_BLEND);
  }
  for (const auto* side : {&above, &below})
    for (const LayerSlot& slot : *side) {
      // Only where rays meet the plane (and reach beyond a far deck's hole), plus two pixels
      // the shader leaves untouched.
      const double sign = side == &above ? 1.0 : -1.0;
      std::vector<glm::vec2> polygon = lines.sideOfHorizon(sign, 2.0);
      if (const std::optional<glm::dvec3> line = lines.strip(*slot.layer, sign))
        polygon =
            clipPolygon(polygon, line->x, line->y, line->z + lines.pixelsOf(line->x, line->y, 2.0));
      if (polygon.empty()) continue;
      SkyPassLayout layout = base;
      layout.background = false;
      (side == &above ? layout.above : layout.below).push_back(slot.kind);
      drawSkyPass(scene, settings, layout, {slot}, polygon);
    }
}

void GlRenderer::drawFusedSky(const Scene& scene, const RenderSettings& settings,
                              const SkyPassLayout& base, const ScreenLines& lines,
                              const std::vector<LayerSlot>& above,
                              const std::vector<LayerSlot>& below, bool background) {
  // One pass per side of the horizon, each with the background and that side's layers:
  // pixels below the horizon never run the code of layers above the camera. Where that
  // side has far decks, it is cut again along the widest of their strips: beyond it the
  // pass leaves them out. The polygons share their edges exactly, so every pixel is drawn
  // once.
  for (const auto* side : {&above, &below}) {
    if (!background && side->empty()) continue;
    const double sign = side == &above ? 1.0 : -1.0;
    const std::vector<glm::vec2> polygon = lines.sideOfHorizon(sign, 0.0);
    if (polygon.empty()) continue;
    std::optional<glm::dvec3> widest;
    std::vector<LayerSlot> open;  // the slots drawn beyond the widest strip
    for (const LayerSlot& slot : *side) {
      const std::optional<glm::dvec3> line = lines.strip(*slot.layer, sign);
      if (!line)
        open.push_back(slot);
      else if (!widest || line->z > widest->z)
        widest = line;
    }
    auto draw = [&](const std::vector<LayerSlot>& slots, const std::vector<glm::vec2>& area) {
      if (area.empty() || (!background && slots.empty())) return;
      SkyPassLayout layout = base;
      layout.background = background;
      layout.ground = side == &below;  // the pass above the horizon holds no ground
      for (const LayerSlot& slot : slots)
        (side == &above ? layout.above : layout.below).push_back(slot.kind);
      drawSkyPass(scene, settings, layout, slots, area);
    };
    if (!widest) {
      draw(*side, polygon);
      continue;
    }
    draw(*side, clipPolygon(polygon, widest->x, widest->y, widest->z));
    draw(open, clipPolygon(polygon, -widest->x, -widest->y, -widest->z));
  }
}

FramePlanRequest GlRenderer::planRequest(const RenderSettings& settings, bool sea_eye) {
  FramePlanRequest request;
  request.heaps = settings.heaps;
  request.ellipsoid_budget = settings.ellipsoid_budget;
  request.ellipsoid_overdraw = settings.ellipsoid_overdraw;
  request.sea_view = true;
  request.sea_eye = sea_eye;
  request.sea_probe_scale = settings.sea_probe_scale;
  request.cull = true;
  request.heap_shadows = settings.shadow_map_size > 0;
  request.plane_shadows = settings.plane_shadows;
  return request;
}

std::unique_ptr<FramePlan> GlRenderer::drawFrame(const Scene& scene, const RenderSettings& settings,
                                                 TargetFormat format, bool sea_eye) {
  const auto start = std::chrono::steady_clock::now();
  const std::uint64_t linked = programsLinked();
  timer_.beginFrame();
  auto owned = std::make_unique<FramePlan>(scene, planRequest(settings, sea_eye));
  const FramePlan& plan = *owned;
  RenderSettings rest = settings;
  if (plan.thinned)
    rest.ellipsoid_budget = rest.ellipsoid_overdraw = 0.0;  // the plan's clouds are within it
  stats_ = {};
  FrameTimes& t = stats_.times;
  t.cpu(CpuStage::kHeaps) = plan.heaps_ms;
  t.cpu(CpuStage::kBudget) = plan.budget_ms;
  t.cpu(CpuStage::kShadows) = plan.shadows_ms;
  // The ground's cloud shadows (MODEL.md section 16) and, with the casting planes, the shadows
  // on the clouds and targets below them, each lobe and target at its centre.
  sunlight_ = {&plan.plane_shadows, plan.heap_shadows ? &*plan.heap_shadows : nullptr};
  shadow_map_.prepare(plan.heap_shadows ? *plan.heap_shadows : CloudShadows(),
                      scene.camera.position, settings.shadow_map_size, stats_, timer_);
  ellipsoids_.setSunlight(&sunlight_);
  drawSeaProbe(plan, rest);
  drawView(plan.view, rest, format);
  ellipsoids_.setSunlight(nullptr);
  sunlight_ = {};  // it points into the plan
  sea_probe_ = false;
  timer_.enter(-1);
  stats_.programs_compiled = int(programsLinked() - linked);
  t.submit_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count() -
      timer_.waitedMs();
  // The draw list and the passes' own GL calls: what the other stages leave of the submission.
  double staged = 0.0;
  for (std::size_t i = 0; i < t.cpu_ms.size(); ++i)
    if (i != std::size_t(CpuStage::kScene)) staged += t.cpu_ms[i];
  t.cpu(CpuStage::kScene) = std::max(0.0, t.submit_ms - staged);
  return owned;
}

void GlRenderer::drawSeaProbe(const FramePlan& plan, const RenderSettings& settings) {
  sea_probe_ = false;
  if (!plan.sea_probe) return;
  const ViewPlan& probe = *plan.sea_probe;
  const std::string view = continuous_view_;
  continuous_view_ = view.empty() ? view : view + "/sea probe";
  drawView(probe, settings, TargetFormat::kFloat);
  continuous_view_ = view;
  const int w = probe.camera().width, h = probe.camera().height;
  if (!sea_probe_texture_ || sea_probe_width_ != w || sea_probe_height_ != h) {
    sea_probe_texture_ = createTexture2D(gl_, GL_RGBA32F, w, h);
    sea_probe_width_ = w;
    sea_probe_height_ = h;
  }
  gl_.CopyImageSubData(colour_buffer_.get(), GL_RENDERBUFFER, 0, 0, 0, 0, sea_probe_texture_.get(),
                       GL_TEXTURE_2D, 0, 0, 0, 0, w, h, 1);
  const ViewBasis pb = viewBasis(probe.camera());
  sea_probe_right_ = pb.right / (pb.tan_half_vfov * pb.aspect);
  sea_probe_up_ = pb.up / pb.tan_half_vfov;
  sea_probe_forward_ = pb.forward;
  sea_probe_ = true;
}

void GlRenderer::setSeaUniforms(GLuint p, const Scene& scene, const RenderSettings& settings) {
  const Sea& sea = *scene.sea;
  if (!sea_surface_ || sea_surface_->sea != sea || sea_surface_->waves != settings.sea_waves) {
    // A re-centred world moves the same waves (and keeps their whitecaps' quantile).
    Sea moved = sea_surface_ ? sea_surface_->sea : Sea{};
    moved.origin_m = sea.origin_m;
    if (sea_surface_ && moved == sea && sea_surface_->waves == settings.sea_waves)
      sea_surface_.emplace(sea, settings.sea_waves, sea_surface_->surface.movedTo(sea.origin_m));
    else
      sea_surface_.emplace(sea, settings.sea_waves, SeaSurface(sea, settings.sea_waves));
  }
  const SeaSurface& surface = sea_surface_->surface;
  const std::vector<WaveComponent>& waves = surface.components();
  const int n = int(std::min<std::size_t>(waves.size(), kMaxSeaWaves));
  std::vector<glm::vec4> packed(std::size_t(std::max(n, 1)));
  std::vector<glm::vec3> wobble(packed.size());
  const glm::dvec2 eye(scene.camera.position);
  constexpr double kTurn = 2.0 * std::numbers::pi;
  for (int i = 0; i < n; ++i) {
    const WaveComponent& w = waves[std::size_t(i)];
    const double phase =
        std::remainder(glm::dot(w.k, eye) - w.omega * scene.time_s + w.phase, kTurn);
    packed[std::size_t(i)] = glm::vec4(glm::vec2(w.k), float(w.amplitude), float(phase));
    wobble[std::size_t(i)] =
        glm::vec3(glm::vec2(w.q), float(std::remainder(glm::dot(w.q, eye) + w.psi, kTurn)));
  }
  gl_.ProgramUniform4fv(p, gl_.GetUniformLocation(p, "u_wave"), GLsizei(n), &packed[0].x);
  gl_.ProgramUniform3fv(p, gl_.GetUniformLocation(p, "u_wave_wobble"), GLsizei(n), &wobble[0].x);
  gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, "u_waves"), n);
  const glm::vec4 params(float(surface.slopeVariance()), float(surface.drawnSlopeVariance()),
                         float(surface.whitecapFraction()),
                         float(seaPixelAngle(scene.camera.vfov_deg, scene.camera.height)));
  gl_.ProgramUniform4fv(p, gl_.GetUniformLocation(p, "u_sea"), 1, &params.x);
  gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_foam_steepness"),
                       float(surface.foamSteepness()));
  setUniform3(gl_, p, "u_sea_body", waterBodyColour(sea.clarity) * scene.sun.colour);
  setUniform3(gl_, p, "u_sea_sun", sunDirection(scene.sun));
  setUniform3(gl_, p, "u_sun_colour", scene.sun.colour);
  setUniform3(gl_, p, "u_probe_right", sea_probe_right_);
  setUniform3(gl_, p, "u_probe_up", sea_probe_up_);
  setUniform3(gl_, p, "u_probe_forward", sea_probe_forward_);
  gl_.BindTextureUnit(6, sea_probe_texture_.get());
}

void GlRenderer::drawView(const ViewPlan& view, const RenderSettings& settings,
                          TargetFormat format) {
  const Camera& camera = view.camera();
  prepareTarget(camera.width, camera.height, format);
  const bool targets = drawTargetsPass(view);
  beginView(camera, format);
  // The eye deep in a cloud: its veil hides what lies behind to within the per-pixel pass's
  // opacity cut, so no sky or cloud pass is drawn under it (MODEL.md section 4).
  const Veil veil = ellipsoids_.veil(view, settings);
  if (veil.opacity >= kOpaqueCoverage) {
    const GLfloat nothing[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    gl_.ClearNamedFramebufferfv(framebuffer_.get(), GL_COLOR, 0, nothing);
    return endView(veil);
  }
  LayerSides sides = layerSides(view, settings);
  prepareClipmaps(view, settings, sides);
  drawBands(view, settings, sides, cloudOrder(view, sides), veil, targets);
  endView(veil);
}

bool GlRenderer::drawTargetsPass(const ViewPlan& view) {
  // Opaque targets first, into their own colour and distance textures.
  const Scene& scene = *view.scene;
  if (scene.targets.empty()) return false;
  bool targets = false;
  {
    GpuPassScope pass(timer_, GpuPass::kTargets);
    targets = targets_.draw(scene, sunlight_);
  }
  if (targets) stats_.target_passes = int(scene.targets.size());
  return targets;
}

void GlRenderer::beginView(const Camera& camera, TargetFormat format) {
  gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffer_.get());
  gl_.Viewport(0, 0, camera.width, camera.height);
  gl_.BindVertexArray(vertex_array_.get());
  if (format == TargetFormat::kSrgb8)
    gl_.Enable(GL_FRAMEBUFFER_SRGB);  // blend in linear, store sRGB
  else
    gl_.Disable(GL_FRAMEBUFFER_SRGB);
  ++frame_;
  ellipsoids_.beginFrame(stats_, timer_, continuous_view_);
  automata_.beginFrame(stats_);
  clipmaps_.beginFrame();
}

void GlRenderer::endView(const Veil& veil) {
  if (veil.opacity > 0.0) {
    GpuPassScope pass(timer_, GpuPass::kVeil);
    ellipsoids_.drawVeil(veil);
  }
  gl_.Disable(GL_BLEND);
  ellipsoids_.endFrame();
  automata_.endFrame();
  clipmaps_.endFrame();
  // Of the layer textures no layer of this frame drew, those without a baked table go,
  // and of the baked, all but the kKeptTextures drawn most recently.
  std::erase_if(textures_, [&](const auto& entry) {
    return entry.second.last_frame != frame_ && !entry.second.texture;
  });
  keepMostRecent(textures_, kKeptTextures, frame_);
}

GlRenderer::LayerSides GlRenderer::layerSides(const ViewPlan& view,
                                              const RenderSettings& settings) {
  // A ray meets only the layers on one side of the camera: above it from the highest down,
  // below it from the lowest up. Those orders are back to front.
  const Scene& scene = *view.scene;
  const Camera& camera = scene.camera;
  const double z = camera.position.z;
  LayerSides sides;
  for (const CloudLayer& layer : scene.layers) {
    if (layer.altitude_m == z) continue;  // seen edge-on: covers no pixel
    CachedTexture& texture = cachedTexture(layer.texture, settings);
    (layer.altitude_m > z ? sides.above : sides.below)
        .push_back({&layer, &texture, layerKind(*texture.source, settings), {}});
  }
  std::sort(sides.above.begin(), sides.above.end(), [](const LayerSlot& a, const LayerSlot& b) {
    return a.layer->altitude_m > b.layer->altitude_m;
  });
  std::sort(sides.below.begin(), sides.below.end(), [](const LayerSlot& a, const LayerSlot& b) {
    return a.layer->altitude_m < b.layer->altitude_m;
  });
  // The casting planes, taken before the hidden layers leave the passes: a layer behind a
  // full deck still shadows what lies below it.
  casters_.clear();
  for (std::size_t index :
       settings.plane_shadows ? castingPlanes(scene) : std::vector<std::size_t>{})
    for (const std::vector<LayerSlot>* side : {&sides.above, &sides.below})
      for (const LayerSlot& slot : *side)
        if (slot.layer == &scene.layers[index]) casters_.push_back(slot);
  // A layer that no texture value leaves translucent (opaque at T = 0, the least T, since
  // eq. 9's translucence falls as T rises; no region or far cover to thin it: a full deck)
  // hides every layer beyond it on its side of the camera, exactly. Those are left out of the
  // passes: the sky shader's own skip behind an opaque surface saves nothing on llvmpipe,
  // which runs both sides of a branch.
  auto opaqueEverywhere = [](const LayerSlot& slot) {
    const CloudLayer& l = *slot.layer;
    return !layerHasRegion(l) && skyPlaneTranslucence(0.0, l.threshold, l.transition) == 0.0;
  };
  for (std::vector<LayerSlot>* side : {&sides.above, &sides.below})  // each is nearest last
    for (std::size_t k = side->size(); k-- > 1;)
      if (opaqueEverywhere((*side)[k])) {
        side->erase(side->begin(), side->begin() + std::ptrdiff_t(k));
        break;
      }
  for (const std::vector<LayerSlot>* side : {&sides.above, &sides.below})
    for (const LayerSlot& slot : *side)
      if (const GardnerTexture* g = slot.texture->source->gardner()) {
        stats_.layer_terms +=
            layerTermsAtMost(*slot.layer, *slot.texture->source, camera, settings.term_filter);
        stats_.layer_terms_total += g->terms();
      }
  return sides;
}

void GlRenderer::prepareClipmaps(const ViewPlan& view, const RenderSettings& settings,
                                 LayerSides& sides) {
  // The clipmaps of the layers that read one, brought to this camera before any pass. `auto`
  // fills a layer's clipmap coarsest ring first, the coarsest whole and then about a frame's
  // pixels of texels a frame: a continuous view from its first frame, reading the rings filled so
  // far; other renders from the second render from the same place, reading the sines until it
  // is complete (so a single render never pays for one). `baked` fills it at once.
  const Camera& camera = view.camera();
  bool baked = false;
  const bool continuous = !continuous_view_.empty();
  const bool wait = settings.texture_evaluation == TextureEvaluation::kAuto && !continuous;
  const std::int64_t budget = settings.texture_evaluation == TextureEvaluation::kAuto
                                  ? std::int64_t(camera.width) * camera.height
                                  : std::numeric_limits<std::int64_t>::max();
  auto prepare = [&](LayerSlot& slot) {
    const LayerTexture& t = *slot.texture->source;
    const glm::dvec2 eye =
        glm::dvec2(camera.position) - t.driftOffset(view.scene->time_s, slot.layer->texture);
    GpuPassScope pass(timer_, GpuPass::kClipmaps);
    StageClock clock(stats_.times.cpu(CpuStage::kUploads));
    slot.clipmap = clipmaps_.prepare(slot.texture->key, *t.gardner(), eye,
                                     LayerClipmaps::sizeFor(camera.height), budget, wait, stats_);
    if (!(continuous ? slot.clipmap.usable() : slot.clipmap.complete()))
      slot.kind = LayerKind::kProceduralGardner;
    baked = true;
  };
  for (std::vector<LayerSlot>* side : {&sides.above, &sides.below})
    for (LayerSlot& slot : *side)
      if (slot.kind == LayerKind::kClipmapGardner) prepare(slot);
  // A casting plane reads the clipmap its drawn slot filled. One left out of the passes (behind
  // a full deck) fills its own rather than sum its sines for every receiving pixel.
  for (LayerSlot& caster : casters_) {
    if (caster.kind != LayerKind::kClipmapGardner) continue;
    const LayerSlot* drawn = nullptr;
    for (const std::vector<LayerSlot>* side : {&sides.above, &sides.below})
      for (const LayerSlot& slot : *side)
        if (slot.layer == caster.layer) drawn = &slot;
    if (drawn)
      caster = *drawn;
    else
      prepare(caster);
  }
  if (baked) {
    gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffer_.get());
    gl_.Viewport(0, 0, camera.width, camera.height);
  }
}

std::vector<GlRenderer::CloudEntry> GlRenderer::cloudOrder(const ViewPlan& view,
                                                           const LayerSides& sides) {
  // Interleave clouds with the layers (docs/MODEL.md, "Compositing order"). On each side of
  // the camera, band b holds what lies beyond the b nearest layers of that side and before
  // the next; surfaces in band b are drawn after the layers beyond them and before the b
  // layers in front. A cloud whose altitudes span several bands is drawn once per band,
  // each time keeping only its surfaces in that band, so a layer cuts through it. Clouds
  // in one band go back to front by distance.
  const Camera& camera = view.camera();
  const CloudBands bands(sides.above, sides.below, camera.position.z);
  std::vector<CloudEntry> clouds;
  auto addCloud = [&](bool automaton, std::size_t index, glm::dvec3 centre, double z_lo,
                      double z_hi) {
    const double distance = glm::length(centre - camera.position);
    const std::vector<CloudBands::Piece> pieces = bands.pieces(z_lo, z_hi);
    for (const CloudBands::Piece& piece : pieces)
      clouds.push_back({automaton, index, piece.band, distance, piece.window});
  };
  // The plan left out the clouds wholly outside the view frustum.
  stats_.ellipsoids_culled += view.ellipsoids_culled;
  for (std::size_t i : view.in_view) {
    const EllipsoidCloud& cloud = view.cloud(i);
    glm::dvec3 centre(0.0);
    for (const Ellipsoid& e : cloud.ellipsoids) centre += e.centre;
    centre /= double(cloud.ellipsoids.size());
    const auto [z_lo, z_hi] = cloudVerticalExtent(cloud);
    addCloud(false, i, centre, z_lo, z_hi);
  }
  const std::vector<AutomatonCloudView>& automata = view.scene->automata;
  for (std::size_t i = 0; i < automata.size(); ++i) {
    const glm::dvec3 lo = automata[i].lowerBound(), hi = automata[i].upperBound();
    addCloud(true, i, 0.5 * (lo + hi), lo.z, hi.z);
  }
  std::sort(clouds.begin(), clouds.end(), [](const CloudEntry& a, const CloudEntry& b) {
    return a.band != b.band ? a.band > b.band : a.distance > b.distance;
  });
  return clouds;
}

void GlRenderer::drawBands(const ViewPlan& view, const RenderSettings& settings,
                           const LayerSides& sides, const std::vector<CloudEntry>& clouds,
                           const Veil& veil, bool targets) {
  const Scene& scene = *view.scene;
  const std::vector<LayerSlot>&above = sides.above, &below = sides.below;
  std::vector<LayerSlot> pending_above, pending_below;
  bool background_pending = true;
  auto flushSky = [&] {
    if (!background_pending && pending_above.empty() && pending_below.empty()) return;
    {
      GpuPassScope pass(timer_, GpuPass::kSky);
      drawSkyGroup(scene, settings, pending_above, pending_below, background_pending, targets);
    }
    background_pending = false;
    pending_above.clear();
    pending_below.clear();
  };
  const Camera& camera = scene.camera;
  const PassTarget frame{framebuffer_.get(), camera.width, camera.height, 1.0 - veil.opacity};
  const int top_band = int(std::max(
      {above.size(), below.size(), clouds.empty() ? std::size_t(0) : std::size_t(clouds[0].band)}));
  auto next_cloud = clouds.begin();
  for (int band = top_band; band >= 0; --band) {
    if (next_cloud != clouds.end() && next_cloud->band == band) flushSky();
    // Automata one by one; each run of ellipsoid clouds between them with one window in one
    // call, which batches the clouds that look alike.
    while (next_cloud != clouds.end() && next_cloud->band == band) {
      if (next_cloud->automaton) {
        GpuPassScope pass(timer_, GpuPass::kAutomata);
        automata_.drawCloud(scene, next_cloud->index, settings, targets, next_cloud->window);
        ++next_cloud;
        continue;
      }
      std::vector<std::size_t> run;
      const AltitudeBand window = next_cloud->window;
      for (; next_cloud != clouds.end() && next_cloud->band == band && !next_cloud->automaton &&
             next_cloud->window.slabs == window.slabs;
           ++next_cloud)
        run.push_back(next_cloud->index);
      GpuPassScope pass(timer_, GpuPass::kHeaps);
      ellipsoids_.drawClouds(view, run, settings, frame, targets, window);
    }
    // Then the layers of rank band - 1 (rank 0 is nearest the camera) on both sides.
    if (band >= 1) {
      if (std::size_t(band) <= above.size()) pending_above.push_back(above[above.size() - band]);
      if (std::size_t(band) <= below.size()) pending_below.push_back(below[below.size() - band]);
    }
  }
  flushSky();
}

}  // namespace nephele
