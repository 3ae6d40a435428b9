#include "world/shading.h"

#include <gtest/gtest.h>

#include "world/formations/heap_light.h"

#include <cmath>
#include <limits>

namespace nephele {
namespace {

TEST(SkyPlaneTranslucence, FollowsGardnerEquation9) {
  EXPECT_DOUBLE_EQ(skyPlaneTranslucence(0.3, 0.3, 0.2), 1.0);  // at threshold: clear
  EXPECT_DOUBLE_EQ(skyPlaneTranslucence(0.4, 0.3, 0.2), 0.5);
  EXPECT_DOUBLE_EQ(skyPlaneTranslucence(0.5, 0.3, 0.2), 0.0);  // T1 + D: opaque
  EXPECT_DOUBLE_EQ(skyPlaneTranslucence(0.9, 0.3, 0.2), 0.0);  // clamped
  EXPECT_DOUBLE_EQ(skyPlaneTranslucence(0.0, 0.3, 0.2), 1.0);
}

TEST(SkyPlaneTranslucence, ZeroTransitionIsAHardThreshold) {
  EXPECT_EQ(skyPlaneTranslucence(0.3, 0.3, 0.0), 1.0);
  EXPECT_EQ(skyPlaneTranslucence(0.3000001, 0.3, 0.0), 0.0);
  EXPECT_EQ(skyPlaneTranslucence(0.0, 0.0, 0.0), 1.0);
}

TEST(SkyPlaneTranslucence, ExtremeParametersStayFinite) {
  const double tiny = std::numeric_limits<double>::denorm_min();
  for (double d : {0.0, tiny, 1e-300, 1e-9, 1.0, 1e300})
    for (double t1 : {0.0, 1.0, -1.0, 2.0})
      for (double it : {0.0, 0.5, 1.0}) {
        const double tr = skyPlaneTranslucence(it, t1, d);
        ASSERT_TRUE(std::isfinite(tr)) << it << " " << t1 << " " << d;
        ASSERT_GE(tr, 0.0);
        ASSERT_LE(tr, 1.0);
      }
}

TEST(EllipsoidTranslucence, ThresholdRisesFromCentreToLimb) {
  // g = 1 (centre): threshold T1; g = 0 (limb): threshold T2.
  EXPECT_DOUBLE_EQ(ellipsoidTranslucence(0.5, 0.3, 0.7, 1.0, 0.4),
                   skyPlaneTranslucence(0.5, 0.3, 0.4));
  EXPECT_DOUBLE_EQ(ellipsoidTranslucence(0.5, 0.3, 0.7, 0.0, 0.4),
                   skyPlaneTranslucence(0.5, 0.7, 0.4));
  EXPECT_DOUBLE_EQ(ellipsoidTranslucence(0.5, 0.3, 0.7, 0.5, 0.4),
                   skyPlaneTranslucence(0.5, 0.5, 0.4));
  EXPECT_EQ(ellipsoidTranslucence(0.5, 0.3, 0.7, 0.0, 0.0), 1.0);  // D = 0 at the limb
}

TEST(GardnerIntensity, FollowsEquation8) {
  ShadingParams s{0.2, 0.3, 0.4, 10.0};
  const glm::dvec3 n(0, 0, 1), l = glm::normalize(glm::dvec3(1, 0, 1)), v(0, 0, 1);
  const double id = glm::dot(n, l);
  const glm::dvec3 r = 2.0 * id * n - l;
  const double is = std::pow(glm::dot(r, v), 10.0);
  const double it = 0.6;
  const double expected = 0.8 * (0.7 * (0.6 * id + 0.4 * is) + 0.3 * it) + 0.2;
  EXPECT_NEAR(gardnerIntensity(s, it, n, l, v), expected, 1e-12);
}

TEST(GardnerIntensity, NormalTurnsTowardsViewerAndBackLitHasNoHighlight) {
  ShadingParams s{0.0, 0.0, 1.0, 4.0};  // specular only
  const glm::dvec3 l(0, 0, 1);
  // Viewer below a plane whose normal points up: the normal flips to face the viewer, so
  // the sun above lights it from behind: no diffuse, no highlight.
  EXPECT_EQ(gardnerIntensity(s, 0.5, {0, 0, 1}, l, {0, 0, -1}), 0.0);
  ShadingParams diffuse{0.0, 0.0, 0.0, 1.0};
  EXPECT_EQ(gardnerIntensity(diffuse, 0.5, {0, 0, -1}, l, {0, 0, 1}), 1.0);
  EXPECT_EQ(gardnerIntensity({1.0, 0.0, 0.0, 1.0}, 0.0, {0, 0, 1}, l, {0, 0, -1}), 1.0);
}

// MODEL.md section 14, against values worked by hand: a sphere of radius 100 m whose centre is
// 300 m above another's takes away 200 m of the lower one's light straight up.
TEST(HeapLight, TransmittanceThroughTheOtherLobes) {
  EllipsoidCloud cloud;
  cloud.light_extinction = 0.02;
  Ellipsoid lower, upper, aside;
  lower.radii = upper.radii = aside.radii = glm::dvec3(100.0);
  lower.centre = {0.0, 0.0, 1000.0};
  upper.centre = {0.0, 0.0, 1300.0};
  aside.centre = {5000.0, 0.0, 1000.0};
  cloud.ellipsoids = {lower, upper, aside};
  const glm::dvec3 up(0.0, 0.0, 1.0);
  const std::vector<LobeLight> lights = lobeLights(cloud, up);              // the sun overhead
  const double through = 1.0 / (1.0 + 0.75 * (1.0 - 0.85) * 0.02 * 200.0);  // two-stream
  EXPECT_NEAR(lights[0].sun, through, 1e-12);
  EXPECT_NEAR(lights[0].sky, 0.5 + 0.5 * through, 1e-12);
  // The lower lobe's top, 1100 m, lies 100 m below the upper's bottom: its sunward point sees
  // the whole 200 m of the upper lobe too. A lobe between them, 1150 m to 1250 m, takes the
  // upper's light from 1250 m at its top: the upper lobe's chord from there is 150 m.
  EXPECT_NEAR(lights[0].sun_face, through, 1e-12);
  Ellipsoid middle;
  middle.radii = {50.0, 50.0, 50.0};
  middle.centre = {0.0, 0.0, 1200.0};
  EllipsoidCloud stacked = cloud;
  stacked.ellipsoids.push_back(middle);
  const std::vector<LobeLight> with_middle = lobeLights(stacked, up);
  EXPECT_NEAR(with_middle[3].sun_face, 1.0 / (1.0 + 0.75 * 0.15 * 0.02 * 150.0), 1e-12);
  EXPECT_NEAR(with_middle[3].sun, 1.0 / (1.0 + 0.75 * 0.15 * 0.02 * 200.0), 1e-12);
  for (int i : {1, 2}) {
    EXPECT_DOUBLE_EQ(lights[i].sun, 1.0) << i;
    EXPECT_DOUBLE_EQ(lights[i].sky, 1.0) << i;
  }
  // The sun from the side: nothing lies east of the lower lobe but the distant one, which a
  // ray 5 km long at its height passes through the middle of.
  const std::vector<LobeLight> east = lobeLights(cloud, {1.0, 0.0, 0.0});
  EXPECT_NEAR(east[0].sun, through, 1e-12);
  EXPECT_DOUBLE_EQ(east[1].sun, 1.0);
  // Off: every lobe takes all the light, and the intensity is eq. 8.
  cloud.light_extinction = 0.0;
  for (const LobeLight& l : lobeLights(cloud, up)) EXPECT_EQ(l.sun + l.sky, 2.0);
  const glm::dvec3 n(0.0, -1.0, 0.0), to_sun = glm::normalize(glm::dvec3(0.3, -1.0, 0.5));
  const glm::dvec3 d(0.0, 1.0, 0.0);
  EXPECT_DOUBLE_EQ(heapIntensity(cloud, LobeLight{0.3, 0.6, 0.5}, 0.4, n, to_sun, d, 0.7),
                   gardnerIntensity(cloud.shading, 0.4, n, to_sun, -d));
}

TEST(HeapLight, EquationWithSunSkyAndForwardScattering) {
  EllipsoidCloud cloud;
  cloud.light_extinction = 0.02;
  cloud.shading = {0.3, 0.2, 0.0, 8.0};
  const glm::dvec3 to_sun = glm::normalize(glm::dvec3(0.0, 1.0, 0.2));  // behind the surface
  const glm::dvec3 d(0.0, 1.0, 0.0), n(0.0, -1.0, 0.0);  // looking north at a face turned south
  const LobeLight light{0.5, 0.8, 0.9};  // sun at the centre, sky, sun at the sunward point
  // The surface's sunlight runs from the centre's (n.L = -1) to the sunward point's (n.L = 1):
  // S = 0.5 + 0.4 (1 + n.L) / 2. The skin's diffuse max(0, (n.L + w) / (1 + w)) is 0 here,
  // so I = (1 - a) t It + a K + S P / (4 pi) TR, with P the Cornette-Shanks phase (g = 0.85)
  // at cos theta = d . L.
  const double n_dot_l = glm::dot(n, to_sun);
  ASSERT_LT(n_dot_l, -kSkinWrap);
  const double sun = 0.5 + 0.4 * 0.5 * (1.0 + n_dot_l);
  const double c = glm::dot(d, to_sun), g = 0.85;
  const double phase = 1.5 * (1.0 - g * g) / (2.0 + g * g) * (1.0 + c * c) /
                       std::pow(1.0 + g * g - 2.0 * g * c, 1.5);
  const double expected = 0.7 * 0.2 * 0.4 + 0.3 * 0.8 + sun * phase / (4.0 * M_PI) * 0.25;
  EXPECT_NEAR(heapIntensity(cloud, light, 0.4, n, to_sun, d, 0.25), expected, 1e-12);
  // A face turned to the sun takes the sunward point's light through its skin; seen from the
  // sun's side (cos theta = -1, no highlight with s = 0):
  // I = (1 - a)((1 - t) S_face (1 + w) / (1 + w) + t It) + a K + S_face P(-1) / (4 pi) TR.
  const double back_phase = 1.5 * (1.0 - g * g) / (2.0 + g * g) * 2.0 / std::pow(1.0 + g, 3.0);
  EXPECT_NEAR(heapIntensity(cloud, light, 0.4, to_sun, to_sun, -to_sun, 0.25),
              0.7 * (0.8 * 0.9 + 0.2 * 0.4) + 0.3 * 0.8 + 0.9 * back_phase / (4.0 * M_PI) * 0.25,
              1e-12);
  // A thin edge against the sun gives off more per unit opacity than the opaque body.
  EXPECT_GT(heapIntensity(cloud, light, 0.4, n, to_sun, d, 0.9),
            1.2 * heapIntensity(cloud, light, 0.4, n, to_sun, d, 0.0));
}

}  // namespace
}  // namespace nephele
