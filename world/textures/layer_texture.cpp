#include "world/textures/layer_texture.h"

#include <cmath>

namespace nephele {

std::string_view textureSourceName(TextureSource source) {
  switch (source) {
    case TextureSource::kGardner:
      return "gardner";
    case TextureSource::kPerlin:
      return "perlin";
    case TextureSource::kDiamondSquare:
      return "diamond-square";
  }
  return "?";
}

LayerTexture::LayerTexture(const LayerTextureSpec& spec) : spec_(spec) {
  const NoiseTableParams& t = spec_.table;
  switch (spec_.source) {
    case TextureSource::kGardner: {
      GardnerTextureParams params = spec_.gardner;
      params.seed = spec_.seed;
      gardner_ = std::make_unique<GardnerTexture>(params);
      break;
    }
    case TextureSource::kPerlin:
      table_ = std::make_unique<TextureTable>(
          perlinNoise(1 << t.size_log2, t.cells, t.octaves, t.persistence, spec_.seed));
      break;
    case TextureSource::kDiamondSquare:
      table_ = std::make_unique<TextureTable>(diamondSquare(t.size_log2, t.roughness, spec_.seed));
      break;
  }
}

glm::dvec2 LayerTexture::period() const {
  return gardner_ ? gardner_->period() : spec_.table.tile_size_m;
}

glm::dvec2 LayerTexture::driftOffset(double time_s) const {
  return driftOffset(time_s, spec_);
}

glm::dvec2 LayerTexture::driftOffset(double time_s, const LayerTextureSpec& motion) const {
  const glm::dvec2 velocity = motion.drift_velocity, offset = motion.drift_offset_m;
  // Without a period there is nothing to wrap by; double keeps a drift of 10^7 m to 2 nm.
  if (!periodic()) return offset + velocity * time_s;
  const glm::dvec2 p = period();
  // Reduce time modulo the time one period takes to pass, so velocity * time stays exact
  // after hours of drift.
  auto axis = [time_s](double velocity, double period_m) {
    if (velocity == 0.0) return 0.0;
    const double time_per_period = period_m / std::abs(velocity);
    return wrapPeriodic(velocity * wrapPeriodic(time_s, time_per_period), period_m);
  };
  return {wrapPeriodic(axis(velocity.x, p.x) + offset.x, p.x),
          wrapPeriodic(axis(velocity.y, p.y) + offset.y, p.y)};
}

glm::dvec2 LayerTexture::periodicCoordinate(glm::dvec2 world_xy, double time_s) const {
  return periodicCoordinate(world_xy, time_s, spec_);
}

glm::dvec2 LayerTexture::periodicCoordinate(glm::dvec2 world_xy, double time_s,
                                            const LayerTextureSpec& motion) const {
  const glm::dvec2 p = period();
  const glm::dvec2 shifted = world_xy - driftOffset(time_s, motion);
  return {wrapPeriodic(shifted.x, p.x) / p.x, wrapPeriodic(shifted.y, p.y) / p.y};
}

double LayerTexture::value(glm::dvec2 world_xy, double time_s) const {
  if (!periodic()) return gardner_->planar(world_xy - driftOffset(time_s));
  const glm::dvec2 uv = periodicCoordinate(world_xy, time_s);
  if (gardner_) return gardner_->planar(uv * period());
  return table_->sampleBilinear(uv);
}

}  // namespace nephele
