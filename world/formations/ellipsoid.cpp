#include "world/formations/ellipsoid.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "world/formulas/ellipsoid.h"

namespace nephele {

std::string ellipsoidError(const Ellipsoid& e) {
  std::ostringstream out;
  for (int i = 0; i < 3; ++i)
    if (!(std::isfinite(e.radii[i]) && e.radii[i] > 0.0)) {
      out << "radius "
          << "xyz"[i] << " = " << e.radii[i] << " is not allowed (allowed: a finite number > 0)";
      return out.str();
    }
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(e.centre[i])) return "centre is not finite (allowed: finite numbers)";
  const Orientation& o = e.orientation;
  if (!std::isfinite(o.heading_deg) || !std::isfinite(o.pitch_deg) || !std::isfinite(o.roll_deg))
    return "orientation is not finite (allowed: finite angles in degrees)";
  return "";
}

glm::dmat3 worldToUnitSphere(const Ellipsoid& e) {
  const glm::dmat3 inverse_scale(1.0 / e.radii.x, 0, 0, 0, 1.0 / e.radii.y, 0, 0, 0,
                                 1.0 / e.radii.z);
  return inverse_scale * glm::transpose(bodyToWorld(e.orientation));
}

glm::dmat3 unitSphereToWorld(const Ellipsoid& e) {
  const glm::dmat3 body = bodyToWorld(e.orientation);
  return {body[0] * e.radii.x, body[1] * e.radii.y, body[2] * e.radii.z};
}

double verticalHalfExtent(const Ellipsoid& e) {
  const glm::dmat3 t = unitSphereToWorld(e);
  return glm::length(glm::dvec3(t[0].z, t[1].z, t[2].z));
}

double quadricValue(const Ellipsoid& e, glm::dvec3 point) {
  const glm::dvec3 o = worldToUnitSphere(e) * (point - e.centre);
  return glm::dot(o, o) - 1.0;
}

SymmetricEigen symmetricEigen(const glm::dmat3& m) {
  double a[3][3], v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) a[i][j] = 0.5 * (m[j][i] + m[i][j]);
  const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int sweep = 0; sweep < 60; ++sweep) {
    const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    const double diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
    if (off <= 1e-32 * diag || off == 0.0) break;
    for (const auto& pq : pairs) {
      const int p = pq[0], q = pq[1];
      if (a[p][q] == 0.0) continue;
      // Rotation J (J_pp = J_qq = c, J_pq = s, J_qp = -s) that zeroes a_pq in J^T A J.
      const double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
      const double t = (theta >= 0.0 ? 1.0 : -1.0) / (std::abs(theta) + std::hypot(theta, 1.0));
      const double c = 1.0 / std::sqrt(t * t + 1.0), s = t * c;
      for (int k = 0; k < 3; ++k) {  // A J
        const double kp = a[k][p], kq = a[k][q];
        a[k][p] = c * kp - s * kq;
        a[k][q] = s * kp + c * kq;
      }
      for (int k = 0; k < 3; ++k) {  // J^T (A J)
        const double pk = a[p][k], qk = a[q][k];
        a[p][k] = c * pk - s * qk;
        a[q][k] = s * pk + c * qk;
      }
      for (int k = 0; k < 3; ++k) {  // V J
        const double kp = v[k][p], kq = v[k][q];
        v[k][p] = c * kp - s * kq;
        v[k][q] = s * kp + c * kq;
      }
    }
  }
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int x, int y) { return a[x][x] < a[y][y]; });
  SymmetricEigen out;
  for (int i = 0; i < 3; ++i) {
    out.values[i] = a[order[i]][order[i]];
    out.vectors[i] = glm::dvec3(v[0][order[i]], v[1][order[i]], v[2][order[i]]);
  }
  return out;
}

EllipsoidView::EllipsoidView(const Ellipsoid& ellipsoid, glm::dvec3 eye)
    : to_unit_(worldToUnitSphere(ellipsoid)), eye_unit_(to_unit_ * (eye - ellipsoid.centre)) {
  c_ = glm::dot(eye_unit_, eye_unit_) - 1.0;
  // Delta(d) = 4 [(o.Wd)^2 - |Wd|^2 c] = 4 (Wd)^T (o o^T - c I) (Wd).
  const glm::dmat3 inner = glm::outerProduct(eye_unit_, eye_unit_) - c_ * glm::dmat3(1.0);
  k_ = 4.0 * glm::transpose(to_unit_) * inner * to_unit_;
  if (eyeInside()) return;
  // Outside, K has one positive eigenvalue (Sylvester: o o^T - c I has eigenvalues 1, -c, -c).
  const SymmetricEigen eigen = symmetricEigen(k_);
  lambda_ = eigen.values[2];
  axis_ = glm::normalize(eigen.vectors[2]);
  if (glm::dot(axis_, ellipsoid.centre - eye) < 0.0) axis_ = -axis_;
  limb_form_ = -(k_ - lambda_ * glm::outerProduct(axis_, axis_)) / lambda_;
}

std::optional<RaySpan> EllipsoidView::intersect(glm::dvec3 direction) const {
  const glm::dvec3 w = to_unit_ * direction;
  if (!(glm::dot(w, w) > 0.0)) return std::nullopt;
  const double quarter_delta = formulas::quarterDelta(eye_unit_, w);
  if (!(quarter_delta > 0.0)) return std::nullopt;
  const glm::dvec2 s = formulas::unitSphereRoots(eye_unit_, w, c_, quarter_delta);
  return RaySpan{std::min(s.x, s.y), std::max(s.x, s.y)};
}

double EllipsoidView::limb(glm::dvec3 direction) const {
  if (eyeInside()) return 0.0;
  const glm::dmat3& p = limb_form_;  // its rows
  return formulas::limbFunction(direction, axis_, glm::dvec3(p[0][0], p[1][0], p[2][0]),
                                glm::dvec3(p[0][1], p[1][1], p[2][1]),
                                glm::dvec3(p[0][2], p[1][2], p[2][2]));
}

glm::dvec3 EllipsoidView::normalAt(glm::dvec3 direction, double s) const {
  const glm::dvec3 gradient = glm::transpose(to_unit_) * (eye_unit_ + s * (to_unit_ * direction));
  return glm::normalize(gradient);
}

glm::dmat3 silhouetteConic(const EllipsoidView& view, const ViewBasis& basis) {
  const glm::dmat3 b(basis.right, basis.up, basis.forward);
  return glm::transpose(b) * view.discriminantForm() * b;
}

namespace {

// NDC interval [lo, hi] of the planes through the eye with normal n(x) = axis - x forward
// that meet the ellipsoid: f(x) = n^T A n >= 0, A = T T^T - c c^T (the dual quadric's block,
// T the body-to-world matrix times the radii, c the centre relative to the eye). f is
// quadratic, a x^2 - 2 b x + k. With a < 0 the ellipsoid lies wholly on one side of the eye
// plane, and if in front, the planes that meet it lie between the two roots; with a > 0 it
// straddles the eye plane and they lie outside them.
glm::dvec2 planeInterval(const glm::dmat3& t, glm::dvec3 c, glm::dvec3 axis, glm::dvec3 forward) {
  const glm::dvec3 ta = glm::transpose(t) * axis, tf = glm::transpose(t) * forward;
  const double ca = glm::dot(c, axis), cf = glm::dot(c, forward);
  const double a = glm::dot(tf, tf) - cf * cf;
  const double b = glm::dot(ta, tf) - ca * cf;
  const double k = glm::dot(ta, ta) - ca * ca;
  const double disc = b * b - a * k;
  const glm::dvec2 none(1.0, -1.0), all(-1.0, 1.0);
  if (a < 0.0 && cf < 0.0) return none;  // wholly behind the eye plane
  if (!(disc > 0.0) || a == 0.0) return a < 0.0 ? none : all;
  const double root = std::sqrt(disc);
  // The roots without cancellation: q = b + sign(b) sqrt(disc), x = q / a and k / q.
  const double q = b + std::copysign(root, b);
  const double r1 = q / a, r2 = q != 0.0 ? k / q : -r1;
  const double lo = std::min(r1, r2), hi = std::max(r1, r2);
  if (a < 0.0) return {std::max(lo, -1.0), std::min(hi, 1.0)};
  // Outside the roots: (-inf, lo] and [hi, inf), each within [-1, 1] if it reaches it.
  glm::dvec2 span = none;
  if (lo >= -1.0) span = {-1.0, std::min(lo, 1.0)};
  if (hi <= 1.0) span = {span.x > span.y ? std::max(hi, -1.0) : span.x, 1.0};
  return span;
}

}  // namespace

glm::dvec4 screenBounds(const Ellipsoid& e, glm::dvec3 eye, const ViewBasis& basis) {
  const glm::dmat3 t = unitSphereToWorld(e);
  const glm::dvec3 c = e.centre - eye;
  const glm::dvec2 x =
      planeInterval(t, c, basis.right / (basis.tan_half_vfov * basis.aspect), basis.forward);
  const glm::dvec2 y = planeInterval(t, c, basis.up / basis.tan_half_vfov, basis.forward);
  if (x.x > x.y || y.x > y.y) return {1.0, 1.0, -1.0, -1.0};
  return {x.x, y.x, x.y, y.y};
}

}  // namespace nephele
