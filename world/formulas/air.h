// The air between the eye and a surface (MODEL.md sections 5 and 17): slabs of fog, veil and
// precipitation, the distance haze and the shafts under heaps. Shared by world/sky.cpp and the
// GL renderer's renderer/gl/shaders/sky/common.glsl (see prelude.h). A ray starts at height
// z0 along the unit direction d and runs `distance` metres, finite here: world/sky.cpp takes
// the endless paths apart.
#ifdef __cplusplus
#pragma once
#include "world/formulas/prelude.h"

namespace nephele::formulas {
#endif

// Each medium's optical depth is capped here, where its transmittance exp(-tau) is already 0
// in float and in double, so that the weights of the colours in airOver stay finite.
CONSTANT real kOpaqueDepth = 1e3;

// The share of a shaft's density left at the ground (RainShaft): its density falls linearly
// from 1 under the heap's base to this at Z = 0.
CONSTANT real kShaftGroundShare = 0.5;

// A slab's density at height z: 1 from bottom to top, linear to 0 over the band either side;
// slab = (bottom, top, band), metres.
FORMULA real slabDensity(vec3 slab, real z) {
  if (z >= slab.x && z <= slab.y) return 1.0;
  real out_by = z < slab.x ? slab.x - z : z - slab.y;
  return slab.z > 0.0 ? max(0.0, 1.0 - out_by / slab.z) : 0.0;
}

// The slab's density integrated from below it up to height z (+-infinity allowed).
FORMULA real slabColumn(vec3 slab, real z) {
  real b = slab.z, low = slab.x - b;
  if (!(z > low)) return 0.0;
  if (z <= slab.x) return (z - low) * (z - low) / (2.0 * b);
  if (z <= slab.y) return 0.5 * b + (z - slab.x);
  real u = min(z - slab.y, b);
  return 0.5 * b + (slab.y - slab.x) + u - (b > 0.0 ? u * u / (2.0 * b) : 0.0);
}

// The density-weighted length through the slab of the path: the difference of the columns at
// its ends over |dz|, or where the path is level, or so nearly that the difference would lose
// its digits, the density half way times the length.
FORMULA real slabPath(vec3 slab, real z0, real dz, real distance) {
  real rise = distance * dz;
  if (abs(rise) < 1e-3) return slabDensity(slab, z0 + 0.5 * rise) * distance;
  return abs(slabColumn(slab, z0 + rise) - slabColumn(slab, z0)) / abs(dz);
}

// The haze's optical depth along the path, extinction sigma0 at Z = 0 falling as exp(-Z / h):
// sigma0 h (e^-a - e^-(a + x)) / dz with a = z0 / h and x = s dz / h, or near x = 0, where the
// difference cancels, the series sigma0 s e^-a (1 - x/2 + x^2/6). A flat Earth sees an endless
// level path; 1e9 m keeps tau finite, and the horizon seen from sea level the haze's colour.
// The end height is held above -50 h: only a ray past the ground goes lower, and its tau is
// then e^50 times any real one.
FORMULA real hazeDepth(real sigma0, real h, real z0, real dz, real distance) {
  real s = min(distance, 1e9);
  real a = z0 / h, x = s * dz / h;
  if (abs(x) < 1e-2) return sigma0 * s * exp(-a) * (1.0 - x / 2.0 + x * x / 6.0);
  return sigma0 * h / dz * (exp(-a) - exp(-max(a + x, -50.0)));
}

// A shaft's optical depth along the path (RainShaft, MODEL.md section 17): shaft = (X, Y of
// its axis from the path's start, radius R, top), sigma its extinction at density 1. The chord
// [t0, t1] lies inside the cylinder (horizontal parts) and between the ground and the top; a
// ray whose horizontal part has a squared length under 1e-8 counts as vertical. About the
// chord's middle m, t = m + u with |u| <= h, the radial factor 1 - rho^2 / R^2 is
// G0 + G1 u + G2 u^2 and the height factor L0 + L1 u, so the odd terms of their product vanish
// over [-h, h]: the integral is 2 h G0 L0 + (2 h^3 / 3)(G2 L0 + G1 L1), exact.
FORMULA real shaftDepth(vec4 shaft, real sigma, real z0, vec3 d, real distance) {
  vec2 o = -vec2(shaft.x, shaft.y), dh = vec2(d.x, d.y);
  real r2 = shaft.z * shaft.z, a = dot(dh, dh), b = dot(o, dh);
  real t0 = 0.0, t1 = distance;
  if (a < 1e-8) {
    if (dot(o, o) >= r2) return 0.0;
  } else {
    // b^2 - a (|o|^2 - R^2) = a R^2 - (o x d)^2, the form that keeps far shafts' digits.
    real cross_od = o.x * dh.y - o.y * dh.x, quarter_delta = a * r2 - cross_od * cross_od;
    if (quarter_delta <= 0.0) return 0.0;
    real root = sqrt(quarter_delta);
    t0 = max(t0, (-b - root) / a);
    t1 = min(t1, (-b + root) / a);
  }
  if (d.z == 0.0) {
    if (z0 < 0.0 || z0 > shaft.w) return 0.0;
  } else {
    real at_ground = -z0 / d.z, at_top = (shaft.w - z0) / d.z;
    t0 = max(t0, min(at_ground, at_top));
    t1 = min(t1, max(at_ground, at_top));
  }
  if (!(t1 > t0)) return 0.0;
  real m = 0.5 * (t0 + t1), h = 0.5 * (t1 - t0);
  vec2 q = o + m * dh;
  real g0 = 1.0 - dot(q, q) / r2, g1 = -2.0 * dot(q, dh) / r2, g2 = -a / r2;
  real fade = (1.0 - kShaftGroundShare) / shaft.w;
  real l0 = kShaftGroundShare + fade * (z0 + m * d.z), l1 = fade * d.z;
  return sigma * max(2.0 * h * g0 * l0 + (2.0 * h * h * h / 3.0) * (g2 * l0 + g1 * l1), 0.0);
}

// The media along a path as airOver takes them, `air` = (the sum of each medium's depth times
// its colour, the sum of the depths), with one more medium of optical depth tau (capped at
// kOpaqueDepth) and colour c.
FORMULA vec4 withMedium(vec4 air, real tau, vec3 c) {
  real capped = min(tau, kOpaqueDepth);
  return vec4(vec3(air.x, air.y, air.z) + capped * c, air.w + capped);
}

// A surface of `colour` seen through media of total optical depth tau (MODEL.md section 5),
// `weighted` the sum of each medium's depth times its colour: the media taken as one of their
// depth-weighted mean colour, colour T + (1 - T) weighted / tau with T = exp(-tau). `colour`
// itself where there is no air (tau 0).
FORMULA vec3 airOver(vec3 colour, vec3 weighted, real tau) {
  if (!(tau > 0.0)) return colour;
  return mix(weighted / tau, colour, exp(-tau));
}

// The clear sky's colour at elevation sine `up` (MODEL.md section 5): from the horizon's colour
// to the zenith's as sqrt(up), the horizon's at and below level.
FORMULA vec3 skyGradient(vec3 horizon, vec3 zenith, real up) {
  return horizon + (zenith - horizon) * sqrt(max(up, 0.0));
}

#ifdef __cplusplus
}  // namespace nephele::formulas
#endif
