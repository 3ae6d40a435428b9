#include "world/camera.h"

#include "world/limits.h"

#include <algorithm>

#include <cmath>
#include <numbers>

namespace nephele {
namespace {

double radians(double degrees) {
  return degrees * std::numbers::pi / 180.0;
}

// Rotations by angle a about the world axes (column-major: m[column][row]).
glm::dmat3 rotationZ(double a) {
  const double c = std::cos(a), s = std::sin(a);
  return glm::dmat3(c, s, 0, -s, c, 0, 0, 0, 1);
}
glm::dmat3 rotationX(double a) {
  const double c = std::cos(a), s = std::sin(a);
  return glm::dmat3(1, 0, 0, 0, c, s, 0, -s, c);
}
glm::dmat3 rotationY(double a) {
  const double c = std::cos(a), s = std::sin(a);
  return glm::dmat3(c, 0, -s, 0, 1, 0, s, 0, c);
}

}  // namespace

glm::dmat3 bodyToWorld(const Orientation& o) {
  return rotationZ(-radians(o.heading_deg)) * rotationX(radians(o.pitch_deg)) *
         rotationY(radians(o.roll_deg));
}

Orientation orientationOf(const glm::dmat3& r) {
  // Columns: right, forward, up. forward = (sin h cos p, cos h cos p, sin p); the z parts of
  // right and up are -sin r cos p and cos r cos p.
  const glm::dvec3 right = r[0], forward = r[1], up = r[2];
  Orientation o;
  o.pitch_deg = std::asin(std::clamp(forward.z, -1.0, 1.0)) * 180.0 / std::numbers::pi;
  if (std::hypot(forward.x, forward.y) > 1e-12) {
    o.heading_deg = std::atan2(forward.x, forward.y) * 180.0 / std::numbers::pi;
    o.roll_deg = std::atan2(-right.z, up.z) * 180.0 / std::numbers::pi;
  } else {  // straight up or down: the heading is that of the body's up (or down) axis
    const double s = forward.z > 0.0 ? -1.0 : 1.0;
    o.heading_deg = std::atan2(s * up.x, s * up.y) * 180.0 / std::numbers::pi;
  }
  if (o.heading_deg < 0.0) o.heading_deg += 360.0;
  return o;
}

std::string frustumError(const Frustum& f) {
  const Range r = Limits::kFrustumAngle;
  for (double a : {f.left, f.right, f.bottom, f.top})
    if (!std::isfinite(a) || !r.contains(a))
      return "frustum: an angle is out of range (allowed: left < right and bottom < top, each " +
             std::to_string(int(r.lo)) + " to " + std::to_string(int(r.hi)) + " degrees)";
  if (!(f.left < f.right && f.bottom < f.top))
    return "frustum: left must be below right and bottom below top";
  return "";
}

OffAxisView offAxisView(const Camera& camera, const Frustum& f) {
  const double tl = std::tan(radians(f.left)), tr = std::tan(radians(f.right));
  const double tb = std::tan(radians(f.bottom)), tt = std::tan(radians(f.top));
  OffAxisView v;
  const int height = std::max(1, camera.height);
  v.focal_px = height / (tt - tb);
  // The centred view reaches the farther side each way; its centre is a whole pixel corner.
  const int half_w = int(std::ceil(v.focal_px * std::max(std::abs(tl), std::abs(tr)) - 1e-9));
  const int half_h = int(std::ceil(v.focal_px * std::max(std::abs(tb), std::abs(tt)) - 1e-9));
  v.render = camera;
  v.render.width = std::max(2 * half_w, 1);
  v.render.height = std::max(2 * half_h, 1);
  v.render.vfov_deg = 2.0 * std::atan(half_h / v.focal_px) * 180.0 / std::numbers::pi;
  // Each edge of the crop is the pixel edge nearest its side of the frustum (image y down);
  // top and bottom are `height` apart exactly, as f (tan top - tan bottom) = height.
  auto edge = [](double x, int hi) { return std::clamp(int(std::lround(x)), 0, hi); };
  v.x0 = edge(half_w + v.focal_px * tl, v.render.width - 1);
  v.y0 = edge(half_h - v.focal_px * tt, v.render.height - 1);
  v.width = std::max(1, edge(half_w + v.focal_px * tr, v.render.width) - v.x0);
  v.height = std::max(1, std::min(height, v.render.height - v.y0));
  v.cx = half_w - v.x0;
  v.cy = half_h - v.y0;
  return v;
}

ViewBasis viewBasis(const Camera& camera) {
  const glm::dmat3 r = bodyToWorld(camera.orientation);
  ViewBasis basis;
  basis.right = r[0];
  basis.forward = r[1];
  basis.up = r[2];
  basis.tan_half_vfov = std::tan(radians(camera.vfov_deg) * 0.5);
  basis.aspect = double(camera.width) / double(camera.height);
  return basis;
}

Camera nadirCamera(glm::dvec2 xy, double base_m, double thickness_m, double span_m, int pixels) {
  Camera c;
  c.vfov_deg = 4.0;
  const double height = 0.5 * span_m / std::tan(radians(c.vfov_deg) * 0.5);
  c.position = glm::dvec3(xy, base_m + 1.3 * thickness_m + height);
  c.orientation = {0.0, -90.0, 0.0};
  c.width = c.height = pixels;
  return c;
}

bool boxMayBeInView(const ViewBasis& basis, glm::dvec3 eye, glm::dvec3 lo, glm::dvec3 hi) {
  const glm::dvec3 centre = 0.5 * (lo + hi) - eye, half = 0.5 * (hi - lo);
  // Each plane holds the eye; n is its inward normal. The box is beyond it when even its
  // corner farthest along n is: n . centre + sum |n_i| half_i < 0. The side planes hold the
  // eye and an image edge: for the right edge n = forward tan(half width) - right, and
  // likewise for the others.
  const double th = basis.tan_half_vfov, tw = th * basis.aspect;
  const glm::dvec3 normals[] = {basis.forward, basis.forward * tw - basis.right,
                                basis.forward * tw + basis.right, basis.forward * th - basis.up,
                                basis.forward * th + basis.up};
  for (const glm::dvec3& n : normals)
    if (glm::dot(n, centre) + glm::dot(glm::abs(n), half) < 0.0) return false;
  return true;
}

glm::dvec3 rayDirection(const ViewBasis& basis, const Camera& camera, double x, double y) {
  const double u = (2.0 * x / camera.width - 1.0) * basis.tan_half_vfov * basis.aspect;
  const double v = (1.0 - 2.0 * y / camera.height) * basis.tan_half_vfov;
  return u * basis.right + v * basis.up + basis.forward;
}

}  // namespace nephele
