// Gardner's shading (MODEL.md sections 3 and 4), shared by world/shading.cpp and the GL
// renderer's shaders (see prelude.h).
#ifdef __cplusplus
#pragma once
#include "world/formulas/prelude.h"

namespace nephele::formulas {
#endif

CONSTANT real kPi = 3.141592653589793;

// Gardner eq. 8 from its terms: I = (1 - a){(1 - t)[(1 - s) Id + s Is] + t It} + a, with
// shading = (a, t, s, e).
FORMULA real gardnerIntensity(vec4 shading, real diffuse, real highlight, real it) {
  real a = shading.x, t = shading.y, s = shading.z;
  return (1.0 - a) * ((1.0 - t) * ((1.0 - s) * diffuse + s * highlight) + t * it) + a;
}

// A surface normal turned towards the viewer: -n where n faces along the view ray `ray` (from
// the eye to the surface, any length), else n.
FORMULA vec3 facingViewer(vec3 n, vec3 ray) {
  return dot(n, ray) > 0.0 ? -n : n;
}

// Phong's highlight Is = max(0, R.V)^e, R the unit `to_sun` mirrored about the unit normal n
// (n_dot_l = n . to_sun, above 0), V the unit `to_viewer`.
FORMULA real phongHighlight(vec3 n, real n_dot_l, vec3 to_sun, vec3 to_viewer, real e) {
  vec3 reflected = 2.0 * n_dot_l * n - to_sun;
  return pow(max(dot(reflected, to_viewer), 0.0), e);
}

// Gardner eq. 9 and 11: translucence TR = clamp(1 - excess / D, 0, 1) for the texture's excess
// over the threshold; D = 0 is a hard threshold.
FORMULA real translucence(real excess, real d) {
  return d <= 0.0 ? (excess <= 0.0 ? 1.0 : 0.0) : clamp(1.0 - excess / d, 0.0, 1.0);
}

// Gardner eq. 11's excess: the texture value It over the threshold that rises from T1 at the
// ellipsoid's centre (limb function g = 1) to T2 at its limb (g = 0).
FORMULA real limbExcess(real it, real t1, real t2, real g) {
  return it - t1 - (t2 - t1) * (1.0 - g);
}

// The mean of max(0, N.L) over the visible disc of a Lambertian sphere at phase angle alpha
// (between the directions to the sun and to the viewer): 2/3 (sin alpha + (pi - alpha)
// cos alpha) / pi. A far deck standing for heaps is lit so (MODEL.md section 11).
FORMULA real sphereDiffuse(real cos_alpha) {
  real alpha = acos(clamp(cos_alpha, -1.0, 1.0));
  return (2.0 / 3.0) * (sin(alpha) + (kPi - alpha) * cos(alpha)) / kPi;
}

#ifdef __cplusplus
}  // namespace nephele::formulas
#endif
