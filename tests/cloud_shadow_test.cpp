// The ground's cloud shadows (MODEL.md section 16): one lobe's share of the sunlight against
// its closed form, the mean-opacity table, a field's shadows against the heaps' own cover,
// and no NaN for any sun.
#include "world/formations/cloud_shadow.h"

#include <gtest/gtest.h>

#include <cmath>

#include "world/automaton/cloud_density.h"
#include "world/formations/ellipsoid.h"
#include "world/formations/weather.h"
#include "world/scene.h"

namespace nephele {
namespace {

EllipsoidCloud sphereCloud(double radius, glm::dvec3 centre) {
  EllipsoidCloud cloud;  // the cumulus genus's thresholds and texture offset (genus.cpp)
  cloud.light_extinction = 0.02;
  cloud.threshold_centre = -0.4;
  cloud.threshold_limb = 0.4;
  cloud.transition = 0.08;
  cloud.texture.gardner.t0 = 1.0;
  Ellipsoid e;
  e.radii = glm::dvec3(radius);
  e.centre = centre;
  cloud.ellipsoids = {e};
  return cloud;
}

TEST(CloudShadowTest, MeanOpacityRisesTowardsTheCentreWithinZeroAndOne) {
  const ShadowTable table = meanOpacityTable(sphereCloud(300.0, {0, 0, 1500}));
  for (int i = 0; i < kShadowTableSize; ++i) {
    EXPECT_GE(table[std::size_t(i)], 0.0f);
    EXPECT_LE(table[std::size_t(i)], 1.0f);
    if (i > 0) {
      EXPECT_GE(table[std::size_t(i)], table[std::size_t(i) - 1]) << i;
    }
  }
  // Gardner eq. 11 with T1 below 0: opaque at the centre whatever the texture, clear at the
  // limb for the texture's values below T2.
  EXPECT_EQ(table.back(), 1.0f);
  EXPECT_LT(table.front(), 0.5f);
  EXPECT_NEAR(meanOpacity(table, 0.5), table[16], 1e-6);
  EXPECT_NEAR(meanOpacity(table, 1.0 / 64.0), 0.5 * (table[0] + table[1]), 1e-6);
}

// A sphere of radius r seen along the sun from a ground point: the ray passes at rho r from
// its centre, so g = 1 - rho^2 and the chord is 2 r sqrt(g).
TEST(CloudShadowTest, OneLobeLetsThroughItsClosedForm) {
  const double r = 400.0;
  const glm::dvec3 centre(1000.0, -500.0, 1500.0);
  const EllipsoidCloud cloud = sphereCloud(r, centre);
  const ShadowTable table = meanOpacityTable(cloud);
  const ShadowCaster caster{centre, worldToUnitSphere(cloud.ellipsoids[0]), r, 0.02, 0};
  const glm::dvec3 to_sun = glm::normalize(glm::dvec3(0.3, -0.2, 1.0));
  // The centre's shadow on the ground, then points across it.
  const glm::dvec3 under = centre - centre.z / to_sun.z * to_sun;
  const glm::dvec3 across = glm::normalize(glm::cross(to_sun, glm::dvec3(1.0, 0.0, 0.0)));
  for (double rho : {0.0, 0.3, 0.7, 0.95}) {
    // A point on the ground whose ray to the sun passes rho r from the centre.
    const glm::dvec3 offset = rho * r * across;
    const glm::dvec3 p = under + offset - offset.z / to_sun.z * to_sun;
    ASSERT_NEAR(p.z, 0.0, 1e-6);
    const double g = 1.0 - rho * rho;
    const double expected =
        1.0 - meanOpacity(table, g) * (1.0 - diffuseTransmittance(0.02 * 2.0 * r * std::sqrt(g)));
    EXPECT_NEAR(casterSunlight(caster, table, p, to_sun), expected, 1e-9) << rho;
  }
  const glm::dvec3 beside = under + 1.2 * r / std::sqrt(1.0 - across.z * across.z) * across;
  EXPECT_EQ(casterSunlight(caster, table, {beside.x, beside.y, 0.0}, to_sun), 1.0);
  // Above the lobe, nothing shadows; inside it, the chord runs from the point on.
  EXPECT_EQ(casterSunlight(caster, table, centre + glm::dvec3(0, 0, 2 * r), to_sun), 1.0);
  const double inside = casterSunlight(caster, table, centre, to_sun);
  EXPECT_NEAR(inside, 1.0 - table.back() * (1.0 - diffuseTransmittance(0.02 * r)), 1e-9);
}

Scene fieldScene(double elevation_deg) {
  Scene scene;
  WeatherLayer w = typicalWeatherLayer(CloudType::kCumulus, 0.4);
  const WeatherClouds clouds = weatherClouds(w, "w", 7);
  scene.fields = clouds.fields;
  scene.sun.elevation_deg = elevation_deg;
  scene.camera.position = {0.0, 0.0, 3000.0};
  return scene;
}

// A cumulus field at 40 % seen from above: its shadows cover a share of the ground near the
// heaps' own cover (larger, as a low sun stretches them; smaller, as the limbs let light by).
TEST(CloudShadowTest, AFieldShadowsAboutItsOwnCover) {
  const Scene scene = fieldScene(60.0);
  const CloudShadows shadows(scene, {}, true);
  ASSERT_FALSE(shadows.empty());
  int shadowed = 0, n = 0;
  for (double y = -5000.0; y < 5000.0; y += 50.0)
    for (double x = -5000.0; x < 5000.0; x += 50.0, ++n) {
      const double s = shadows.sunlight({x, y});
      ASSERT_TRUE(s >= 0.0 && s <= 1.0) << x << "," << y << ": " << s;
      shadowed += s < 0.5;
    }
  const double share = double(shadowed) / n;
  EXPECT_GT(share, 0.15);
  EXPECT_LT(share, 0.7);
}

TEST(CloudShadowTest, EverySunGivesASunlightShareWithinZeroAndOne) {
  for (double elevation : {-10.0, 0.0, 0.99, 1.0, 3.0, 45.0, 89.9, 90.0}) {
    const CloudShadows shadows(fieldScene(elevation), {}, true);
    EXPECT_EQ(shadows.empty(), elevation < 1.0) << elevation;
    for (double x = -20000.0; x <= 20000.0; x += 997.0) {
      const double s = shadows.sunlight({x, 0.5 * x});
      EXPECT_TRUE(s >= 0.0 && s <= 1.0) << elevation << " at " << x << ": " << s;
    }
  }
}

// The planes that cast (MODEL.md section 16, "sky planes"): the kMaxCastingPlanes lowest,
// lowest first, none with the sun below kMinShadowElevationDeg; the sun's crossing of a plane.
TEST(CloudShadowTest, TheLowestPlanesCastWhileTheSunIsUp) {
  Scene scene;
  for (int i = 0; i < kMaxCastingPlanes + 2; ++i) {
    CloudLayer layer;
    layer.altitude_m = 1000.0 * double((7 * i) % (kMaxCastingPlanes + 2)) + 500.0;
    scene.layers.push_back(layer);
  }
  scene.sun.elevation_deg = 30.0;
  const std::vector<std::size_t> casting = castingPlanes(scene);
  ASSERT_EQ(casting.size(), std::size_t(kMaxCastingPlanes));
  for (std::size_t k = 0; k < casting.size(); ++k)
    EXPECT_EQ(scene.layers[casting[k]].altitude_m, 1000.0 * double(k) + 500.0);
  scene.sun.elevation_deg = 0.5 * kMinShadowElevationDeg;
  EXPECT_TRUE(castingPlanes(scene).empty());
  // From a point 1 km under a plane, with the sun 45 degrees up in the east, 1 km east.
  const glm::dvec2 q =
      planeCrossing({10.0, 20.0, 500.0}, 1500.0, glm::normalize(glm::dvec3(1.0, 0.0, 1.0)));
  EXPECT_NEAR(q.x, 1010.0, 1e-9);
  EXPECT_NEAR(q.y, 20.0, 1e-9);
}

// Shadows on what lies between the ground and the casters (MODEL.md section 16, "heaps under
// clouds"): a point under a lobe, anywhere on the sun's line through it, takes the lobe's share
// for the chord above it alone (none once above the lobe); the lobe's own heap, given as the
// envelope the point lies on, is left out; an opaque plane above takes all the sunlight, one
// below it none.
TEST(CloudShadowTest, CloudsShadowWhatLiesBelowThemAlone) {
  const double r = 400.0;
  const glm::dvec3 centre(0.0, 0.0, 2000.0);
  Scene scene;
  scene.sun.elevation_deg = 50.0;
  scene.clouds.push_back(sphereCloud(r, centre));
  const CloudShadows shadows(scene, {}, true);
  const glm::dvec3 to_sun = shadows.toSun();
  const ShadowTable table = meanOpacityTable(scene.clouds[0]);
  const ShadowCaster caster{centre, worldToUnitSphere(scene.clouds[0].ellipsoids[0]), r, 0.02, 0};
  // Along the sun's line 150 m off the centre: below, inside and above the lobe.
  const glm::dvec3 off = 150.0 * glm::normalize(glm::cross(to_sun, glm::dvec3(0.0, 0.0, 1.0)));
  for (double s : {-3000.0, -1000.0, -100.0, 0.0, 200.0, 600.0}) {
    const glm::dvec3 p = centre + off + s * to_sun;
    EXPECT_NEAR(shadows.sunlightAt(p), casterSunlight(caster, table, p, to_sun), 1e-12) << s;
  }
  EXPECT_LT(shadows.sunlightAt(centre + off - 1000.0 * to_sun), 0.9);
  EXPECT_EQ(shadows.sunlightAt(centre + off + 600.0 * to_sun), 1.0);
  EXPECT_EQ(shadows.sunlight(glm::dvec2(centre + off - centre.z / to_sun.z * to_sun)),
            shadows.sunlightAt(centre + off - centre.z / to_sun.z * to_sun));
  const HeapEnvelope own{centre, glm::dvec3(r), 0.02};
  EXPECT_EQ(shadows.sunlightAt(centre + off - 100.0 * to_sun, &own), 1.0);
  const HeapEnvelope other{centre + glm::dvec3(0.0, 0.0, -2.0 * r), glm::dvec3(r), 0.02};
  EXPECT_LT(shadows.sunlightAt(centre + off - 1000.0 * to_sun, &other), 0.9);

  CloudLayer deck;
  deck.altitude_m = 3000.0;
  deck.threshold = -1.0;  // opaque whatever the texture
  deck.transition = 0.1;
  scene.layers.push_back(deck);
  const PlaneShadows planes(scene);
  EXPECT_EQ(planes.sunlight({0.0, 0.0, 2999.0}), 0.0);
  EXPECT_EQ(planes.sunlight({0.0, 0.0, 3000.0}), 1.0);  // a plane never shadows itself
  const SceneSunlight both{&planes, &shadows};
  EXPECT_EQ(both.at({0.0, 0.0, 5.0}), 0.0);
  scene.sun.elevation_deg = 0.5 * kMinShadowElevationDeg;
  EXPECT_TRUE(PlaneShadows(scene).empty());
}

}  // namespace
}  // namespace nephele
