#include "world/camera.h"

#include <gtest/gtest.h>

#include <cmath>

namespace nephele {
namespace {

void expectNear(glm::dvec3 actual, glm::dvec3 expected) {
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(actual[i], expected[i], 1e-12) << "component " << i;
}

TEST(Camera, IdentityLooksNorthWithZUp) {
  const glm::dmat3 r = bodyToWorld({});
  expectNear(r[0], {1, 0, 0});
  expectNear(r[1], {0, 1, 0});
  expectNear(r[2], {0, 0, 1});
}

TEST(Camera, HeadingNinetyLooksEast) {
  expectNear(bodyToWorld({90, 0, 0})[1], {1, 0, 0});
}

TEST(Camera, PitchNinetyLooksUp) {
  expectNear(bodyToWorld({0, 90, 0})[1], {0, 0, 1});
}

TEST(Camera, RollNinetyTurnsImageUpToEast) {
  const glm::dmat3 r = bodyToWorld({0, 0, 90});
  expectNear(r[2], {1, 0, 0});
  expectNear(r[0], {0, 0, -1});  // right wing down
}

TEST(Camera, RotationIsOrthonormal) {
  const glm::dmat3 r = bodyToWorld({37, -21, 123});
  const glm::dmat3 identity = glm::transpose(r) * r;
  for (int c = 0; c < 3; ++c)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(identity[c][k], c == k ? 1.0 : 0.0, 1e-12);
  EXPECT_NEAR(glm::determinant(r), 1.0, 1e-12);
}

TEST(Camera, PixelRaysFollowSpecImagePlane) {
  Camera camera;
  camera.width = 200;
  camera.height = 100;
  camera.vfov_deg = 90.0;  // tan(45) = 1
  const ViewBasis basis = viewBasis(camera);
  // Image centre: the optical axis.
  expectNear(rayDirection(basis, camera, 100, 50), {0, 1, 0});
  // Top-left corner: u = -aspect, v = +1.
  expectNear(rayDirection(basis, camera, 0, 0), {-2, 1, 1});
  // Pixel (i, j) centre: u = (2 (i + 0.5) / W - 1) tan W/H.
  const glm::dvec3 d = rayDirection(basis, camera, 10 + 0.5, 20 + 0.5);
  EXPECT_NEAR(d.x, (2.0 * 10.5 / 200 - 1.0) * 2.0, 1e-12);
  EXPECT_NEAR(d.z, 1.0 - 2.0 * 20.5 / 100, 1e-12);
}

}  // namespace
}  // namespace nephele

namespace nephele {
namespace {

// orientationOf inverts bodyToWorld, including rolled, inverted and vertical attitudes (the
// CIGI views compose an entity's attitude with the view's offset through it).
TEST(Camera, OrientationOfInvertsBodyToWorld) {
  for (double h : {0.0, 37.0, 181.0, 359.0})
    for (double p : {-89.0, -30.0, 0.0, 45.0, 89.9})
      for (double r : {-179.0, -20.0, 0.0, 60.0, 180.0}) {
        const glm::dmat3 m = bodyToWorld({h, p, r});
        const glm::dmat3 back = bodyToWorld(orientationOf(m));
        for (int c = 0; c < 3; ++c)
          for (int k = 0; k < 3; ++k)
            EXPECT_NEAR(back[c][k], m[c][k], 1e-9) << h << " " << p << " " << r;
      }
  for (double p : {-90.0, 90.0}) {  // vertical: the body axes still come back
    const glm::dmat3 m = bodyToWorld({30.0, p, 10.0});
    const glm::dmat3 back = bodyToWorld(orientationOf(m));
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) EXPECT_NEAR(back[c][k], m[c][k], 1e-9) << p;
  }
}

}  // namespace
}  // namespace nephele

namespace nephele {
namespace {

// An off-axis view cut from a centred render: the crop's edges, seen through the render
// camera's own rays, are the frustum's sides to within half a pixel, and its principal point
// is where the optical axis lands.
TEST(Camera, OffAxisViewCropsToTheFrustum) {
  const Frustum cases[] = {
      {-30, 30, -20, 20}, {-20, 40, -10, 25}, {-45, -5, 3, 30}, {-5, 5, -80, 80}};
  for (const Frustum& f : cases) {
    ASSERT_EQ(frustumError(f), "");
    Camera camera;
    camera.height = 200;
    camera.orientation = {30.0, 10.0, 0.0};
    const OffAxisView v = offAxisView(camera, f);
    ASSERT_LE(v.x0 + v.width, v.render.width);
    ASSERT_LE(v.y0 + v.height, v.render.height);
    EXPECT_EQ(v.height, 200);
    const ViewBasis basis = viewBasis(v.render);
    auto angle = [&](double x, double y, bool horizontal) {
      const glm::dvec3 d = rayDirection(basis, v.render, x, y);
      const double along = glm::dot(d, basis.forward);
      return std::atan((horizontal ? glm::dot(d, basis.right) : glm::dot(d, basis.up)) / along) *
             180.0 / M_PI;
    };
    const double half_pixel = std::atan(0.5 / v.focal_px) * 180.0 / M_PI * 1.01;
    const double mid_y = v.y0 + 0.5 * v.height, mid_x = v.x0 + 0.5 * v.width;
    EXPECT_NEAR(angle(v.x0, mid_y, true), f.left, half_pixel);
    EXPECT_NEAR(angle(v.x0 + v.width, mid_y, true), f.right, half_pixel);
    EXPECT_NEAR(angle(mid_x, v.y0, false), f.top, half_pixel);
    EXPECT_NEAR(angle(mid_x, v.y0 + v.height, false), f.bottom, half_pixel);
    // The principal point is the optical axis: zero angle both ways.
    EXPECT_NEAR(angle(v.x0 + v.cx, v.y0 + v.cy, true), 0.0, 1e-9);
    EXPECT_NEAR(angle(v.x0 + v.cx, v.y0 + v.cy, false), 0.0, 1e-9);
  }
  EXPECT_NE(frustumError({10, -10, -5, 5}), "");
  EXPECT_NE(frustumError({-10, 10, -5, 95}), "");
}

}  // namespace
}  // namespace nephele
