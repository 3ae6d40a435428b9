// The sea (MODEL.md section 18) against the works it follows, each measured from the drawn
// surface (bench/sea_measures.h, which sea_bench prints): the surface's frequency spectrum
// against Pierson-Moskowitz, its autocorrelation (repetition), its mean glint against Cox and
// Munk's, its foam against Monahan's fraction; Fresnel's limits, a host's wave train, and
// finite output at the extremes.
#include "world/sea.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "bench/sea_measures.h"

namespace nephele {
namespace {

using namespace sea_measures;

Sea windSea(double speed, double fetch = 0.0) {
  Sea sea;
  sea.wind = {0.6 * speed, 0.8 * speed};
  sea.fetch_m = fetch;
  return sea;
}

TEST(SeaTest, FresnelMeetsItsLimits) {
  const double n = 1.34;
  EXPECT_NEAR(fresnelWater(1.0), std::pow((n - 1) / (n + 1), 2), 1e-12);
  EXPECT_NEAR(fresnelWater(0.0), 1.0, 1e-12);
  double last = 0.0;
  for (double c = 1.0; c >= 0.0; c -= 0.01) {
    const double f = fresnelWater(c);
    EXPECT_GE(f, last - 1e-12) << c;
    last = f;
  }
  // Thermal infrared, index 1.2: emissivity 0.99 straight down, falling towards grazing.
  EXPECT_NEAR(seaEmissivity(1.0), 1.0 - std::pow(0.2 / 2.2, 2), 1e-12);
  EXPECT_LT(seaEmissivity(0.1), 0.8);
}

// The height's frequency spectrum measured at one point over 55 minutes falls above the peak
// as Pierson-Moskowitz's does (the slopes of their band densities within 10 %) and holds its
// energy.
TEST(SeaTest, MeasuredSpectrumFollowsPiersonMoskowitz) {
  for (double speed : {5.0, 10.0, 15.0}) {
    const SpectrumFit fit = measureSpectrum(SeaSurface(windSea(speed)), speed);
    EXPECT_NEAR(fit.energy_ratio, 1.0, 0.15) << speed;
    EXPECT_NEAR(fit.measured_slope / fit.expected_slope, 1.0, 0.1) << speed << " m/s";
  }
}

// The height's autocorrelation with the wind and across it stays under 0.3 at every lag from
// three peak wavelengths to 10 km: no tile repeats.
TEST(SeaTest, SurfaceDoesNotRepeat) {
  for (double speed : {3.0, 8.0, 15.0}) {
    const Sea sea = windSea(speed);
    const SeaSurface surface(sea);
    const glm::dvec2 along = glm::normalize(sea.wind);
    EXPECT_LT(repetition(surface, along), 0.3) << speed << " m/s, along the wind";
    EXPECT_LT(repetition(surface, {-along.y, along.x}), 0.3) << speed << " m/s, across it";
  }
}

// Cox and Munk's glint against the drawn surface's, averaged over its waves and facets, over
// the glint's core, |tan beta| < sigma: within 20 %.
TEST(SeaTest, MeanGlintFollowsCoxMunk) {
  const glm::dvec3 sun = glm::normalize(glm::dvec3(0.0, 0.8, 0.6));
  for (double speed : {2.0, 7.0, 15.0}) {
    const SeaSurface surface(windSea(speed));
    const double sigma = std::sqrt(0.003 + 5.12e-3 * speed);
    for (double tan_beta : {0.0, 0.5 * sigma, 0.9 * sigma})
      EXPECT_NEAR(glintRatio(surface, speed, tan_beta, sun), 1.0, 0.2)
          << speed << " m/s, tan beta " << tan_beta;
  }
}

// Monahan and O'Muircheartaigh (1980): foam covers W = 3.84e-6 U^3.41 of the sea, whether its
// crests are resolved or a pixel sees only the mean.
TEST(SeaTest, FoamCoversMonahansFraction) {
  for (double speed : {8.0, 15.0, 25.0}) {
    const SeaSurface surface(windSea(speed));
    const double w = 3.84e-6 * std::pow(speed, 3.41);
    EXPECT_NEAR(surface.whitecapFraction(), w, 1e-12);
    const double mean = meanFoam(surface);
    EXPECT_NEAR(mean / w, 1.0, 0.25) << speed;
    const SeaSample far = surface.sample({0.0, 0.0}, 0.0, 1e6);
    EXPECT_NEAR(foamShare(w, surface.foamSteepness(), glm::dot(far.slope, far.slope),
                          surface.drawnSlopeVariance(),
                          surface.drawnSlopeVariance() - far.resolved_slope_var),
                w, 1e-9);
  }
  Sea calm = windSea(15.0);
  calm.whitecaps = false;
  EXPECT_EQ(SeaSurface(calm).whitecapFraction(), 0.0);
}

// A host's wave train is drawn as given: its crest height and its travel.
TEST(SeaTest, WaveTrainIsDrawnAsGiven) {
  Sea sea;
  sea.wind = {0.0, 0.0};
  sea.trains.push_back({1, 3.0, 120.0, 0.0, 90.0, 0.0});  // 3 m, travelling east
  const SeaSurface surface(sea);
  ASSERT_EQ(surface.components().size(), 1u);
  EXPECT_NEAR(surface.sample({0.0, 0.0}, 0.0, 0.0).height, 1.5, 1e-12);
  EXPECT_NEAR(surface.sample({60.0, 0.0}, 0.0, 0.0).height, -1.5, 1e-9);
  // Deep water: the crest moves at sqrt(g lambda / 2 pi).
  const double c = std::sqrt(kG * 120.0 / (2.0 * kPi));
  EXPECT_NEAR(surface.sample({10.0 * c, 0.0}, 10.0, 0.0).height, 1.5, 1e-9);
  EXPECT_NEAR(surface.sample({0.0, 37.0}, 0.0, 0.0).height, 1.5, 1e-12);  // long-crested
}

// Every legal sea, seen from any angle under any sun, shades to finite, non-negative light.
TEST(SeaTest, ExtremeSeasShadeFinite) {
  std::vector<Sea> seas;
  for (double speed : {0.0, 0.3, 0.5, 40.0, 200.0})
    for (double fetch : {0.0, 1.0, 2e6}) seas.push_back(windSea(speed, fetch));
  Sea trains;
  trains.trains.push_back({0, 30.0, 1.0, 0.0, -360.0, 360.0});
  trains.trains.push_back({255, 0.0, 2000.0, 60.0, 360.0, -360.0});
  seas.push_back(trains);
  for (const Sea& sea : seas) {
    const SeaSurface surface(sea);
    for (double dz : {-1.0, -0.3, -1e-6})
      for (double sun_z : {-0.5, 0.0, 0.01, 1.0})
        for (double footprint : {0.0, 1.0, 1e9}) {
          const glm::dvec3 d = glm::normalize(glm::dvec3(0.0, 1.0, dz));
          const glm::dvec3 sun = glm::normalize(glm::dvec3(0.0, 1.0, sun_z));
          const SeaSample s = surface.sample({1e5, -3e4}, 1e6, footprint);
          const SeaShading shade = shadeSea(surface, sea, s, d, sun, {1.0, 1.0, 1.0}, 1.0);
          for (double v : {shade.fresnel, shade.foam, shade.glint.x, shade.body_and_foam.y,
                           shade.reflect_dir.z}) {
            EXPECT_TRUE(std::isfinite(v)) << glm::length(sea.wind) << " " << dz << " " << sun_z;
            EXPECT_GE(v, 0.0);
          }
        }
  }
}

}  // namespace
}  // namespace nephele
