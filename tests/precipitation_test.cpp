// Precipitation (MODEL.md section 17): extinction by rate against its drop-size sums, the slabs
// a scene's weather makes, a target's contrast through rain against Koschmieder's law, and no
// NaN at the extremes.
#include "world/precipitation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "world/formations/cloud_field.h"
#include "world/formations/ellipsoid.h"
#include "world/scene.h"

namespace nephele {
namespace {

// pi N0 / Lambda^3 (per m) for an exponential size distribution, N0 per m^3 per mm, Lambda per
// mm: extinction efficiency 2 times the drops' summed cross-section.
double distributionExtinction(double n0, double lambda) {
  return std::numbers::pi * n0 / (lambda * lambda * lambda) * 1e-6;
}

TEST(PrecipitationTest, RainAndSnowFollowTheirSizeDistributions) {
  for (double rate : {0.5, 1.0, 4.0, 25.0, 100.0}) {
    const double rain = precipitationExtinction({PrecipitationKind::kRain, rate, 0.0});
    const double mp = distributionExtinction(8000.0, 4.1 * std::pow(rate, -0.21));
    EXPECT_NEAR(rain / mp, 1.0, 2e-3) << rate;
    const double snow = precipitationExtinction({PrecipitationKind::kSnow, rate, 0.0});
    const double gm =
        distributionExtinction(3800.0 * std::pow(rate, -0.87), 2.55 * std::pow(rate, -0.48));
    // Melted diameters widened to flakes of density 0.1: (1 / 0.1)^(2/3) times the area.
    EXPECT_NEAR(snow / (gm * std::pow(10.0, 2.0 / 3.0)), 1.0, 0.02) << rate;
  }
  // Moderate rain, 4 mm/h: 4.5 km; heavy snow at the same rate: well under 1 km.
  EXPECT_NEAR(precipitationVisibility({PrecipitationKind::kRain, 4.0, 0.0}), 4475.0, 5.0);
  EXPECT_LT(precipitationVisibility({PrecipitationKind::kSnow, 4.0, 0.0}), 1000.0);
  // A visibility given wins; sand has no rate.
  EXPECT_DOUBLE_EQ(precipitationVisibility({PrecipitationKind::kRain, 4.0, 700.0}), 700.0);
  EXPECT_EQ(precipitationExtinction({PrecipitationKind::kSand, 10.0, 0.0}), 0.0);
  WeatherLayer sand;
  sand.precipitation = {PrecipitationKind::kSand, 0.0, 0.0};
  EXPECT_NE(weatherLayerError(sand).find("precipitation_visibility"), std::string::npos);
}

// A nimbostratus deck at 900 m raining `rate` mm/h.
WeatherLayer rainingDeck(double rate) {
  WeatherLayer deck;
  deck.type = CloudType::kNimbostratus;
  deck.base_m = 900.0;
  deck.precipitation = {PrecipitationKind::kRain, rate, 0.0};
  return deck;
}

TEST(PrecipitationTest, ALayerRainsFromItsBaseAndACloudlessOneFillsItsOwnSlab) {
  Scene scene;
  const WeatherLayer deck = rainingDeck(4.0);
  scene.weather[{1, std::nullopt}] = deck;
  WeatherLayer dust;
  dust.base_m = 200.0;
  dust.thickness_m = 1000.0;
  dust.precipitation = {PrecipitationKind::kDust, 0.0, 3000.0};
  scene.weather[{9, std::nullopt}] = dust;
  scene.weather[{4, std::uint16_t(3)}] = deck;  // a region's: not drawn
  const std::vector<Fog> media = precipitationMedia(scene).slabs;
  ASSERT_EQ(media.size(), 2u);
  EXPECT_EQ(media[0].bottom_m, 0.0);
  EXPECT_EQ(media[0].top_m, 900.0);
  EXPECT_NEAR(media[0].visibility_m, 4475.0, 5.0);
  EXPECT_EQ(media[1].bottom_m, 200.0);
  EXPECT_EQ(media[1].top_m, 1200.0);
  EXPECT_DOUBLE_EQ(media[1].visibility_m, 3000.0);
  EXPECT_TRUE(sceneHasAir(scene));
}

// A dark target seen level through rain against a bright background: its apparent contrast
// falls as exp(-sigma d), to 2 % at the rain's visibility (Koschmieder).
TEST(PrecipitationTest, ATargetBehindRainKeepsKoschmiedersContrast) {
  Scene scene;
  WeatherLayer deck = rainingDeck(10.0);
  scene.weather[{1, std::nullopt}] = deck;
  const std::vector<Fog> media = precipitationMedia(scene).slabs;
  const double visibility = precipitationVisibility(deck.precipitation);
  const glm::dvec3 eye(0.0, 0.0, 100.0), level(0.0, 1.0, 0.0);
  for (double d : {0.25 * visibility, visibility, 2.0 * visibility}) {
    const glm::dvec3 target = throughAir(glm::dvec3(0.0), std::nullopt, std::nullopt, std::nullopt,
                                         {}, eye, level, d, media);
    const glm::dvec3 white = throughAir(glm::dvec3(1.0), std::nullopt, std::nullopt, std::nullopt,
                                        {}, eye, level, d, media);
    const double contrast = (white - target).g;
    EXPECT_NEAR(contrast, std::exp(-extinctionForVisibility(visibility) * d), 1e-9) << d;
  }
  const double at = (throughAir(glm::dvec3(1.0), std::nullopt, std::nullopt, std::nullopt, {}, eye,
                                level, visibility, media) -
                     throughAir(glm::dvec3(0.0), std::nullopt, std::nullopt, std::nullopt, {}, eye,
                                level, visibility, media))
                        .g;
  EXPECT_NEAR(at, 0.02, 1e-9);
  // The heaviest rain on every ray, endless ones included: finite, between the two colours.
  deck.precipitation.rate_mm_h = 500.0;
  scene.weather[{1, std::nullopt}] = deck;
  const std::vector<Fog> heavy = precipitationMedia(scene).slabs;
  for (double z : {-1.0, 0.0, 1e-9, 0.3, 1.0})
    for (double d : {0.0, 1.0, 1e4, std::numeric_limits<double>::infinity()}) {
      const glm::dvec3 c = throughAir(glm::dvec3(1.0), std::nullopt, std::nullopt, std::nullopt, {},
                                      eye, glm::normalize(glm::dvec3(0.0, 1.0, z)), d, heavy);
      EXPECT_TRUE(std::isfinite(c.r) && c.r >= 0.0 && c.r <= 1.0) << z << " " << d;
    }
}

// The shaft's density written out (MODEL.md section 17), to be summed independently.
double shaftDensity(const RainShaft& s, glm::dvec3 p) {
  const double rho2 = glm::dot(glm::dvec2(p) - s.centre, glm::dvec2(p) - s.centre);
  if (rho2 >= s.radius_m * s.radius_m || p.z < 0.0 || p.z > s.top_m) return 0.0;
  return (1.0 - rho2 / (s.radius_m * s.radius_m)) *
         (kShaftGroundShare + (1.0 - kShaftGroundShare) * p.z / s.top_m);
}

// The exact optical depth against a midpoint sum of the density over 200,000 steps, for rays
// level, slanting, straight up inside and from far away, stopped short or endless.
TEST(PrecipitationTest, AShaftsOpticalDepthIsTheIntegralOfItsDensity) {
  RainShaft shaft;
  shaft.centre = {1000.0, 3000.0};
  shaft.radius_m = 1500.0;
  shaft.top_m = 1200.0;
  shaft.sigma = 2e-3;
  struct Ray {
    glm::dvec3 origin, towards;
    double distance;
  };
  const Ray rays[] = {
      {{1000.0, 0.0, 300.0}, {0.0, 1.0, 0.0}, 1e9},         // level through the axis
      {{0.0, -2000.0, 50.0}, {0.2, 1.0, 0.08}, 1e9},        // rising through it
      {{0.0, -2000.0, 2000.0}, {0.1, 1.0, -0.35}, 1e9},     // from above its top, down
      {{1200.0, 3100.0, 10.0}, {0.0, 0.0, 1.0}, 1e9},       // straight up inside
      {{1200.0, 3100.0, 600.0}, {1.0, 0.3, 0.02}, 800.0},   // from inside, stopped short
      {{-90000.0, 2500.0, 400.0}, {1.0, 0.0, 0.001}, 1e9},  // from 90 km
      {{1000.0, 0.0, 300.0}, {0.0, 1.0, 0.0}, 2500.0},      // stopped in the middle
      {{5000.0, 0.0, 300.0}, {0.0, 1.0, 0.0}, 1e9},         // missing it
  };
  for (const Ray& ray : rays) {
    const glm::dvec3 d = glm::normalize(ray.towards);
    const double exact = shaftOpticalDepth(shaft, ray.origin, d, ray.distance);
    // The sum over the part of the ray near the shaft.
    const double from =
        std::max(0.0, glm::dot(glm::dvec3(shaft.centre, 0.0) - ray.origin, d) - 20000.0);
    const double to = std::min(ray.distance, from + 40000.0);
    constexpr int kSteps = 200000;
    double sum = 0.0;
    for (int i = 0; i < kSteps; ++i)
      sum += shaftDensity(shaft, ray.origin + (from + (i + 0.5) * (to - from) / kSteps) * d);
    sum *= shaft.sigma * (to - from) / kSteps;
    EXPECT_NEAR(exact, sum, 2e-3 * std::max(sum, 1.0)) << ray.origin.x << " " << ray.origin.y;
  }
  // Level through the axis at height z: sigma (4/3) R (1/2 + z / (2 top)).
  EXPECT_NEAR(shaftOpticalDepth(shaft, {1000.0, 0.0, 300.0}, {0.0, 1.0, 0.0}, 1e9),
              2e-3 * 4.0 / 3.0 * 1500.0 * (0.5 + 0.5 * 300.0 / 1200.0), 1e-9);
  // Extremes: a metre-wide shaft of the heaviest rain, rays along its axis and its edge.
  RainShaft thin{{0.0, 0.0}, 1.0, 20000.0, 1.0, {}};
  for (const glm::dvec3 d : {glm::dvec3(0.0, 0.0, 1.0), glm::dvec3(0.0, 0.0, -1.0),
                             glm::normalize(glm::dvec3(1.0, 0.0, 1e-9))})
    for (const glm::dvec3 o :
         {glm::dvec3(0.0, 0.0, 10.0), glm::dvec3(-1.0, 0.0, 10.0), glm::dvec3(0.0, -1.0, 10.0)}) {
      const double tau = shaftOpticalDepth(thin, o, d, std::numeric_limits<double>::infinity());
      EXPECT_TRUE(std::isfinite(tau) && tau >= 0.0) << o.x << " " << d.z;
    }
}

// A raining cumulonimbus layer: a shaft under each heap in view, its top at the heaps' base and
// its axis inside the heap's bottom; no slab; none without rain.
TEST(PrecipitationTest, HeapsRainInShaftsUnderTheirBases) {
  CloudField field;
  field.type = CloudType::kCumulonimbus;
  field.base_m = 1000.0;
  field.thickness_m = 9000.0;
  field.coverage = 0.3;
  field.seed = 11;
  Camera camera;
  camera.position = {0.0, 0.0, 40000.0};
  camera.orientation.pitch_deg = -90.0;
  camera.vfov_deg = 90.0;
  EXPECT_TRUE(fieldRainShafts(field, camera).empty());
  field.precipitation = {PrecipitationKind::kRain, 25.0, 0.0};
  const std::vector<RainShaft> shafts = fieldRainShafts(field, camera);
  ASSERT_FALSE(shafts.empty());
  const std::vector<EllipsoidCloud> heaps = fieldShadowClouds(field, camera);
  for (const RainShaft& s : shafts) {
    EXPECT_EQ(s.top_m, field.base_m);
    EXPECT_NEAR(s.sigma, precipitationExtinction(field.precipitation), 1e-12);
    const glm::dvec3 under_base(s.centre, field.base_m + 10.0);
    bool inside = false;
    for (const EllipsoidCloud& heap : heaps)
      for (const Ellipsoid& e : heap.ellipsoids) {
        const glm::dvec3 u = worldToUnitSphere(e) * (under_base - e.centre);
        inside = inside || glm::dot(u, u) < 1.0;
      }
    EXPECT_TRUE(inside) << s.centre.x << " " << s.centre.y;
  }
  // Through a scene: shafts, no slab, at most kMaxRainShafts, and air to draw.
  Scene scene;
  scene.camera = camera;
  WeatherLayer layer;
  layer.type = CloudType::kCumulonimbus;
  layer.precipitation = field.precipitation;
  scene.weather[{1, std::nullopt}] = layer;
  scene.fields.push_back(field);
  const PrecipitationMedia media = precipitationMedia(scene);
  EXPECT_TRUE(media.slabs.empty());
  EXPECT_EQ(media.shafts.size(), std::min(shafts.size(), std::size_t(kMaxRainShafts)));
  EXPECT_TRUE(sceneHasAir(scene));
  const Scene drawn = withFieldClouds(scene);
  EXPECT_EQ(drawn.rain_shafts, media.shafts);
}

}  // namespace
}  // namespace nephele
