// Cloud shadows (MODEL.md section 16): the sunlight a lobe lets through to a point below it,
// and the light of the ground and of targets for a share of the sunlight. Shared by
// world/formations/cloud_shadow (casterSunlight, groundLight), world/sea.cpp and the GL renderer's
// shadow map (renderer/gl/shaders/shadow_map/sunlight.glsl) and ground and sea (sky/common.glsl,
// sky/layers.glsl), world/target.cpp and the targets' shader (target/shading.glsl; see
// prelude.h).
#ifdef __cplusplus
#pragma once
#include "world/formulas/heap.h"
#include "world/formulas/prelude.h"

namespace nephele::formulas {
#endif

// The share of the ground's light that comes from the sky rather than straight from the sun
// under a clear sky: a ground point in full shadow keeps this much.
CONSTANT real kGroundSkyShare = 0.3;

// The ground's brightness relative to the unshadowed ground, for sunlight share S in [0, 1]:
// kGroundSkyShare + (1 - kGroundSkyShare) S.
FORMULA real groundLight(real sunlight) {
  return kGroundSkyShare + (1.0 - kGroundSkyShare) * sunlight;
}

// Where the line through p along `direction` (unit or not, not level) crosses the plane
// Z = altitude: the sun's ray's ground point or a plane's point above it, or a view ray's
// ground point.
FORMULA vec2 planeCrossing(vec3 p, real altitude, vec3 direction) {
  return vec2(p.x, p.y) + ((altitude - p.z) / direction.z) * vec2(direction.x, direction.y);
}

// The limb value g = 1 - |o_perp|^2 of the ray o + s w through a lobe's unit sphere (o the
// point, w the direction towards the sun in the lobe's unit-sphere space): the limb function of
// an eye at infinity, 1 through the centre, 0 on the outline, below 0 where the ray misses.
FORMULA real sunRayLimb(vec3 o, vec3 w) {
  real a = dot(w, w), half_b = dot(o, w);
  return (half_b * half_b - a * (dot(o, o) - 1.0)) / a;
}

// The share of the sunlight a lobe lets through: 1 - C (1 - T(depth)), C its surface's mean
// opacity at the ray's limb value, depth its extinction times the chord and T the two-stream
// transmittance of asymmetry g (heap.h).
FORMULA real lobeSunlight(real mean_opacity, real depth, real g) {
  return 1.0 - mean_opacity * (1.0 - diffuseTransmittance(depth, g));
}

// A target's brightness relative to its albedo lit by the whole sun (MODEL.md sections 5, 16):
// kTargetAmbient from the sky, the rest from the sun by Lambert's law, for the sunlight share S
// reaching it and N.L.
CONSTANT real kTargetAmbient = 0.3;
FORMULA real targetLight(real sunlight, real n_dot_l) {
  return kTargetAmbient + (1.0 - kTargetAmbient) * (sunlight * max(0.0, n_dot_l));
}

#ifdef __cplusplus
}  // namespace nephele::formulas
#endif
