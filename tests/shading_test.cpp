#include "world/shading.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace nephele
