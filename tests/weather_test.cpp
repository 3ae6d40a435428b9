#include "world/formations/weather.h"

#include <gtest/gtest.h>

#include "world/textures/layer_texture.h"

namespace nephele {
namespace {

// The covered fraction of a layer, measured on a grid offset from (and finer than) the one
// thresholdForCoverage uses.
double coveredFraction(const CloudLayer& layer) {
  const LayerTexture texture(layer.texture);
  const glm::dvec2 p = texture.period();
  constexpr int n = 157;
  int covered = 0;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      covered += texture.value({(i + 0.37) / n * p.x, (j + 0.71) / n * p.y}, 0.0) > layer.threshold;
  return double(covered) / (n * n);
}

TEST(Weather, StratiformTypesCoverWhatIsAsked) {
  for (CloudType type : {CloudType::kAltocumulus, CloudType::kAltostratus, CloudType::kCirrocumulus,
                         CloudType::kCirrostratus, CloudType::kCirrus, CloudType::kNimbostratus,
                         CloudType::kStratocumulus, CloudType::kStratus})
    for (double coverage : {0.1, 0.5, 0.9}) {
      const WeatherClouds w = weatherClouds({type, 2000.0, 500.0, coverage, {}}, "w", {}, 7);
      ASSERT_EQ(w.layers.size(), 1u) << cloudTypeName(type);
      EXPECT_TRUE(w.clouds.empty());
      EXPECT_EQ(w.layers[0].altitude_m, 2000.0);
      EXPECT_NEAR(coveredFraction(w.layers[0]), coverage, 0.03)
          << cloudTypeName(type) << " at " << coverage;
    }
}

TEST(Weather, ConvectiveTypesBecomeHeapsOverTheField) {
  const glm::dvec2 centre{5000.0, -3000.0};
  const WeatherClouds few =
      weatherClouds({CloudType::kCumulus, 1500.0, 800.0, 0.02, {}}, "w1", centre, 3);
  // 0.02 * R^2 / (w/2)^2 with w = 1.2 * 800 m and R = 8 km: 5.6, rounded to 6.
  ASSERT_EQ(few.clouds.size(), 6u);
  EXPECT_TRUE(few.layers.empty());
  for (const EllipsoidCloud& c : few.clouds) {
    EXPECT_EQ(c.name.rfind("w1/heap", 0), 0u);
    glm::dvec3 lowest{0.0, 0.0, 1e9};
    for (const Ellipsoid& e : c.ellipsoids)
      if (e.centre.z - e.radii.z < lowest.z) lowest = e.centre - glm::dvec3(0, 0, e.radii.z);
    EXPECT_NEAR(lowest.z, 1500.0, 200.0);
    EXPECT_LE(glm::length(glm::dvec2(c.ellipsoids[0].centre) - centre),
              WeatherLimits::kFieldRadius + 1000.0);
  }
  const WeatherClouds many =
      weatherClouds({CloudType::kCumulonimbus, 1000.0, 9000.0, 1.0, {}}, "w2", centre, 3);
  EXPECT_GE(many.clouds.size(), 1u);
  EXPECT_LE(many.clouds.size(), std::size_t(WeatherLimits::kMaxHeaps));
  const WeatherClouds capped =
      weatherClouds({CloudType::kCumulus, 1000.0, 200.0, 1.0, {}}, "w3", centre, 3);
  EXPECT_EQ(capped.clouds.size(), std::size_t(WeatherLimits::kMaxHeaps));
  // Deterministic in the seed.
  const WeatherClouds again =
      weatherClouds({CloudType::kCumulus, 1500.0, 800.0, 0.02, {}}, "w1", centre, 3);
  EXPECT_EQ(again.clouds[2].ellipsoids[0].centre, few.clouds[2].ellipsoids[0].centre);
}

TEST(Weather, NoneOrNoCoverageAddsNothing) {
  EXPECT_TRUE(weatherClouds({CloudType::kNone, 1000.0, 500.0, 1.0, {}}, "w", {}, 1).layers.empty());
  const WeatherClouds empty =
      weatherClouds({CloudType::kCumulus, 1000.0, 500.0, 0.0, {}}, "w", {}, 1);
  EXPECT_TRUE(empty.layers.empty() && empty.clouds.empty());
  EXPECT_EQ(cloudTypeName(CloudType::kStratocumulus), "stratocumulus");
}

}  // namespace
}  // namespace nephele
