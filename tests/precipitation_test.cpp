// Precipitation (MODEL.md section 17): extinction by rate against its drop-size sums, the slabs
// a scene's weather makes, a target's contrast through rain against Koschmieder's law, and no
// NaN at the extremes.
#include "world/precipitation.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "world/formations/cloud_field.h"
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
  const std::vector<Fog> media = precipitationMedia(scene);
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
  const std::vector<Fog> media = precipitationMedia(scene);
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
  const std::vector<Fog> heavy = precipitationMedia(scene);
  for (double z : {-1.0, 0.0, 1e-9, 0.3, 1.0})
    for (double d : {0.0, 1.0, 1e4, std::numeric_limits<double>::infinity()}) {
      const glm::dvec3 c = throughAir(glm::dvec3(1.0), std::nullopt, std::nullopt, std::nullopt, {},
                                      eye, glm::normalize(glm::dvec3(0.0, 1.0, z)), d, heavy);
      EXPECT_TRUE(std::isfinite(c.r) && c.r >= 0.0 && c.r <= 1.0) << z << " " << d;
    }
}

}  // namespace
}  // namespace nephele
