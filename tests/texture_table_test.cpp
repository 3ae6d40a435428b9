#include "world/textures/texture_table.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace nephele {
namespace {

// Mean absolute difference between horizontally adjacent texels: across the wrap seam
// (last column to first) and inside the table. A periodic table shows no seam.
std::pair<double, double> seamAndInteriorSteps(const TextureTable& t) {
  double seam = 0.0, interior = 0.0;
  for (int y = 0; y < t.height; ++y) {
    seam += std::abs(t.at(t.width - 1, y) - t.at(0, y));
    for (int x = 0; x + 1 < t.width; ++x) interior += std::abs(t.at(x + 1, y) - t.at(x, y));
  }
  return {seam / t.height, interior / (double(t.height) * (t.width - 1))};
}

void expectUnitRange(const TextureTable& t) {
  const auto [lo, hi] = std::minmax_element(t.values.begin(), t.values.end());
  EXPECT_FLOAT_EQ(*lo, 0.0f);
  EXPECT_FLOAT_EQ(*hi, 1.0f);
}

// `a` and `same_seed` come from one seed, `other_seed` from another.
void expectSeededPeriodicTable(const TextureTable& a, const TextureTable& same_seed,
                               const TextureTable& other_seed) {
  expectUnitRange(a);
  EXPECT_EQ(a.values, same_seed.values);
  EXPECT_NE(a.values, other_seed.values);
  const auto [seam, interior] = seamAndInteriorSteps(a);
  EXPECT_LT(seam, 2.0 * interior);
}

TEST(DiamondSquare, NormalisedSeededAndPeriodic) {
  const TextureTable a = diamondSquare(7, 1.0, 42);
  ASSERT_EQ(a.width, 128);
  expectSeededPeriodicTable(a, diamondSquare(7, 1.0, 42), diamondSquare(7, 1.0, 43));
}

TEST(DiamondSquare, RoughnessControlsHighFrequencies) {
  const auto smooth = seamAndInteriorSteps(diamondSquare(7, 2.0, 5)).second;
  const auto rough = seamAndInteriorSteps(diamondSquare(7, 0.3, 5)).second;
  EXPECT_LT(smooth, rough);
}

TEST(PerlinNoise, NormalisedSeededAndPeriodic) {
  expectSeededPeriodicTable(perlinNoise(128, 4, 5, 0.5, 3), perlinNoise(128, 4, 5, 0.5, 3),
                            perlinNoise(128, 4, 5, 0.5, 4));
}

TEST(TextureTable, BilinearSampleHitsTexelCentresAndWraps) {
  const TextureTable t = diamondSquare(4, 1.0, 1);
  for (int y = 0; y < t.height; y += 3)
    for (int x = 0; x < t.width; x += 5) {
      const glm::dvec2 centre((x + 0.5) / t.width, (y + 0.5) / t.height);
      EXPECT_NEAR(t.sampleBilinear(centre), t.at(x, y), 1e-6);
      EXPECT_NEAR(t.sampleBilinear(centre + glm::dvec2(3.0, -2.0)), t.at(x, y), 1e-6);
    }
  // Halfway between two texels: their mean.
  EXPECT_NEAR(t.sampleBilinear({1.0 / t.width, 0.5 / t.height}), 0.5 * (t.at(0, 0) + t.at(1, 0)),
              1e-6);
}

TEST(BakedGardner, TexelsEqualTheTruncatedTexture) {
  GardnerTextureParams params;
  params.terms = 5;
  params.fx1 = 2e-3;
  params.fy1 = 1e-3;
  params.t0 = 0.4;
  params.seed = 12;
  const GardnerTexture g(params);
  const int size = gardnerBakeSize(5, 4);
  EXPECT_EQ(size, 128);
  for (int terms : {5, 3, 1, 0}) {
    const GardnerTruncations t = bakeGardner(g, size, terms);
    for (int y = 0; y < size; y += 7)
      for (int x = 0; x < size; x += 11) {
        const glm::dvec2 p((x + 0.5) / size * g.period().x, (y + 0.5) / size * g.period().y);
        ASSERT_NEAR(t.with_terms.at(x, y), g.planar(p, terms), 1e-6) << x << "," << y;
        ASSERT_NEAR(t.one_fewer.at(x, y), g.planar(p, std::max(terms - 1, 0)), 1e-6)
            << x << "," << y << " m=" << terms;
      }
  }
}

TEST(BakedGardner, SizeIsCapped) {
  EXPECT_EQ(gardnerBakeSize(8, 16), kMaxBakeSize);
  EXPECT_EQ(gardnerBakeSize(1, 2), 4);
}

}  // namespace
}  // namespace nephele
