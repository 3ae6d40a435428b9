#include "renderer/gl/ellipsoid_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <future>
#include <sstream>

#include "image/image_encoding.h"
#include "renderer/gl/ellipsoid_internal.h"
#include "world/automaton/cloud_density.h"
#include "world/check.h"

// The clouds' textures: Gardner's sums baked into 3D tables, Perlin tables and the spotlight.
namespace nephele {

using namespace ellipsoid_detail;

namespace {

constexpr int kSpotlightSize = 64;

// The spec whose table a baked texture of `spec` is: the same texture at unit scale. Every
// Gardner term runs at 2^i cycles per period whatever the base frequencies (MODEL.md section
// 2), and a Perlin table is tiled over its period, so the table does not depend on the scale;
// baking it at a fixed one makes it a function of its key alone, not of which cloud asked first.
SolidTextureSpec bakedTableSpec(SolidTextureSpec spec) {
  spec.gardner.fx1 = spec.gardner.fy1 = 1.0;
  spec.perlin_period_m = 1.0;
  return spec;
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

}  // namespace

namespace ellipsoid_detail {

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

BakedSolidLayout bakedSolidLayout(const GardnerTexture& gardner) {
  const int n = gardner.terms(), coarse = n / 2;
  return {coarse, n - coarse, std::exp2(coarse)};
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

}  // namespace ellipsoid_detail

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

}  // namespace nephele
