#pragma once
// Periodic scalar tables: seeded noise sources (McReynolds and Blythe's diamond-square,
// Elinas' Perlin noise) and Gardner's texture baked for texture hardware.
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "world/textures/gardner_texture.h"

namespace nephele {

// Index i wrapped into [0, n).
int wrapIndex(int i, int n);
// Perlin's quintic fade, 6t^5 - 15t^4 + 10t^3.
double smootherstep(double t);
// Rescales values linearly onto [0, 1] (all 0.5 when they are all equal).
void normaliseToUnit(std::vector<float>& values);

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

// Gardner's texture over one period on a size x size grid of texel centres (what texture
// hardware samples instead of the sines), truncated to `terms` terms and, from the same
// partial sums, to one term fewer (at least 0); k stays as for all n terms.
struct GardnerTruncations {
  TextureTable with_terms;
  TextureTable one_fewer;
};
GardnerTruncations bakeGardner(const GardnerTexture& texture, int size, int terms);

// Base size of a baked Gardner texture: `texels_per_cycle` texels per cycle of the highest
// term (2^n cycles per period), halved as needed to stay within kMaxBakeSize.
inline constexpr int kMaxBakeSize = 2048;
int gardnerBakeSize(int terms, int texels_per_cycle);

}  // namespace nephele
