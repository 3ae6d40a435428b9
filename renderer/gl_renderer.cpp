#include "renderer/gl_renderer.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <vector>

#include "renderer/sky_shaders.h"
#include "world/check.h"
#include "world/layer_texture.h"
#include "world/texture_table.h"

namespace nephele {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

glm::vec3 toFloat(glm::dvec3 v) {
  return glm::vec3(v);
}

// The part of the screen square [-1, 1]^2 where a * x + b * y + c >= 0, as a convex polygon
// (Sutherland-Hodgman against one line). Empty when nothing is left.
std::vector<glm::vec2> clipScreenToHalfPlane(double a, double b, double c) {
  const glm::dvec2 square[4] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  std::vector<glm::vec2> out;
  for (int i = 0; i < 4; ++i) {
    const glm::dvec2 p = square[i], q = square[(i + 1) % 4];
    const double fp = a * p.x + b * p.y + c, fq = a * q.x + b * q.y + c;
    if (fp >= 0.0) out.emplace_back(p);
    if ((fp >= 0.0) != (fq >= 0.0)) out.emplace_back(p + (q - p) * (fp / (fp - fq)));
  }
  return out;
}

// Cache key: every parameter of a layer texture and the settings its GPU form depends on.
std::string textureKey(const LayerTextureSpec& spec, const RenderSettings& settings) {
  std::ostringstream key;
  key.precision(17);
  key << int(spec.source) << '/' << spec.seed << '/' << spec.drift_velocity.x << '/'
      << spec.drift_velocity.y << '/';
  if (spec.source == TextureSource::kGardner) {
    const GardnerTextureParams& g = spec.gardner;
    key << g.terms << '/' << g.fx1 << '/' << g.fy1 << '/' << g.t0 << '/' << g.seeded_phases << '/'
        << settings.bake_texels_per_cycle;
  } else {
    const NoiseTableParams& t = spec.table;
    key << t.tile_size_m.x << '/' << t.tile_size_m.y << '/' << t.size_log2 << '/' << t.roughness
        << '/' << t.cells << '/' << t.octaves << '/' << t.persistence;
  }
  return key.str();
}

void uploadLevels(const GlApi& gl, GLuint texture, const std::vector<TextureTable>& levels) {
  gl.TextureStorage2D(texture, GLsizei(levels.size()), GL_R16, levels[0].width, levels[0].height);
  for (std::size_t level = 0; level < levels.size(); ++level)
    gl.TextureSubImage2D(texture, GLint(level), 0, 0, levels[level].width, levels[level].height,
                         GL_RED, GL_FLOAT, levels[level].values.data());
}

}  // namespace

GlRenderer::GlRenderer(const GlPlatform& platform)
    : gl_(platform.gl()),
      vertex_array_(createVertexArray(gl_)),
      framebuffer_(createFramebuffer(gl_)) {}

GlRenderer::~GlRenderer() = default;

FloatImage GlRenderer::renderFloat(const Scene& scene, const RenderSettings& settings) {
  drawFrame(scene, settings, TargetFormat::kFloat);
  const int w = scene.camera.width, h = scene.camera.height;
  FloatImage image{w, h, std::vector<float>(std::size_t(w) * h * 4)};
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
  gl_.ReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, image.rgba.data());
  // GL rows run bottom-up; FloatImage rows run top-down.
  const std::size_t row = std::size_t(w) * 4;
  for (int y = 0; y < h / 2; ++y)
    std::swap_ranges(image.rgba.begin() + y * row, image.rgba.begin() + (y + 1) * row,
                     image.rgba.begin() + (h - 1 - y) * row);
  return image;
}

Srgb8Image GlRenderer::renderSrgb8(const Scene& scene, const RenderSettings& settings) {
  drawFrame(scene, settings, TargetFormat::kSrgb8);
  const int w = scene.camera.width, h = scene.camera.height;
  Srgb8Image image{w, h, /*bottom_up=*/true, std::vector<std::uint8_t>(std::size_t(w) * h * 4)};
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
  gl_.ReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, image.rgba.data());
  return image;
}

void GlRenderer::prepareTarget(int width, int height, TargetFormat format) {
  if (colour_buffer_ && width == target_width_ && height == target_height_ &&
      format == target_format_)
    return;
  colour_buffer_ = createRenderbuffer(gl_);
  gl_.NamedRenderbufferStorage(colour_buffer_.get(),
                               format == TargetFormat::kFloat ? GL_RGBA32F : GL_SRGB8_ALPHA8, width,
                               height);
  gl_.NamedFramebufferRenderbuffer(framebuffer_.get(), GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER,
                                   colour_buffer_.get());
  const GLenum status = gl_.CheckNamedFramebufferStatus(framebuffer_.get(), GL_FRAMEBUFFER);
  NEPHELE_CHECK(status == GL_FRAMEBUFFER_COMPLETE,
                "framebuffer " << width << "x" << height << " status 0x" << std::hex << status);
  target_width_ = width;
  target_height_ = height;
  target_format_ = format;
}

GLuint GlRenderer::program(const std::string& key, const std::string& fragment_source) {
  auto found = programs_.find(key);
  if (found != programs_.end()) return found->second.get();
  std::string error;
  GlObject compiled = createProgram(gl_, polygonVertexSource(), fragment_source, error);
  NEPHELE_CHECK(compiled, key << ": " << error);
  return programs_.emplace(key, std::move(compiled)).first->second.get();
}

void GlRenderer::setViewUniforms(GLuint p, const Scene& scene) {
  const Camera& camera = scene.camera;
  const ViewBasis basis = viewBasis(camera);
  auto uniform3 = [&](const char* name, glm::dvec3 v) {
    const glm::vec3 f = toFloat(v);
    gl_.ProgramUniform3fv(p, gl_.GetUniformLocation(p, name), 1, &f.x);
  };
  uniform3("u_right", basis.right * basis.tan_half_vfov * basis.aspect);
  uniform3("u_up", basis.up * basis.tan_half_vfov);
  uniform3("u_forward", basis.forward);
  const glm::vec2 viewport(camera.width, camera.height);
  gl_.ProgramUniform2fv(p, gl_.GetUniformLocation(p, "u_viewport"), 1, &viewport.x);
  gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_camera_z"), float(camera.position.z));
  if (scene.fog) {
    gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_fog_top"), float(scene.fog->top_m));
    gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_fog_sigma"),
                         float(fogExtinction(*scene.fog)));
    uniform3("u_fog_colour", scene.fog->colour);
  }
}

GlRenderer::CachedTexture& GlRenderer::cachedTexture(const LayerTextureSpec& spec,
                                                     const RenderSettings& settings) {
  auto [entry, inserted] = textures_.try_emplace(textureKey(spec, settings));
  if (inserted) entry->second.source = std::make_unique<LayerTexture>(spec);
  entry->second.used = true;
  return entry->second;
}

GLuint GlRenderer::gpuTexture(CachedTexture& cached, const RenderSettings& settings) {
  if (cached.texture) return cached.texture.get();
  cached.texture = createTexture(gl_, GL_TEXTURE_2D);
  const GLuint t = cached.texture.get();
  if (const GardnerTexture* gardner = cached.source->gardner()) {
    uploadLevels(gl_, t, bakeGardnerLevels(*gardner, settings.bake_texels_per_cycle));
  } else {
    const TextureTable& table = *cached.source->table();
    const int levels = int(std::log2(std::max(table.width, table.height))) + 1;
    gl_.TextureStorage2D(t, levels, GL_R16, table.width, table.height);
    gl_.TextureSubImage2D(t, 0, 0, 0, table.width, table.height, GL_RED, GL_FLOAT,
                          table.values.data());
    gl_.GenerateTextureMipmap(t);
  }
  gl_.TextureParameteri(t, GL_TEXTURE_WRAP_S, GL_REPEAT);
  gl_.TextureParameteri(t, GL_TEXTURE_WRAP_T, GL_REPEAT);
  gl_.TextureParameteri(t, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  gl_.TextureParameteri(t, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  return t;
}

void GlRenderer::drawLayer(const Scene& scene, const CloudLayer& layer,
                           const RenderSettings& settings) {
  const Camera& camera = scene.camera;
  const double height = layer.altitude_m - camera.position.z;
  const ViewBasis basis = viewBasis(camera);
  // Only pixels whose ray climbs towards the plane (or descends to it) can see it: draw the
  // screen region where sign(height) * ray.z >= 0, widened by two pixels; the shader
  // discards the rest of the margin.
  const double side = height > 0.0 ? 1.0 : -1.0;
  const double a = side * basis.right.z * basis.tan_half_vfov * basis.aspect;
  const double b = side * basis.up.z * basis.tan_half_vfov;
  const double margin = std::abs(a) * 4.0 / camera.width + std::abs(b) * 4.0 / camera.height;
  const std::vector<glm::vec2> polygon =
      clipScreenToHalfPlane(a, b, side * basis.forward.z + margin);
  if (polygon.size() < 3) return;

  CachedTexture& cached = cachedTexture(layer.texture, settings);
  const LayerTexture& texture = *cached.source;
  LayerShaderVariant variant;
  variant.fog = scene.fog.has_value();
  variant.specular = layer.shading.specular > 0.0;
  variant.term_filter = settings.term_filter;
  if (!texture.gardner())
    variant.texture = LayerShaderVariant::Texture::kTable;
  else if (settings.texture_evaluation == TextureEvaluation::kProcedural)
    variant.texture = LayerShaderVariant::Texture::kProceduralGardner;
  const GLuint p = program(variant.key(), layerFragmentSource(variant));
  gl_.UseProgram(p);
  setViewUniforms(p, scene);

  auto location = [&](const char* name) { return gl_.GetUniformLocation(p, name); };
  auto uniform3 = [&](const char* name, glm::dvec3 v) {
    const glm::vec3 f = toFloat(v);
    gl_.ProgramUniform3fv(p, location(name), 1, &f.x);
  };
  gl_.ProgramUniform1f(p, location("u_height"), float(height));
  uniform3("u_colour", layer.colour * scene.sun.colour);
  uniform3("u_to_sun", sunDirection(scene.sun));
  const glm::vec4 shading(layer.shading.ambient, layer.shading.texture_fraction,
                          layer.shading.specular, layer.shading.shininess);
  gl_.ProgramUniform4fv(p, location("u_shading"), 1, &shading.x);
  gl_.ProgramUniform1f(p, location("u_threshold"), float(layer.threshold));
  gl_.ProgramUniform1f(p, location("u_transition"), float(layer.transition));

  // SPEC precision rule: the texture's local origin is the point under the camera, reduced
  // modulo the period in double; the shader only sees offsets from it.
  const glm::dvec2 period = texture.period();
  const glm::dvec2 origin_uv =
      texture.periodicCoordinate({camera.position.x, camera.position.y}, scene.time_s);
  const glm::vec2 origin_f(origin_uv), inv_period(1.0 / period);
  gl_.ProgramUniform2fv(p, location("u_origin"), 1, &origin_f.x);
  gl_.ProgramUniform2fv(p, location("u_inv_period"), 1, &inv_period.x);

  if (const GardnerTexture* g = texture.gardner()) {
    gl_.ProgramUniform1f(p, location("u_terms"), float(g->terms()));
    if (variant.texture == LayerShaderVariant::Texture::kProceduralGardner) {
      const glm::dvec2 origin = origin_uv * period;  // metres inside one period
      float fx[8], fy[8], amp[8], phx[8], phy[8], half_x[8], half_y[8];
      for (int i = 0; i < g->terms(); ++i) {
        fx[i] = float(g->frequencyX(i));
        fy[i] = float(g->frequencyY(i));
        amp[i] = float(g->amplitude(i));
        phx[i] = float(wrapPeriodic(g->frequencyX(i) * origin.x + g->phaseX(i), kTwoPi));
        phy[i] = float(wrapPeriodic(g->frequencyY(i) * origin.y + g->phaseY(i), kTwoPi));
        half_x[i] = float(wrapPeriodic(0.5 * g->frequencyX(i) * origin.x, kTwoPi));
        half_y[i] = float(wrapPeriodic(0.5 * g->frequencyY(i) * origin.y, kTwoPi));
      }
      const GLsizei n = g->terms();
      gl_.ProgramUniform1fv(p, location("u_fx"), n, fx);
      gl_.ProgramUniform1fv(p, location("u_fy"), n, fy);
      gl_.ProgramUniform1fv(p, location("u_amplitude"), n, amp);
      gl_.ProgramUniform1fv(p, location("u_phase_x"), n, phx);
      gl_.ProgramUniform1fv(p, location("u_phase_y"), n, phy);
      gl_.ProgramUniform1fv(p, location("u_half_phase_x"), n, half_x);
      gl_.ProgramUniform1fv(p, location("u_half_phase_y"), n, half_y);
      gl_.ProgramUniform1f(p, location("u_t0"), float(g->params().t0));
      gl_.ProgramUniform1f(p, location("u_k"), float(g->normalisation()));
    }
  }
  if (variant.texture != LayerShaderVariant::Texture::kProceduralGardner) {
    gl_.BindTextureUnit(0, gpuTexture(cached, settings));
    gl_.ProgramUniform1i(p, location("u_table"), 0);
  }
  gl_.ProgramUniform2fv(p, location("u_polygon"), GLsizei(polygon.size()), &polygon[0].x);
  gl_.DrawArrays(GL_TRIANGLE_FAN, 0, GLsizei(polygon.size()));
}

void GlRenderer::drawFrame(const Scene& scene, const RenderSettings& settings,
                           TargetFormat format) {
  const Camera& camera = scene.camera;
  prepareTarget(camera.width, camera.height, format);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffer_.get());
  gl_.Viewport(0, 0, camera.width, camera.height);
  gl_.BindVertexArray(vertex_array_.get());
  if (format == TargetFormat::kSrgb8)
    gl_.Enable(GL_FRAMEBUFFER_SRGB);  // blend in linear, store sRGB
  else
    gl_.Disable(GL_FRAMEBUFFER_SRGB);
  for (auto& [key, cached] : textures_) cached.used = false;

  // Background: sky gradient and ground, coverage 0.
  gl_.Disable(GL_BLEND);
  const GLuint bg = program(scene.fog ? "background/fog" : "background",
                            backgroundFragmentSource(scene.fog.has_value()));
  gl_.UseProgram(bg);
  setViewUniforms(bg, scene);
  auto uniform3 = [&](const char* name, glm::dvec3 v) {
    const glm::vec3 f = toFloat(v);
    gl_.ProgramUniform3fv(bg, gl_.GetUniformLocation(bg, name), 1, &f.x);
  };
  uniform3("u_zenith", scene.sky.zenith);
  uniform3("u_horizon", scene.sky.horizon);
  uniform3("u_ground", scene.sky.ground);
  const glm::vec2 screen[4] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  gl_.ProgramUniform2fv(bg, gl_.GetUniformLocation(bg, "u_polygon"), 4, &screen[0].x);
  gl_.DrawArrays(GL_TRIANGLE_FAN, 0, 4);

  // Layers back to front: a ray meets only the layers on one side of the camera, farthest
  // first, so layers above draw from the highest down and layers below from the lowest up.
  std::vector<const CloudLayer*> order;
  for (const CloudLayer& layer : scene.layers)
    if (layer.altitude_m != camera.position.z) order.push_back(&layer);
  const double z = camera.position.z;
  std::sort(order.begin(), order.end(), [z](const CloudLayer* a, const CloudLayer* b) {
    return std::abs(a->altitude_m - z) > std::abs(b->altitude_m - z);
  });
  gl_.Enable(GL_BLEND);
  // Colour: alpha C + (1 - alpha) C_behind; coverage: 1 - product of TR.
  gl_.BlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  for (const CloudLayer* layer : order) drawLayer(scene, *layer, settings);
  gl_.Disable(GL_BLEND);

  std::erase_if(textures_, [](const auto& entry) { return !entry.second.used; });
}

}  // namespace nephele
