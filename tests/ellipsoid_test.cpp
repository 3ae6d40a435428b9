// The ellipsoid primitive (MODEL.md sections 4 and 5): quadric, ray hits, the limb function g
// against the definition of MODEL.md section 4 restated here, the silhouette conic, the eye-space
// box, solid textures, the in-cloud model and targets.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "world/formations/ellipsoid.h"
#include "world/formations/ellipsoid_cloud.h"
#include "world/scene.h"
#include "world/target.h"
#include "world/textures/solid_texture.h"

namespace nephele {
namespace {

Ellipsoid tilted() {
  return {{500.0, 300.0, 120.0}, {200.0, 900.0, 1500.0}, {30.0, 20.0, -15.0}};
}

// MODEL.md section 4, restated: Q(X) = (X - C)^T M (X - C) - 1 with M from the nine parameters,
// the ray quadratic a s^2 + b s + c and its discriminant.
struct Quadratic {
  double a, b, c;
};
Quadratic rayQuadratic(const Ellipsoid& e, glm::dvec3 eye, glm::dvec3 d) {
  const glm::dmat3 r = bodyToWorld(e.orientation);
  const glm::dmat3 inv_s2(1.0 / (e.radii.x * e.radii.x), 0, 0, 0, 1.0 / (e.radii.y * e.radii.y), 0,
                          0, 0, 1.0 / (e.radii.z * e.radii.z));
  const glm::dmat3 m = r * inv_s2 * glm::transpose(r);
  const glm::dvec3 o = eye - e.centre;
  return {glm::dot(d, m * d), 2.0 * glm::dot(d, m * o), glm::dot(o, m * o) - 1.0};
}

glm::dvec3 randomUnit(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  return glm::normalize(glm::dvec3(n(rng), n(rng), n(rng)));
}

// Issue 31, item 1: a frame's work budget keeps the `budget` ellipsoids of largest projected
// size (near and large before far and small, none behind the camera), whatever order the
// clouds come in, and changes nothing within it.
TEST(EllipsoidBudget, KeepsTheLargestInViewAndIsDeterministic) {
  Scene scene;
  scene.camera.position = {0.0, 0.0, 0.0};  // heading 0: looking north (+Y)
  auto cloud = [](const char* name, double y, double radius, int n) {
    EllipsoidCloud c;
    c.name = name;
    c.texture.seed = c.texture.gardner.seed = 7;
    for (int i = 0; i < n; ++i) {
      Ellipsoid e;
      e.radii = glm::dvec3(radius);
      e.centre = {10.0 * i, y, 0.0};
      c.ellipsoids.push_back(e);
    }
    return c;
  };
  scene.clouds = {cloud("far", 10000.0, 50.0, 6), cloud("near", 1000.0, 50.0, 4),
                  cloud("behind", -1000.0, 500.0, 5)};
  const Scene kept = *withinEllipsoidBudget(scene, 7.0);
  EXPECT_EQ(ellipsoidCount(kept), 7u);
  ASSERT_EQ(kept.clouds.size(), 2u);  // the cloud behind the camera is gone, unmerged
  EXPECT_EQ(kept.clouds[0].name, "far");
  // Its first two lobes (ties by lobe order), and the body of the three the first choice
  // dropped (lobes 3 to 5, about their mean centre, its moments' radii times 1.5), for which
  // the lobes are chosen again with one place fewer (lobe 2 goes unmerged).
  ASSERT_EQ(kept.clouds[0].ellipsoids.size(), 3u);
  EXPECT_EQ(kept.clouds[0].ellipsoids[1].centre, scene.clouds[0].ellipsoids[1].centre);
  EXPECT_NEAR(kept.clouds[0].ellipsoids[2].centre.x, 40.0, 1e-9);
  EXPECT_NEAR(kept.clouds[0].ellipsoids[2].centre.y, 10000.0, 1e-9);
  EXPECT_GT(kept.clouds[0].ellipsoids[2].radii.x, 75.0);  // spread along x by the lobes
  EXPECT_NEAR(kept.clouds[0].ellipsoids[2].radii.y, 75.0, 1e-6);
  EXPECT_EQ(kept.clouds[0].texture.seed, 0u);  // thinned: the shared texture
  EXPECT_EQ(kept.clouds[1].name, "near");
  EXPECT_EQ(kept.clouds[1].ellipsoids.size(), 4u);  // every near lobe
  EXPECT_EQ(kept.clouds[1].texture.seed, 7u);
  EXPECT_EQ(ellipsoidCount(*withinEllipsoidBudget(scene, 7.0)), ellipsoidCount(kept));
  EXPECT_EQ(withinEllipsoidBudget(scene, 7.0)->clouds[0].ellipsoids[2].centre,
            kept.clouds[0].ellipsoids[2].centre);
  EXPECT_FALSE(withinEllipsoidBudget(scene, 15.0));  // within: unchanged
  EXPECT_FALSE(withinEllipsoidBudget(scene, 0.0));   // 0: no budget
}

// A footprint is the projected bounding square of the largest radius, clipped to the view,
// in views: restated here for a 90 degree square view, where a sphere of radius r at distance
// a ahead spans tan = r / sqrt(a^2 - r^2) either side of its centre's image.
TEST(EllipsoidBudget, FootprintIsTheClippedBoundingSquareInViews) {
  Camera camera;
  camera.position = {0.0, 0.0, 0.0};  // heading 0: looking north (+Y)
  camera.vfov_deg = 90.0;
  camera.width = camera.height = 100;
  const ViewBasis basis = viewBasis(camera);
  auto sphere = [](glm::dvec3 centre, double r) {
    Ellipsoid e;
    e.centre = centre;
    e.radii = {r, 0.5 * r, 0.25 * r};  // the largest radius counts
    return e;
  };
  // Centred: half side 3/4 of the view's half side, so (3/4)^2 of the view.
  EXPECT_NEAR(ellipsoidFootprint(sphere({0.0, 5.0, 0.0}, 3.0), camera, basis), 0.5625, 1e-12);
  // Its centre on the right edge: half of that square is inside.
  EXPECT_NEAR(ellipsoidFootprint(sphere({5.0, 5.0, 0.0}, 3.0), camera, basis), 0.28125, 1e-12);
  EXPECT_EQ(ellipsoidFootprint(sphere({0.0, 2.0, 0.0}, 3.0), camera, basis), 1.0);   // at the eye
  EXPECT_EQ(ellipsoidFootprint(sphere({0.0, -9.0, 0.0}, 3.0), camera, basis), 0.0);  // behind
  EXPECT_EQ(ellipsoidFootprint(sphere({50.0, 5.0, 0.0}, 3.0), camera, basis), 0.0);  // beside

  // The overdraw budget takes the largest first while their footprints fit: ten such lobes of
  // 0.5625 views each, the nearest slightly larger, within 2 views keep the three nearest.
  Scene scene;
  scene.camera = camera;
  EllipsoidCloud cloud;
  for (int i = 0; i < 10; ++i) cloud.ellipsoids.push_back(sphere({0.0, 5.0 + 1e-3 * i, 0.0}, 3.0));
  scene.clouds = {cloud};
  // The first choice keeps three and merges the other seven into a body whose footprint (its
  // radii 1.5 times theirs) is the whole view, half the budget; in the view left the lobes are
  // chosen again: the nearest, and the body.
  const std::optional<Scene> kept = withinEllipsoidBudget(scene, 0.0, 2.0);
  ASSERT_TRUE(kept);
  ASSERT_EQ(ellipsoidCount(*kept), 2u);
  EXPECT_EQ(kept->clouds[0].ellipsoids[0].centre, cloud.ellipsoids[0].centre);
  EXPECT_NEAR(kept->clouds[0].ellipsoids[1].centre.y, 5.0 + 1e-3 * 6.0, 1e-9);
  EXPECT_EQ(ellipsoidFootprint(kept->clouds[0].ellipsoids[1], camera, basis), 1.0);
  EXPECT_FALSE(withinEllipsoidBudget(scene, 0.0, 6.0));  // 5.6 views: within
  // The largest always, and the body of the rest.
  EXPECT_EQ(ellipsoidCount(*withinEllipsoidBudget(scene, 0.0, 0.1)), 2u);
}

TEST(Ellipsoid, SymmetricEigenReconstructs) {
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  for (int trial = 0; trial < 50; ++trial) {
    glm::dmat3 m;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j <= i; ++j) m[i][j] = m[j][i] = u(rng);
    const SymmetricEigen e = symmetricEigen(m);
    EXPECT_LE(e.values[0], e.values[1]);
    EXPECT_LE(e.values[1], e.values[2]);
    for (int k = 0; k < 3; ++k) {
      const glm::dvec3 residual = m * e.vectors[k] - e.values[k] * e.vectors[k];
      EXPECT_LT(glm::length(residual), 1e-9);
      EXPECT_NEAR(glm::length(e.vectors[k]), 1.0, 1e-12);
    }
  }
}

TEST(Ellipsoid, RayHitsLieOnTheQuadric) {
  const Ellipsoid e = tilted();
  const glm::dvec3 eye(-3000.0, -2000.0, 400.0);
  const EllipsoidView view(e, eye);
  std::mt19937_64 rng(7);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    // Directions around the one to the centre, some hitting, some missing.
    const glm::dvec3 d = glm::normalize(e.centre - eye) + 0.08 * randomUnit(rng);
    const Quadratic q = rayQuadratic(e, eye, d);
    const auto span = view.intersect(d);
    ASSERT_EQ(span.has_value(), q.b * q.b - 4 * q.a * q.c > 0.0) << i;
    if (!span) continue;
    ++hits;
    EXPECT_NEAR(quadricValue(e, eye + span->near * d), 0.0, 1e-9);
    EXPECT_NEAR(quadricValue(e, eye + span->far * d), 0.0, 1e-9);
    EXPECT_LE(span->near, span->far);
  }
  EXPECT_GT(hits, 200);
  EXPECT_LT(hits, 1800);
}

// 100 km from the origin the hit is as exact, relative to the ellipsoid, as at the origin.
TEST(Ellipsoid, FarFromTheOriginStaysExact) {
  Ellipsoid near = tilted(), far = tilted();
  const glm::dvec3 shift(1.0e5, -1.0e5, 0.0);
  far.centre += shift;
  const glm::dvec3 eye(-3000.0, -2000.0, 400.0), d = glm::normalize(near.centre - eye);
  const auto a = EllipsoidView(near, eye).intersect(d),
             b = EllipsoidView(far, eye + shift).intersect(d);
  ASSERT_TRUE(a && b);
  EXPECT_NEAR(a->near, b->near, 1e-7);
  EXPECT_NEAR(EllipsoidView(near, eye).limb(d), EllipsoidView(far, eye + shift).limb(d), 1e-9);
}

TEST(Ellipsoid, LimbFunctionFollowsTheSpec) {
  const Ellipsoid e = tilted();
  const glm::dvec3 eye(-2500.0, -1500.0, 300.0);
  const EllipsoidView view(e, eye);
  const glm::dmat3& k = view.discriminantForm();
  const double lambda = view.limbEigenvalue();
  const glm::dvec3 axis = view.limbAxis();
  // K's eigenpair: K a = lam a, the one positive eigenvalue; a points at the ellipsoid.
  EXPECT_LT(glm::length(k * axis - lambda * axis), 1e-9 * lambda);
  const SymmetricEigen eigen = symmetricEigen(k);
  EXPECT_LT(eigen.values[1], 0.0);
  EXPECT_GT(eigen.values[2], 0.0);
  EXPECT_GT(glm::dot(axis, e.centre - eye), 0.0);
  EXPECT_NEAR(view.limb(axis), 1.0, 1e-12);

  std::mt19937_64 rng(11);
  for (int i = 0; i < 2000; ++i) {
    const glm::dvec3 d = (glm::normalize(e.centre - eye) + 0.2 * randomUnit(rng)) * 3.7;
    const Quadratic q = rayQuadratic(e, eye, d);
    const double delta = q.b * q.b - 4.0 * q.a * q.c;
    EXPECT_NEAR(glm::dot(d, k * d), delta, 1e-9 * std::abs(q.b * q.b));
    const double expected =
        std::clamp(delta / (lambda * glm::dot(d, axis) * glm::dot(d, axis)), 0.0, 1.0);
    EXPECT_NEAR(view.limb(d), expected, 1e-9) << i;
  }
}

// Rays on the silhouette (found by bisection between a hit and a miss) have g = 0 and lie on
// the silhouette conic.
TEST(Ellipsoid, SilhouetteConicAndLimbAgree) {
  const Ellipsoid e = tilted();
  Camera camera;
  camera.position = {-2500.0, -1500.0, 300.0};
  camera.orientation = {60.0, 15.0, 10.0};
  const ViewBasis basis = viewBasis(camera);
  const EllipsoidView view(e, camera.position);
  const glm::dmat3 conic = silhouetteConic(view, basis);
  const glm::dvec3 to_centre = e.centre - camera.position;
  const glm::dvec2 centre_uv(glm::dot(to_centre, basis.right) / glm::dot(to_centre, basis.forward),
                             glm::dot(to_centre, basis.up) / glm::dot(to_centre, basis.forward));
  for (int k = 0; k < 16; ++k) {
    const double angle = 2.0 * 3.141592653589793 * k / 16;
    const glm::dvec2 step(std::cos(angle), std::sin(angle));
    double lo = 0.0, hi = 1.0;  // in image-plane units from the centre's image
    auto dir = [&](double t) {
      const glm::dvec2 uv = centre_uv + t * step;
      return uv.x * basis.right + uv.y * basis.up + basis.forward;
    };
    ASSERT_TRUE(view.intersect(dir(lo)).has_value());
    ASSERT_FALSE(view.intersect(dir(hi)).has_value());
    for (int i = 0; i < 60; ++i) (view.intersect(dir(0.5 * (lo + hi))) ? lo : hi) = 0.5 * (lo + hi);
    const glm::dvec2 uv = centre_uv + lo * step;
    const glm::dvec3 h(uv, 1.0);
    EXPECT_NEAR(glm::dot(h, conic * h) / glm::dot(h, h), 0.0, 1e-6 * view.limbEigenvalue());
    EXPECT_NEAR(view.limb(dir(lo)), 0.0, 1e-6);
  }
}

// screenBounds against the ellipsoid's own points projected: every point in front of the eye
// that lands on screen lies in the rectangle, and each side not at the screen's edge is
// reached. Three cases: wholly in front, straddling the eye plane (the image runs to the top
// of the screen only), and wholly behind (no rectangle).
TEST(Ellipsoid, ScreenBoundsHoldTheImageTightly) {
  struct Case {
    Ellipsoid e;
    glm::dvec3 eye;
    Orientation look;
  };
  const std::vector<Case> cases = {
      {tilted(), {-2500.0, -1500.0, 300.0}, {60.0, 15.0, 10.0}},
      {{{2000.0, 1500.0, 600.0}, {0.0, 300.0, 1000.0}, {20.0, 0.0, 0.0}},
       {0.0, 0.0, 2.0},
       {0.0, 15.0, 0.0}},
      {{{300.0, 300.0, 300.0}, {0.0, -5000.0, 500.0}, {}}, {0.0, 0.0, 500.0}, {0.0, 0.0, 0.0}}};
  std::mt19937_64 rng(5);
  for (std::size_t c = 0; c < cases.size(); ++c) {
    const auto& [e, eye, look] = cases[c];
    Camera camera;
    camera.position = eye;
    camera.orientation = look;
    camera.width = 640;
    camera.height = 480;
    const ViewBasis basis = viewBasis(camera);
    const glm::dvec4 bounds = screenBounds(e, eye, basis);
    const glm::dmat3 body = bodyToWorld(e.orientation);
    glm::dvec4 seen(1e9, 1e9, -1e9, -1e9);
    for (int i = 0; i < 200000; ++i) {
      const glm::dvec3 p = e.centre + body * (randomUnit(rng) * e.radii) - eye;
      const double z = glm::dot(p, basis.forward);
      if (z <= 0.0) continue;
      const double x = glm::dot(p, basis.right) / (z * basis.tan_half_vfov * basis.aspect);
      const double y = glm::dot(p, basis.up) / (z * basis.tan_half_vfov);
      if (std::abs(x) > 1.0 || std::abs(y) > 1.0) continue;
      seen = {std::min(seen.x, x), std::min(seen.y, y), std::max(seen.z, x), std::max(seen.w, y)};
    }
    SCOPED_TRACE("case " + std::to_string(c));
    if (c == 1) {  // straddling: the image runs to the top of the screen, not the bottom
      EXPECT_EQ(bounds.w, 1.0);
      EXPECT_GT(bounds.y, -1.0);
    }
    if (seen.x > seen.z) {  // nothing on screen
      EXPECT_GT(bounds.x, bounds.z);
      continue;
    }
    EXPECT_LE(bounds.x, seen.x + 1e-9);
    EXPECT_LE(bounds.y, seen.y + 1e-9);
    EXPECT_GE(bounds.z, seen.z - 1e-9);
    EXPECT_GE(bounds.w, seen.w - 1e-9);
    const double tight = 0.01 * std::max(bounds.z - bounds.x, bounds.w - bounds.y);
    for (int side = 0; side < 4; ++side) {
      if (std::abs(bounds[side]) < 1.0) {
        EXPECT_NEAR(bounds[side], seen[side], tight) << side;
      }
    }
  }
}

TEST(Ellipsoid, InvalidParametersAreNamed) {
  Ellipsoid e = tilted();
  EXPECT_EQ(ellipsoidError(e), "");
  e.radii.y = 0.0;
  EXPECT_NE(ellipsoidError(e).find("radius y"), std::string::npos);
  e.radii.y = -1.0;
  EXPECT_NE(ellipsoidError(e).find("> 0"), std::string::npos);
  e.radii.y = std::numeric_limits<double>::quiet_NaN();
  EXPECT_NE(ellipsoidError(e), "");
  e = tilted();
  e.centre.x = std::numeric_limits<double>::infinity();
  EXPECT_NE(ellipsoidError(e).find("centre"), std::string::npos);
}

TEST(Ellipsoid, EyeInsideHasNoSurface) {
  const Ellipsoid e = tilted();
  const EllipsoidView view(e, e.centre + glm::dvec3(10.0, 0.0, 0.0));
  EXPECT_TRUE(view.eyeInside());
  EXPECT_EQ(view.limb({1.0, 0.0, 0.0}), 0.0);
  EXPECT_LT(view.eyeRadius(), 1.0);
}

// The baked sums (MODEL.md section 2, "baked solid texture"): the first two terms over the
// period and the last two over a quarter of it, added with T0 and multiplied, are the solid
// texture of all four terms. Sizes 16 and 4 put the two tables' texel centres at the same
// points, so no interpolation enters.
TEST(SolidTexture, BakedSumsAddUpToTheSolidTexture) {
  GardnerTextureParams params{4, 0.01, 0.013, 0.2, true, 9};
  const GardnerTexture gardner(params);
  const VolumeTable coarse = bakeGardnerSums(gardner, 16, 0, 2);
  const VolumeTable fine = bakeGardnerSums(gardner, 4, 2, 2);
  ASSERT_EQ(coarse.channels, 2);
  const glm::dvec2 period = gardner.period();
  const double t0 = params.t0, k = gardner.normalisation();
  double spread = 0.0;
  for (int z = 0; z < 16; z += 3)
    for (int y = 0; y < 16; y += 5)
      for (int x = 0; x < 16; ++x) {
        const glm::dvec3 p((x + 0.5) / 16 * period.x, (y + 0.5) / 16 * period.y,
                           (z + 0.5) / 16 * period.x);
        const double sx = t0 + coarse.at(x, y, z, 0) + fine.at(x, y, z, 0);
        const double sy = t0 + coarse.at(x, y, z, 1) + fine.at(x, y, z, 1);
        EXPECT_NEAR(k * std::max(sx, 0.0) * std::max(sy, 0.0), gardner.solid(p, 4), 1e-6);
        spread = std::max(spread, std::abs(double(fine.at(x, y, z, 0))));
      }
  EXPECT_GT(spread, 0.05);  // the fine terms are there
  // No terms: zero sums.
  const VolumeTable none = bakeGardnerSums(gardner, 4, 4, 2);
  for (float v : none.values) EXPECT_EQ(v, 0.0f);
}

TEST(SolidTexture, PeriodicInEveryAxisAndFarAway) {
  SolidTextureSpec spec;
  spec.seed = 4;
  const SolidTexture texture(spec);
  const glm::dvec3 period = texture.period();
  const glm::dvec3 p(123.0, 456.0, 789.0);
  for (int axis = 0; axis < 3; ++axis) {
    glm::dvec3 q = p;
    q[axis] += 80.0 * period[axis];
    EXPECT_NEAR(texture.value(p), texture.value(q), 1e-9);
  }
  spec.source = SolidTextureSource::kPerlin;
  spec.perlin_size_log2 = 4;
  const SolidTexture perlin(spec);
  double lo = 1.0, hi = 0.0;
  for (float v : perlin.volume()->values)
    lo = std::min(lo, double(v)), hi = std::max(hi, double(v));
  EXPECT_EQ(lo, 0.0);
  EXPECT_EQ(hi, 1.0);
  EXPECT_NEAR(perlin.value(p), perlin.value(p + perlin.period()), 1e-9);
}

TEST(InCloudModel, ContinuousAcrossTheSurface) {
  EXPECT_EQ(surfaceFade(1.0), 0.0);
  EXPECT_EQ(surfaceFade(1.0 + kInCloudBand), 1.0);
  EXPECT_EQ(veilOpacity(1.0 + kInCloudBand), 0.0);
  EXPECT_NEAR(veilOpacity(1.0), 0.5, 1e-12);
  EXPECT_EQ(veilOpacity(1.0 - kInCloudBand), 1.0);
  for (double rho = 0.5; rho < 1.5; rho += 1e-3) {
    EXPECT_LT(std::abs(surfaceFade(rho + 1e-4) - surfaceFade(rho)), 2e-3);
    EXPECT_LT(std::abs(veilOpacity(rho + 1e-4) - veilOpacity(rho)), 2e-3);
  }
  EllipsoidCloud cloud;
  cloud.ellipsoids = {tilted()};
  const SolidTexture texture(cloud.texture);
  const Sun sun;
  auto only = [&](std::size_t) -> const SolidTexture& { return texture; };
  const Veil far = inCloudVeil({cloud}, only, {0.0, 0.0, 0.0}, sun);
  EXPECT_EQ(far.opacity, 0.0);
  const Veil inside = inCloudVeil({cloud}, only, tilted().centre, sun);
  EXPECT_EQ(inside.opacity, 1.0);
  EXPECT_GT(inside.colour.x, 0.0);
}

TEST(Targets, BoxAndMeshHits) {
  Target box;
  box.centre = {0.0, 100.0, 50.0};
  box.size = {5.0, 10.0, 2.0};
  const auto hit = intersectTarget(box, {0.0, 0.0, 50.0}, {0.0, 1.0, 0.0});
  ASSERT_TRUE(hit);
  EXPECT_NEAR(hit->distance, 90.0, 1e-9);
  EXPECT_NEAR(hit->normal.y, -1.0, 1e-12);
  EXPECT_FALSE(intersectTarget(box, {0.0, 0.0, 50.0}, {0.0, -1.0, 0.0}));

  // A mesh of the same box's front face (a square of two triangles), scaled by `size`.
  auto square = std::make_shared<TriangleMesh>();
  square->vertices = {{-1, -1, -1}, {1, -1, -1}, {1, -1, 1}, {-1, -1, 1}};
  square->triangles = {{0, 1, 2}, {0, 2, 3}};
  Target mesh = box;
  mesh.shape = TargetShape::kMesh;
  mesh.mesh = square;
  for (double x : {-4.9, 0.0, 3.0}) {
    const auto a = intersectTarget(box, {x, 0.0, 51.0}, {0.0, 1.0, 0.0});
    const auto b = intersectTarget(mesh, {x, 0.0, 51.0}, {0.0, 1.0, 0.0});
    ASSERT_TRUE(a && b);
    EXPECT_NEAR(a->distance, b->distance, 1e-9);
  }
  EXPECT_FALSE(intersectTarget(mesh, {5.1, 0.0, 50.0}, {0.0, 1.0, 0.0}));
}

TEST(Cumulus, DeterministicAndValid) {
  const auto a = cumulusEllipsoids(27, {0.0, 0.0, 800.0}, 2000.0, 5);
  const auto b = cumulusEllipsoids(27, {0.0, 0.0, 800.0}, 2000.0, 5);
  ASSERT_EQ(a.size(), 27u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].centre, b[i].centre);
    EXPECT_EQ(ellipsoidError(a[i]), "");
    EXPECT_GT(a[i].centre.z - a[i].radii.z, 700.0);  // nothing far below the base
  }
  EXPECT_EQ(cumulusEllipsoids(1, {0, 0, 0}, 100.0, 1).size(), 1u);
}

}  // namespace
}  // namespace nephele
