#pragma once
// Textures of ellipsoid clouds: Gardner's texture with solid phases, or seeded periodic
// Perlin noise in three dimensions (Elinas), evaluated at world points.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "world/textures/gardner_texture.h"

namespace nephele {

// A size^3 grid that repeats along all three axes, `channels` values per texel.
struct VolumeTable {
  int size = 0;
  std::vector<float> values;  // channels fastest, then x, then y, then z
  int channels = 1;

  float at(int x, int y, int z, int channel = 0) const;  // wraps
  // Trilinear sample at uvw in periods, texel centres at (i + 0.5) / size.
  double sampleTrilinear(glm::dvec3 uvw) const;
};

// Part of Gardner's solid sums (MODEL.md section 2): SX - T0 and SY - T0 of terms
// [first, first + count) only, two channels at size^3 texel centres over the period of term
// `first` and those above it, a 2^first-th of the texture's (4 pi / FX1 in X and Z, 4 pi / FY1
// in Y), over which they all repeat. T is k max(T0 + the parts' SX, 0) max(T0 + ..., 0).
VolumeTable bakeGardnerSums(const GardnerTexture& texture, int size, int first, int count);
// The same a row at a time: `row(z, y, sx, sy)` receives the size values of SX - T0 and of
// SY - T0 along x at (y, z), valid during the call. For a caller that stores the table in
// its own format (the GL's half floats), with no float table between.
using GardnerSumRow =
    std::function<void(std::size_t z, std::size_t y, const float* sx, const float* sy)>;
void bakeGardnerSums(const GardnerTexture& texture, int size, int first, int count,
                     const GardnerSumRow& row);

// Periodic 3D gradient noise: `octaves` octaves, the first with `cells` lattice cells per
// period, each next one with twice the cells and `persistence` times the amplitude.
// Normalised to [0, 1].
VolumeTable perlinVolume(int size, int cells, int octaves, double persistence, std::uint64_t seed);

enum class SolidTextureSource { kGardner, kPerlin };

struct SolidTextureSpec {
  SolidTextureSource source = SolidTextureSource::kGardner;
  // Gardner: a period of 4 pi / 0.01 = 1257 m suits clouds of a few hundred metres.
  GardnerTextureParams gardner{5, 1.0e-2, 1.0e-2, 0.0, true, 0};
  double perlin_period_m = 1500.0;  // Perlin: one repeat of the table, metres, all axes
  int perlin_size_log2 = 6;         // table of 2^size_log2 texels a side
  int perlin_cells = 4;
  int perlin_octaves = 4;
  double perlin_persistence = 0.5;
  std::uint64_t seed = 0;
};

class SolidTexture {
 public:
  explicit SolidTexture(const SolidTextureSpec& spec);

  const SolidTextureSpec& spec() const { return spec_; }
  glm::dvec3 period() const;  // metres
  // Position inside one period, in periods [0, 1), of a world point (reduced in double).
  glm::dvec3 periodicCoordinate(glm::dvec3 world) const;
  // T at a world point: every Gardner term, or the trilinear Perlin table.
  double value(glm::dvec3 world) const;

  const GardnerTexture* gardner() const { return gardner_.get(); }  // null for Perlin
  const VolumeTable* volume() const { return volume_.get(); }       // null for Gardner

 private:
  SolidTextureSpec spec_;
  std::unique_ptr<GardnerTexture> gardner_;
  std::unique_ptr<VolumeTable> volume_;
};

}  // namespace nephele
