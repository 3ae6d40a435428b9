#pragma once
// World frame, orientation and camera (MODEL.md section 1).
#include <glm/glm.hpp>

#include <string>

namespace nephele {

// Heading clockwise from north (+Y), pitch nose up, roll right wing down; degrees.
struct Orientation {
  double heading_deg = 0.0;
  double pitch_deg = 0.0;
  double roll_deg = 0.0;
};

// R = Rz(-h) Rx(p) Ry(r): columns are the world directions of body right, forward and up.
glm::dmat3 bodyToWorld(const Orientation& orientation);
// The orientation whose bodyToWorld is the rotation `r` (heading in [0, 360), pitch in
// [-90, 90], roll in (-180, 180]; at pitch +-90 the roll is folded into the heading).
Orientation orientationOf(const glm::dmat3& r);

struct Camera {
  glm::dvec3 position{0.0, 0.0, 2.0};
  Orientation orientation;
  double vfov_deg = 60.0;
  int width = 640;
  int height = 480;
};

// The camera's image-plane basis: a ray through continuous image position (x, y), with x
// from the left and y from the top in pixels, has direction u * right + v * up + forward.
struct ViewBasis {
  glm::dvec3 right;    // world direction of image +u
  glm::dvec3 up;       // world direction of image +v
  glm::dvec3 forward;  // world direction of the optical axis
  double tan_half_vfov = 0.0;
  double aspect = 1.0;  // width / height
};

ViewBasis viewBasis(const Camera& camera);

// An off-axis (asymmetric) view: the angles of the frustum's four sides from the view's axis,
// degrees, left and bottom negative when they lie left of and below the axis (CIGI View
// Definition's left, right, bottom, top).
struct Frustum {
  double left = -30.0, right = 30.0, bottom = -20.0, top = 20.0;
  bool operator==(const Frustum&) const = default;
};
// "" when left < right, bottom < top and each is within Limits::kFrustumAngle, else why.
std::string frustumError(const Frustum& f);

// How an off-axis view of `height` pixels is drawn exactly: the centred pinhole view `render`
// (same pose and focal length, wide enough to hold the frustum) cropped to the rectangle at
// (x0, y0) of width x height pixels. Square pixels: the width follows from the frustum's
// extents. The principal point (cx, cy) of the crop is exact; each edge is the asked side to
// within half a pixel.
struct OffAxisView {
  Camera render;
  int x0 = 0, y0 = 0, width = 0, height = 0;
  double focal_px = 0.0, cx = 0.0, cy = 0.0;
};
OffAxisView offAxisView(const Camera& camera, const Frustum& frustum);

// Straight down onto a square `span_m` metres wide centred at `xy`, from above clouds whose
// base is `base_m` and thickness `thickness_m` (heaps reach 1.3 times it): a 4 degree view
// (near-orthographic: heap tops magnified by under 1 %), `pixels` a side. The view the
// coverage, repetition and realism figures are measured in (SPEC section 9).
Camera nadirCamera(glm::dvec2 xy, double base_m, double thickness_m, double span_m, int pixels);

// False only when the axis-aligned box [lo, hi] lies wholly outside the camera's view frustum
// (beyond one of its four side planes or behind the eye); conservative near the frustum's
// edges and corners.
bool boxMayBeInView(const ViewBasis& basis, glm::dvec3 eye, glm::dvec3 lo, glm::dvec3 hi);

// Unnormalised ray direction through image position (x, y) in pixels (pixel centres at +0.5).
glm::dvec3 rayDirection(const ViewBasis& basis, const Camera& camera, double x, double y);

}  // namespace nephele
