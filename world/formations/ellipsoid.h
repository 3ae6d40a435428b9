#pragma once
// Gardner's ellipsoid primitive (MODEL.md sections 4 and 5): nine parameters, its quadric, and,
// for one eye, the ray quadratic, the exact limb function g, the silhouette conic and the
// image's screen rectangle. Everything is camera-relative and in double, so a cloud 100 km
// from the origin is as exact as one at it.
#include <optional>
#include <string>

#include <glm/glm.hpp>

#include "world/camera.h"

namespace nephele {

struct Ellipsoid {
  glm::dvec3 radii{400.0, 400.0, 250.0};  // semi-axes along body x, y, z, metres
  glm::dvec3 centre{0.0, 0.0, 1500.0};
  Orientation orientation;
};

// Empty when the ellipsoid is usable, else what is wrong with it and what is allowed.
std::string ellipsoidError(const Ellipsoid& ellipsoid);

// Maps world offsets from the centre into the ellipsoid's unit-sphere frame: W = S^-1 R^T,
// so the surface is |W (X - centre)| = 1.
glm::dmat3 worldToUnitSphere(const Ellipsoid& ellipsoid);
// Its inverse, T = R S: the unit sphere's points to world offsets from the centre.
glm::dmat3 unitSphereToWorld(const Ellipsoid& ellipsoid);
// How far it reaches above and below its centre: |row z of R S|.
double verticalHalfExtent(const Ellipsoid& ellipsoid);

// The quadric Q(X) = (X - C)^T M (X - C) - 1 with M = W^T W (MODEL.md section 5).
double quadricValue(const Ellipsoid& ellipsoid, glm::dvec3 point);

// Entry and exit distances of a ray along a unit or non-unit direction.
struct RaySpan {
  double near;
  double far;
};

// Symmetric 3x3 eigen-decomposition (cyclic Jacobi): values ascending, vectors as columns.
struct SymmetricEigen {
  glm::dvec3 values;
  glm::dmat3 vectors;
};
SymmetricEigen symmetricEigen(const glm::dmat3& m);

// One ellipsoid seen from one eye.
class EllipsoidView {
 public:
  EllipsoidView(const Ellipsoid& ellipsoid, glm::dvec3 eye);

  // The ray eye + s d gives Q = a s^2 + b s + c with a = |W d|^2, b = 2 o.W d, c = |o|^2 - 1
  // for o = W (eye - centre). c <= 0 means the eye is inside or on the surface.
  bool eyeInside() const { return c_ <= 0.0; }
  double eyeRadius() const { return glm::length(eye_unit_); }  // |o|: 1 on the surface
  glm::dvec3 eyeInUnitSphere() const { return eye_unit_; }
  const glm::dmat3& toUnitSphere() const { return to_unit_; }

  // Both hits of the ray along `direction` (any length), distances in units of that length;
  // nullopt when it misses or only grazes. Hits may lie behind the eye (negative).
  std::optional<RaySpan> intersect(glm::dvec3 direction) const;

  // The discriminant Delta(d) = b^2 - 4ac as the quadratic form d^T K d (MODEL.md section 4).
  const glm::dmat3& discriminantForm() const { return k_; }
  // K's single positive eigenvalue and its unit eigenvector turned towards the ellipsoid
  // (the axis of the cone of tangent rays). Valid only while the eye is outside.
  double limbEigenvalue() const { return lambda_; }
  glm::dvec3 limbAxis() const { return axis_; }
  // P = -(K - lam a a^T) / lam, so that g(d) = 1 - q^T P q with q = d / (d.a) - a: the same
  // g as the limb function's Delta / (lam (d.a)^2), written so floats keep it accurate near the
  // axis.
  const glm::dmat3& limbForm() const { return limb_form_; }

  // The exact limb function g(d) = Delta(d) / (lam (d.a)^2), clamped to [0, 1]: 1 on the
  // cone's axis, 0 on the silhouette.
  double limb(glm::dvec3 direction) const;

  // Unit outward surface normal at eye + s d (the normalised quadric gradient).
  glm::dvec3 normalAt(glm::dvec3 direction, double s) const;

 private:
  glm::dmat3 to_unit_;   // W
  glm::dvec3 eye_unit_;  // o
  double c_ = 0.0;       // |o|^2 - 1
  glm::dmat3 k_{0.0};    // K
  double lambda_ = 0.0;
  glm::dvec3 axis_{0.0};
  glm::dmat3 limb_form_{0.0};
};

// Silhouette conic of the ellipsoid in the image plane: with d = u right + v up + forward
// (MODEL.md section 1), the rays that touch the ellipsoid are [u v 1] C [u v 1]^T = 0 and the
// rays that meet it have a non-negative value. C = B^T K B with B = [right up forward].
glm::dmat3 silhouetteConic(const EllipsoidView& view, const ViewBasis& basis);

// The smallest rectangle [x0, y0, x1, y1] of normalised device coordinates (-1 to 1, x right,
// y up) holding the ellipsoid's image, from the planes through the eye that touch it
// (MODEL.md section 15); empty (x0 > x1) when the image misses the screen. Part of an
// ellipsoid behind the eye plane makes the image unbounded on that side; the rectangle
// then runs to the screen's edge there.
glm::dvec4 screenBounds(const Ellipsoid& ellipsoid, glm::dvec3 eye, const ViewBasis& basis);

}  // namespace nephele
