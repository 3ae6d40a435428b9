#pragma once
// The texture of a cloud layer: one of three seeded sources, drifting with the wind.
#include <cstdint>
#include <memory>
#include <string_view>

#include <glm/glm.hpp>

#include "world/textures/gardner_texture.h"
#include "world/textures/texture_table.h"

namespace nephele {

enum class TextureSource { kGardner, kPerlin, kDiamondSquare };

std::string_view textureSourceName(TextureSource source);

// Parameters of the tabulated sources (Perlin, diamond-square).
struct NoiseTableParams {
  glm::dvec2 tile_size_m{20000.0, 20000.0};  // one table repeat, metres
  int size_log2 = 9;                         // table of 2^size_log2 texels a side
  double roughness = 1.0;                    // diamond-square: displacement decay 2^-roughness
  int cells = 4;                             // Perlin: lattice cells per tile, first octave
  int octaves = 6;                           // Perlin octaves
  double persistence = 0.5;                  // Perlin: amplitude ratio between octaves
};

struct LayerTextureSpec {
  TextureSource source = TextureSource::kGardner;
  GardnerTextureParams gardner;
  NoiseTableParams table;
  std::uint64_t seed = 0;               // seeds phases and noise
  glm::dvec2 drift_velocity{0.0, 0.0};  // metres per second, the layer moving with the wind
  // Drift at time 0, metres: keeps the layer where it was when its wind changes mid-run.
  glm::dvec2 drift_offset_m{0.0, 0.0};
};

// An evaluable layer texture: T(X, Y) in [0, 1] at world coordinates and a time.
class LayerTexture {
 public:
  explicit LayerTexture(const LayerTextureSpec& spec);

  const LayerTextureSpec& spec() const { return spec_; }
  // Repeat lengths in metres (for a rotated Gardner texture, which never repeats, its scale).
  glm::dvec2 period() const;
  // False for a Gardner texture whose terms are rotated (GardnerTextureParams::rotation_deg).
  bool periodic() const { return !gardner_ || gardner_->periodic(); }
  // Drift offset at time t in double, wrapped into [0, period) when the texture is periodic
  // (MODEL.md section 2).
  glm::dvec2 driftOffset(double time_s) const;
  // Position inside one period, in periods [0, 1), of world point p at time t (periodic
  // textures only).
  glm::dvec2 periodicCoordinate(glm::dvec2 world_xy, double time_s) const;
  // The same with the drift (velocity and offset) of `motion`: a renderer keeps one texture
  // for every layer that differs from it only in drift.
  glm::dvec2 driftOffset(double time_s, const LayerTextureSpec& motion) const;
  glm::dvec2 periodicCoordinate(glm::dvec2 world_xy, double time_s,
                                const LayerTextureSpec& motion) const;
  // T with every term (the reference's evaluation).
  double value(glm::dvec2 world_xy, double time_s) const;

  const GardnerTexture* gardner() const { return gardner_.get(); }  // null for tables
  const TextureTable* table() const { return table_.get(); }        // null for Gardner

 private:
  LayerTextureSpec spec_;
  std::unique_ptr<GardnerTexture> gardner_;
  std::unique_ptr<TextureTable> table_;
};

}  // namespace nephele
