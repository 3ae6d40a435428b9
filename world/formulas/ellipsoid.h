// An ellipsoid seen from the eye (MODEL.md section 4), in the unit-sphere space of its body:
// the eye at o, a view ray's direction at w (W times the world direction, any length), and
// c = |o|^2 - 1. Shared by world/formations/ellipsoid.cpp (EllipsoidView), heap_light.cpp
// (envelopeChord) and the GL renderer's renderer/gl/shaders/ellipsoid/cloud.glsl (see
// prelude.h).
#ifdef __cplusplus
#pragma once
#include "world/formulas/prelude.h"

namespace nephele::formulas {
#endif

// A quarter of the discriminant of |o + s w|^2 = 1: (o.w)^2 - |w|^2 c = |w|^2 - |o x w|^2, the
// form free of cancellation far away. The ray meets the ellipsoid where it is above 0.
FORMULA real quarterDelta(vec3 o, vec3 w) {
  vec3 o_x_w = cross(o, w);
  return dot(w, w) - dot(o_x_w, o_x_w);
}

// Both roots s of |o + s w| = 1, in units of w, unordered, for quarter_delta (above 0) from
// quarterDelta: q = -(o.w + sign(o.w) sqrt(quarter_delta)), then q / |w|^2 and c / q, the pair
// that keeps its digits whichever way the ray points.
FORMULA vec2 unitSphereRoots(vec3 o, vec3 w, real c, real quarter_delta) {
  real half_b = dot(o, w);
  real q = -(half_b + (half_b >= 0.0 ? 1.0 : -1.0) * sqrt(quarter_delta));
  return vec2(q / dot(w, w), c / q);
}

// The length of the ray o + s w, s >= 0, inside the unit sphere, in units of w: a heap's
// envelope seen from a point of its surface (envelopeChord, MODEL.md section 14), o and w
// the point and the direction in the envelope's unit-sphere space. 0 where the ray misses.
FORMULA real unitSphereChord(vec3 o, vec3 w) {
  real a = dot(w, w), half_b = dot(o, w), c = dot(o, o) - 1.0;
  real quarter_delta = half_b * half_b - a * c;
  if (!(quarter_delta > 0.0) || !(a > 0.0)) return 0.0;
  real root = sqrt(quarter_delta);
  return max(0.0, (-half_b + root) / a - max((-half_b - root) / a, 0.0));
}

// Gardner's limb function g (MODEL.md section 4) along view direction d: 1 - q^T P q with
// q = d / (d.a) - a, for the axis a of the cone of tangent rays and the limb form P (its rows
// p0, p1, p2; EllipsoidView::limbForm), clamped to [0, 1]: 1 on the axis, 0 on the silhouette
// and for rays turned away from the ellipsoid.
FORMULA real limbFunction(vec3 d, vec3 axis, vec3 p0, vec3 p1, vec3 p2) {
  real along = dot(d, axis);
  if (!(along > 0.0)) return 0.0;
  vec3 q = d / along - axis;
  vec3 pq = vec3(dot(p0, q), dot(p1, q), dot(p2, q));
  return clamp(1.0 - dot(q, pq), 0.0, 1.0);
}

#ifdef __cplusplus
}  // namespace nephele::formulas
#endif
