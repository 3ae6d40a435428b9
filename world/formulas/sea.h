// The sea's optics (MODEL.md section 18), shared by world/sea.cpp and the GL renderer's
// renderer/gl/shaders/sky/common.glsl (see prelude.h).
#ifdef __cplusplus
#pragma once
#include "world/formulas/prelude.h"

namespace nephele::formulas {
#endif

// The effective reflectance of whitecap foam (Koepke 1984).
CONSTANT real kFoamReflectance = 0.22;
// The share of the sea's slope variance the drawn sines may take (SeaSurface); the rest stays
// unresolved at every distance, for the glint, so that no pixel is a perfect mirror.
CONSTANT real kResolvedSlopeShare = 0.8;

// The slope variance the glint spreads over, for the sea's total and the share the drawn sines
// resolve at the pixel: what they leave, but at least 1 - kResolvedSlopeShare of the total.
FORMULA real unresolvedSlopeVariance(real total, real resolved) {
  return max(total - resolved, (1.0 - kResolvedSlopeShare) * total);
}

// The unit facet normal of a surface whose height has gradient `slope`.
FORMULA vec3 seaNormal(vec2 slope) {
  return normalize(vec3(-slope.x, -slope.y, 1.0));
}

// The cosine of the incidence of unit view ray d on the facet of unit normal n, 0 for a facet
// turned away.
FORMULA real seaIncidence(vec3 d, vec3 n) {
  return clamp(-dot(d, n), 0.0, 1.0);
}

// Where the sea mirrors unit view ray d: d reflected about the facet normal n (cos_i from
// seaIncidence). A facet that sends the ray back down would show the sea again, so the ray
// leaves at least 0.01 above level, and sees the sky at the horizon.
FORMULA vec3 mirroredRay(vec3 d, vec3 n, real cos_i) {
  vec3 r = d + 2.0 * cos_i * n;
  r.z = max(r.z, 0.01);
  return normalize(r);
}

// The light the sea sends back from below its surface and from its foam, lit by `diffuse` (the
// sun's and sky's light on a level surface, per pi): the water body's reflectance `body` where
// neither foam nor the Fresnel mirror covers it, foam's kFoamReflectance of `foam_colour` where
// foam does. Colours in the caller's units (times the sun's colour).
FORMULA vec3 seaBodyAndFoam(real diffuse, real foam, real fresnel, vec3 body, vec3 foam_colour) {
  return diffuse * ((1.0 - foam) * (1.0 - fresnel) * body + foam * kFoamReflectance * foam_colour);
}

// Unpolarised Fresnel reflectance of a dielectric of index n from air (Born and Wolf), for the
// cosine of the incidence angle.
FORMULA real fresnelWater(real cos_incidence, real n) {
  real c = clamp(cos_incidence, 0.0, 1.0);
  real g = sqrt(n * n - 1.0 + c * c);
  real a = (g - c) / (g + c), b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0);
  return 0.5 * a * a * (1.0 + b * b);
}

// The share of a point covered by foam (SeaSurface, foamShare in world/sea.h): where the
// surface is resolved, the logistic of its squared slope over `foam_steepness`, softened over
// the unresolved slopes' variance; where it is not, the whitecap fraction w. The two blend by
// the share of the drawn slope variance `var_total` resolved.
FORMULA real foamShare(real w, real foam_steepness, real steepness, real var_total,
                       real var_unresolved) {
  if (!(w > 0.0)) return 0.0;
  if (w >= 1.0) return 1.0;
  real resolved = var_total > 0.0 ? clamp(1.0 - var_unresolved / var_total, 0.0, 1.0) : 0.0;
  real edge = sqrt(max(var_unresolved, 1e-4 * var_total + 1e-12));
  real crest = 1.0 / (1.0 + exp(-1.702 * (steepness - foam_steepness) / edge));
  return (1.0 - resolved) * w + resolved * crest;
}

// Cox-Munk glint radiance for a unit irradiance per pi: F p / (4 mu_v mu_n^4) with p =
// exp(-tan^2 beta / s^2) / (pi s^2), the facet normal that mirrors the unit view ray d to the
// unit `sun` taken relative to the unit surface normal n, slope variance s^2 = slope_var.
FORMULA real glintRadiance(vec3 d, vec3 sun, vec3 n, real slope_var) {
  vec3 v = -d;
  real mu_v = dot(v, n), mu_s = dot(sun, n);
  if (!(mu_v > 0.0) || !(mu_s > 0.0)) return 0.0;
  vec3 h = normalize(v + sun);
  real mu_n = dot(h, n);
  if (!(mu_n > 0.0)) return 0.0;
  real mu_n2 = mu_n * mu_n, tan2 = (1.0 - mu_n2) / mu_n2;
  return fresnelWater(dot(v, h), 1.34) * exp(-tan2 / slope_var) /
         (4.0 * slope_var * max(mu_v, 1e-2) * mu_n2 * mu_n2);
}

// The metres per pixel at `distance` along a ray of elevation sine `sin_elev` below the horizon,
// `pixel_rad` radians a pixel: distance pixel / sqrt(|sin|), the geometric mean of the
// footprint's two sides.
FORMULA real seaFootprint(real distance, real sin_elev, real pixel_rad) {
  return distance * pixel_rad / sqrt(max(abs(sin_elev), 1e-4));
}

// A sine's weight for a pixel's footprint f (MODEL.md section 18, filtering): 1 while its
// wavelength L is at least 8 footprints, 0 at 4 or fewer, linear between: clamp(L / (4 f) - 1).
FORMULA real waveResolved(real wavelength, real footprint) {
  return clamp(wavelength / (4.0 * footprint) - 1.0, 0.0, 1.0);
}

// The variance of a sine's height, amplitude a at weight w: w^2 a^2 / 2 (times |k|^2, its
// slope's).
FORMULA real waveHeightVariance(real w, real amplitude) {
  return 0.5 * w * w * amplitude * amplitude;
}

// The slope of the sine a cos(phase), phase = k . x + m sin(q . x + psi) + ..., at weight w:
// -w a sin(phase) (k + m cos(q . x + psi) q), this returning its negative. The sines are the
// caller's: the reference takes sin and cos (the model, MODEL.md section 18), the GPU its
// polynomial gardnerSin, within 4e-6 of them (docs/ACCURACY.md, "Per-pixel sines").
FORMULA vec2 waveSlope(real w, real amplitude, real sin_phase, vec2 k, real m, real cos_wobble,
                       vec2 q) {
  return (w * amplitude * sin_phase) * (k + m * cos_wobble * q);
}

#ifdef __cplusplus
}  // namespace nephele::formulas
#endif
