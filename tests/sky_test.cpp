#include "world/sky.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

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

// The haze's depth against the integral of sigma0 exp(-z / H) along the ray by Simpson's rule
// over 20,000 steps (relative error below 1e-9 on these paths), an independent computation.
double hazeDepthBySimpson(const Haze& haze, glm::dvec3 o, glm::dvec3 d, double s) {
  const double sigma0 = -std::log(0.02) / haze.visibility_m;
  auto f = [&](double u) { return sigma0 * std::exp(-(o.z + u * d.z) / haze.scale_height_m); };
  const int n = 20000;
  const double h = s / n;
  double sum = f(0.0) + f(s);
  for (int i = 1; i < n; ++i) sum += (i % 2 ? 4.0 : 2.0) * f(i * h);
  return sum * h / 3.0;
}

// The in-layer veil's slab (MODEL.md section 5): density 1 from bottom to top, falling
// linearly to 0 over the band either side. Its path integral, restated here as a midpoint sum
// of the density along the ray, for rays from inside, in the bands and outside, up, down,
// slanted, level and grazing.
TEST(Fog, BandedSlabPathMatchesTheIntegralAlongTheRay) {
  Fog veil;
  veil.bottom_m = 600.0;
  veil.top_m = 1100.0;
  veil.band_m = 150.0;
  auto density = [&](double z) {
    if (z >= veil.bottom_m && z <= veil.top_m) return 1.0;
    const double out = z < veil.bottom_m ? veil.bottom_m - z : z - veil.top_m;
    return std::max(0.0, 1.0 - out / veil.band_m);
  };
  for (double z : {300.0, 500.0, 600.0, 850.0, 1150.0, 1400.0})
    for (double dz : {-1.0, -0.3, -0.01, 0.0, 1e-5, 0.02, 0.5, 1.0})
      for (double distance : {10.0, 700.0, 5000.0}) {
        const glm::dvec3 d = glm::normalize(glm::dvec3(1.0, 0.2, dz));
        constexpr int kSteps = 200000;
        double sum = 0.0;
        for (int i = 0; i < kSteps; ++i)
          sum += density(z + (i + 0.5) / kSteps * distance * d.z) * distance / kSteps;
        EXPECT_NEAR(fogPathLength(veil, {0.0, 0.0, z}, d, distance), sum, 1e-3 * (1.0 + sum))
            << "z " << z << " dz " << dz << " distance " << distance;
      }
  // Without end: the whole column over |dz| looking out of it; endless on a level ray inside.
  const double column = veil.top_m - veil.bottom_m + veil.band_m;
  EXPECT_NEAR(fogPathLength(veil, {0, 0, 100}, {0, 0, 1}, kInf), column, 1e-9);
  EXPECT_NEAR(fogPathLength(veil, {0, 0, 2000}, {0, 0, -1}, kInf), column, 1e-9);
  EXPECT_EQ(fogPathLength(veil, {0, 0, 1200}, {1, 0, 0}, kInf), kInf);  // in the band
  EXPECT_EQ(fogPathLength(veil, {0, 0, 1300}, {1, 0, 0}, kInf), 0.0);   // beyond it
}

TEST(Haze, DepthMatchesTheIntegralAlongTheRay) {
  const Haze haze{30000.0, 1200.0};
  struct Path {
    glm::dvec3 origin, direction;
    double distance;
  };
  const Path paths[] = {
      {{0, 0, 0}, {1, 0, 0}, 40000.0},                                   // level at sea level
      {{0, 0, 500}, glm::normalize(glm::dvec3(1, 0, 0.02)), 60000.0},    // up to a far heap
      {{0, 0, 500}, glm::normalize(glm::dvec3(1, 0, 1e-7)), 20000.0},    // nearly level
      {{0, 0, 10000}, glm::normalize(glm::dvec3(1, 0, -0.5)), 22000.0},  // down to the ground
      {{0, 0, 3000}, {0, 0, 1}, 5000.0},                                 // straight up
  };
  for (const Path& p : paths) {
    const double exact = hazeDepthBySimpson(haze, p.origin, p.direction, p.distance);
    EXPECT_NEAR(hazeOpticalDepth(haze, p.origin, p.direction, p.distance), exact, 1e-9 * exact)
        << p.origin.z << " " << p.direction.z;
  }
  // Koschmieder at sea level: 2 % contrast left after the visibility, on a level path.
  EXPECT_NEAR(std::exp(-hazeOpticalDepth(haze, {0, 0, 0}, {1, 0, 0}, 30000.0)), 0.02, 1e-12);
  // Upwards to infinity the depth is sigma0 H exp(-z0 / H) / dz.
  const glm::dvec3 up = glm::normalize(glm::dvec3(1, 0, 0.3));
  EXPECT_NEAR(hazeOpticalDepth(haze, {0, 0, 800}, up, kInf),
              -std::log(0.02) / 30000.0 * 1200.0 * std::exp(-800.0 / 1200.0) / up.z, 1e-12);
}

// Legal extremes give finite colours between the surface's and the air's.
TEST(Haze, ThroughAirStaysFiniteAtTheExtremes) {
  const glm::dvec3 colour(0.9, 0.5, 0.1), horizon(0.6, 0.7, 0.9);
  const std::optional<Fog> fog = Fog{};
  const std::optional<Fog> no_fog;
  for (const Haze haze : {Haze{10.0, 10.0}, Haze{1.0e7, 1.0e5}, Haze{40000.0, 1200.0}})
    for (double z : {0.0, 1.0, 50.0, 1.0e5, 1.0e6})
      for (double dz : {-1.0, -1e-3, -1e-12, 0.0, 1e-12, 1e-3, 1.0})
        for (double distance : {0.0, 1.0, 1.0e4, 1.0e12, kInf}) {
          const glm::dvec3 d = glm::normalize(glm::dvec3(1.0, 0.0, dz));
          const double tau = hazeOpticalDepth(haze, {0, 0, z}, d, distance);
          ASSERT_TRUE(tau >= 0.0) << z << " " << dz << " " << distance;
          for (const auto& f : {fog, no_fog}) {
            const glm::dvec3 c = throughAir(colour, f, f, haze, horizon, {0, 0, z}, d, distance);
            for (int i = 0; i < 3; ++i)
              ASSERT_TRUE(c[i] >= 0.1 - 1e-12 && c[i] <= 0.9 + 1e-12)
                  << z << " " << dz << " " << distance << " " << c[i];
          }
        }
  // A level path at sea level without end is the horizon colour.
  const glm::dvec3 end =
      throughAir(colour, no_fog, no_fog, Haze{}, horizon, {0, 0, 0}, {1, 0, 0}, kInf);
  EXPECT_NEAR(glm::length(end - horizon), 0.0, 1e-12);
}

}  // namespace
}  // namespace nephele
