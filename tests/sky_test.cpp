#include "world/sky.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace nephele {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(SkyBackground, GradientFromHorizonToZenithAndGroundBelow) {
  const Sky sky;
  const glm::dvec3 zenith = skyBackground(sky, {0, 0, 5});
  const glm::dvec3 horizon = skyBackground(sky, {1, 0, 0});
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR(zenith[c], sky.zenith[c], 1e-12);
    EXPECT_NEAR(horizon[c], sky.horizon[c], 1e-12);
  }
  const glm::dvec3 mid = skyBackground(sky, {std::sqrt(0.75), 0, 0.5});
  EXPECT_NEAR(mid.x, sky.horizon.x + (sky.zenith.x - sky.horizon.x) * std::sqrt(0.5), 1e-12);
  EXPECT_EQ(skyBackground(sky, {0, 1, -0.01}), sky.ground);
}

TEST(Sun, DirectionFromAzimuthAndElevation) {
  const glm::dvec3 east = sunDirection({90.0, 0.0, {1, 1, 1}});
  EXPECT_NEAR(east.x, 1.0, 1e-12);
  EXPECT_NEAR(east.z, 0.0, 1e-12);
  const glm::dvec3 high = sunDirection({0.0, 30.0, {1, 1, 1}});
  EXPECT_NEAR(high.y, std::cos(M_PI / 6), 1e-12);
  EXPECT_NEAR(high.z, 0.5, 1e-12);
}

TEST(Fog, ExtinctionLeavesTwoPercentAtVisibility) {
  Fog fog;
  fog.visibility_m = 2500.0;
  EXPECT_NEAR(std::exp(-fogExtinction(fog) * 2500.0), 0.02, 1e-12);
}

TEST(Fog, PathLengthInsideTheSlab) {
  Fog fog;
  fog.top_m = 100.0;
  const glm::dvec3 up(0, 0, 1), down(0, 0, -1), level(1, 0, 0);
  const glm::dvec3 slant = glm::normalize(glm::dvec3(1, 0, -1));
  // Inside, looking up to the sky: from the camera to the top.
  EXPECT_NEAR(fogPathLength(fog, {0, 0, 40}, up, kInf), 60.0, 1e-9);
  // Inside, looking down at the ground 40 m below.
  EXPECT_NEAR(fogPathLength(fog, {0, 0, 40}, down, 40.0), 40.0, 1e-9);
  // Above, looking down at 45 degrees to the ground: the lower 100 m, slanted.
  EXPECT_NEAR(fogPathLength(fog, {0, 0, 300}, slant, 300 * std::sqrt(2.0)), 100 * std::sqrt(2.0),
              1e-9);
  // A surface above the fog seen from above: no fog.
  EXPECT_EQ(fogPathLength(fog, {0, 0, 300}, slant, 100.0), 0.0);
  // Level inside: infinite. Level above: none.
  EXPECT_EQ(fogPathLength(fog, {0, 0, 50}, level, kInf), kInf);
  EXPECT_EQ(fogPathLength(fog, {0, 0, 500}, level, kInf), 0.0);
  EXPECT_NEAR(fogPathLength(fog, {0, 0, 50}, level, 123.0), 123.0, 1e-12);
}

}  // namespace
}  // namespace nephele
