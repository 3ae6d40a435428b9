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

// MODEL.md section 14, against values worked by hand. Two spheres of radius 100 m, centres
// 100 m apart one above the other, are one heap (each centre lies within the other); their
// envelope has the second moments of the two: centroid 1050 m, horizontal variance
// 100^2 / 5, vertical 100^2 / 5 + 50^2, so semi-axes 100 m and sqrt(100^2 + 5 50^2) = 150 m,
// and it is filled (two volumes of 4/3 pi 100^3 over 4/3 pi 100 100 150: more than 1, so 1).
// A sphere 5 km away is a heap of its own, its envelope itself.
TEST(HeapLight, EnvelopeOfEachHeapAndTheDepthThroughIt) {
  EllipsoidCloud cloud;
  cloud.light_extinction = 0.02;
  Ellipsoid lower, upper, aside;
  lower.radii = upper.radii = aside.radii = glm::dvec3(100.0);
  lower.centre = {0.0, 0.0, 1000.0};
  upper.centre = {0.0, 0.0, 1100.0};
  aside.centre = {5000.0, 0.0, 1000.0};
  cloud.ellipsoids = {lower, upper, aside};
  const std::vector<HeapEnvelope> envelopes = heapEnvelopes(cloud);
  ASSERT_EQ(envelopes.size(), 3u);
  for (int i : {0, 1}) {
    EXPECT_NEAR(envelopes[i].centre.z, 1050.0, 1e-9);
    EXPECT_NEAR(envelopes[i].radii.x, 100.0, 1e-9);
    EXPECT_NEAR(envelopes[i].radii.z, 150.0, 1e-9);
    EXPECT_DOUBLE_EQ(envelopes[i].extinction, 0.02);
  }
  EXPECT_NEAR(envelopes[2].centre.x, 5000.0, 1e-9);
  EXPECT_NEAR(envelopes[2].radii.y, 100.0, 1e-9);
  EXPECT_NEAR(envelopes[2].extinction, 0.02, 1e-12);
  auto two_stream = [](double tau) { return 1.0 / (1.0 + 0.75 * (1.0 - 0.85) * tau); };
  const glm::dvec3 up(0.0, 0.0, 1.0), down(0.0, 0.0, -1.0), west(-1.0, 0.0, 0.0);
  // The bottom of the heap, facing down, with the sun overhead: the whole 300 m of the
  // envelope above it (900 m to 1200 m), counted fully since the face looks away from it.
  const HeapLight bottom = heapLightAt(envelopes[0], {0.0, 0.0, 900.0}, down, up);
  EXPECT_NEAR(bottom.sun, two_stream(0.02 * 300.0), 1e-12);
  EXPECT_NEAR(bottom.sky, 0.5 + 0.5 * two_stream(0.02 * 300.0), 1e-12);
  // The top takes all the light; a west face with the sun in the east looks through the
  // envelope at 1000 m, where its half-width is 100 sqrt(1 - (50 / 150)^2), counted by
  // (1 - n.L) / 2 = 1; a face turned to 60 degrees from the sun counts it by (1 - cos 60) / 2.
  const HeapLight top = heapLightAt(envelopes[1], {0.0, 0.0, 1200.0}, up, up);
  EXPECT_DOUBLE_EQ(top.sun, 1.0);
  EXPECT_DOUBLE_EQ(top.sky, 1.0);
  const double width = 2.0 * 100.0 * std::sqrt(1.0 - 1.0 / 9.0);
  const glm::dvec3 east(1.0, 0.0, 0.0);
  EXPECT_NEAR(heapLightAt(envelopes[0], {-100.0, 0.0, 1000.0}, west, east).sun,
              two_stream(0.02 * width), 1e-9);
  const glm::dvec3 half_way(0.5, 0.0, std::sqrt(0.75));
  EXPECT_NEAR(heapLightAt(envelopes[0], {-100.0, 0.0, 1000.0}, half_way, east).sun,
              two_stream(0.02 * width * 0.25), 1e-9);
  // The unscattered beam falls as exp(-depth) over the same depth.
  EXPECT_NEAR(heapLightAt(envelopes[0], {-100.0, 0.0, 1000.0}, west, east).direct,
              std::exp(-0.02 * width), 1e-9);
  EXPECT_DOUBLE_EQ(top.direct, 1.0);
  // Parts named by the cloud override the grouping: three parts, three envelopes.
  EllipsoidCloud parted = cloud;
  parted.parts = {0, 1, 2};
  EXPECT_NEAR(heapEnvelopes(parted)[0].radii.z, 100.0, 1e-9);
  // Off: every point takes all the light, and the intensity is eq. 8, its sun terms times the
  // sunlight other clouds let through (MODEL.md section 16); the sky light is not used.
  cloud.light_extinction = 0.0;
  for (const HeapEnvelope& e : heapEnvelopes(cloud)) {
    const HeapLight light = heapLightAt(e, e.centre, down, up);
    EXPECT_EQ(light.sun + light.sky, 2.0);
  }
  const glm::dvec3 n(0.0, -1.0, 0.0), to_sun = glm::normalize(glm::dvec3(0.3, -1.0, 0.5));
  const glm::dvec3 d(0.0, 1.0, 0.0);
  EXPECT_DOUBLE_EQ(heapIntensity(cloud, HeapLight{1.0, 0.6}, 0.4, n, to_sun, d, 0.7),
                   gardnerIntensity(cloud.shading, 0.4, n, to_sun, -d));
  const DiffuseHighlight lit = diffuseHighlight(cloud.shading, n, to_sun, -d);
  EXPECT_DOUBLE_EQ(heapIntensity(cloud, HeapLight{0.3, 0.6}, 0.4, n, to_sun, d, 0.7),
                   gardnerIntensity(cloud.shading, 0.3 * lit.diffuse, 0.3 * lit.highlight, 0.4));
}

TEST(HeapLight, EquationWithSunSkyAndForwardScattering) {
  EllipsoidCloud cloud;
  cloud.light_extinction = 0.02;
  cloud.shading = {0.3, 0.2, 0.0, 8.0};
  const glm::dvec3 to_sun = glm::normalize(glm::dvec3(0.0, 1.0, 0.2));  // behind the surface
  const glm::dvec3 d(0.0, 1.0, 0.0), n(0.0, -1.0, 0.0);  // looking north at a face turned south
  // Sun and sky reaching the point, and the unscattered beam B that alone is scattered forward.
  const HeapLight light{0.5, 0.8, 0.3};
  // The skin's diffuse max(0, (n.L + w) / (1 + w)) is 0 here, so
  // I = (1 - a) t It + a K + B P / (4 pi) TR, with P the Cornette-Shanks phase (g = 0.85) at
  // cos theta = d . L.
  ASSERT_LT(glm::dot(n, to_sun), -kSkinWrap);
  const double c = glm::dot(d, to_sun), g = 0.85;
  const double phase = 1.5 * (1.0 - g * g) / (2.0 + g * g) * (1.0 + c * c) /
                       std::pow(1.0 + g * g - 2.0 * g * c, 1.5);
  const double expected = 0.7 * 0.2 * 0.4 + 0.3 * 0.8 + 0.3 * phase / (4.0 * M_PI) * 0.25;
  EXPECT_NEAR(heapIntensity(cloud, light, 0.4, n, to_sun, d, 0.25), expected, 1e-12);
  // A face turned to the sun takes it through its skin; seen from the sun's side
  // (cos theta = -1, no highlight with s = 0):
  // I = (1 - a)((1 - t) S (1 + w) / (1 + w) + t It) + a K + B P(-1) / (4 pi) TR.
  const double back_phase = 1.5 * (1.0 - g * g) / (2.0 + g * g) * 2.0 / std::pow(1.0 + g, 3.0);
  EXPECT_NEAR(heapIntensity(cloud, light, 0.4, to_sun, to_sun, -to_sun, 0.25),
              0.7 * (0.8 * 0.5 + 0.2 * 0.4) + 0.3 * 0.8 + 0.3 * back_phase / (4.0 * M_PI) * 0.25,
              1e-12);
  // A thin edge against the sun gives off more per unit opacity than the opaque body.
  EXPECT_GT(heapIntensity(cloud, light, 0.4, n, to_sun, d, 0.9),
            1.2 * heapIntensity(cloud, light, 0.4, n, to_sun, d, 0.0));
}

// MODEL.md section 14, "one mass": a lobe's normal is bent towards its heap envelope's by
// kHeapNormalBend, and left alone without heap light or at the envelope's centre.
TEST(HeapLight, LobeNormalBendsTowardsTheHeapsOwn) {
  HeapEnvelope envelope;
  envelope.centre = {0.0, 0.0, 1000.0};
  envelope.radii = {200.0, 200.0, 100.0};
  envelope.extinction = 0.02;
  const glm::dvec3 east(1.0, 0.0, 0.0), up(0.0, 0.0, 1.0);
  // On the envelope's top the heap faces up: a lobe facing east there is lit as facing
  // normalize(0.4 east + 0.6 up).
  const glm::dvec3 top(0.0, 0.0, 1100.0);
  const glm::dvec3 bent = heapLitNormal(envelope, top, east);
  const glm::dvec3 expected = glm::normalize((1.0 - kHeapNormalBend) * east + kHeapNormalBend * up);
  EXPECT_NEAR(glm::distance(bent, expected), 0.0, 1e-12);
  EXPECT_NEAR(glm::length(bent), 1.0, 1e-12);
  // The envelope's normal is its quadric's gradient, not the direction from its centre: at
  // (100, 0, 1000 + 50 sqrt 3) it is along (100 / 200^2, 0, 50 sqrt 3 / 100^2).
  const glm::dvec3 p(100.0, 0.0, 1000.0 + 50.0 * std::sqrt(3.0));
  const glm::dvec3 gradient =
      glm::normalize(glm::dvec3(100.0 / 4e4, 0.0, 50.0 * std::sqrt(3.0) / 1e4));
  EXPECT_NEAR(glm::distance(heapLitNormal(envelope, p, gradient), gradient), 0.0, 1e-12);
  // Opposite normals still give a unit normal (the blend is at least |1 - 2b| long).
  const glm::dvec3 away = heapLitNormal(envelope, top, -up);
  EXPECT_NEAR(glm::length(away), 1.0, 1e-12);
  EXPECT_GT(away.z, 0.0);
  // Unchanged at the centre and without heap light.
  EXPECT_EQ(heapLitNormal(envelope, envelope.centre, east), east);
  envelope.extinction = 0.0;
  EXPECT_EQ(heapLitNormal(envelope, top, east), east);
}

}  // namespace
}  // namespace nephele
