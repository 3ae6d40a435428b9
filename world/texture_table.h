#pragma once
// Periodic scalar tables: seeded noise sources (McReynolds and Blythe's diamond-square,
// Elinas' Perlin noise) and Gardner's texture baked for texture hardware.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "world/gardner_texture.h"

namespace nephele {

// A width x height grid of values in [0, 1] that repeats in both directions.
struct TextureTable {
  int width = 0;
  int height = 0;
  std::vector<float> values;  // row-major, row 0 at v = 0

  float at(int x, int y) const;  // wraps x and y
  // Bilinear sample at (u, v) in periods (1.0 = one whole table), texel centres at
  // (i + 0.5) / width as texture hardware places them.
  double sampleBilinear(glm::dvec2 uv) const;
};

// Diamond-square midpoint displacement on a periodic 2^size_log2 grid; each finer level's
// displacement is scaled by 2^-roughness. Normalised to [0, 1].
TextureTable diamondSquare(int size_log2, double roughness, std::uint64_t seed);

// Sum of `octaves` octaves of periodic gradient (Perlin) noise, the first with `cells`
// lattice cells per period, each next one with twice the cells and `persistence` times the
// amplitude. Sampled on a size x size grid and normalised to [0, 1].
TextureTable perlinNoise(int size, int cells, int octaves, double persistence, std::uint64_t seed);

// Gardner's texture over one period, baked as a mip chain: level l has (texels_per_cycle *
// 2^n) >> l texels a side and holds the truncation to max(n - l, 0) terms, so that each
// level has exactly `texels_per_cycle` texels per cycle of its highest term. Sampling at
// level n - c blends the truncations floor(c) and floor(c) + 1, which is the term fade.
// The base size is capped at kMaxBakeSize by lowering texels_per_cycle.
inline constexpr int kMaxBakeSize = 4096;
std::vector<TextureTable> bakeGardnerLevels(const GardnerTexture& texture, int texels_per_cycle);

}  // namespace nephele
