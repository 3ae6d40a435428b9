// Scattering in clouds (MODEL.md sections 6 and 14): the phase functions, the light a point of
// an automaton cloud scatters towards the viewer and a segment's transmittance, and the sunbeam
// a heap's skin scatters forward. Shared by world/automaton/cloud_density.h,
// world/formations/heap_light.cpp and the GL renderer's volume pass and ellipsoid shader
// (renderer/gl/shaders/automaton/volume_pass.glsl, ellipsoid/cloud.glsl; see prelude.h).
#ifdef __cplusplus
#pragma once
#include "world/formulas/prelude.h"
#include "world/formulas/shading.h"

namespace nephele::formulas {
#endif

// Rayleigh's phase function, 3/4 (1 + cos^2 theta), for the cosine c of the scattering angle.
FORMULA real rayleighPhase(real c) {
  return 0.75 * (1.0 + c * c);
}

// Cornette and Shanks' phase function (Shen eq. 11) of asymmetry g for the cosine c:
// 3/2 (1 - g^2) / (2 + g^2) (1 + c^2) / (1 + g^2 - 2 g c)^(3/2). The base is held at 1e-12 or
// more, so that g = 1 looking into the sun stays finite.
FORMULA real cornetteShanksPhase(real c, real g) {
  real g2 = g * g;
  return 1.5 * (1.0 - g2) / (2.0 + g2) * (1.0 + c * c) /
         pow(max(1.0 + g2 - 2.0 * g * c, 1e-12), 1.5);
}

// The sunbeam scattered forward through a heap's translucent skin (MODEL.md section 14): the
// unscattered share `sun` of the sunlight times P(c) / (4 pi), P Cornette-Shanks of asymmetry
// g.
FORMULA real forwardScattered(real sun, real c, real g) {
  return sun * cornetteShanksPhase(c, g) / (4.0 * kPi);
}

// The transmittance of a segment of `length` metres whose density runs linearly from rho_a to
// rho_b, `extinction` per metre at density 1: exact, and in [0, 1] however thick the segment.
FORMULA real segmentTransmittance(real rho_a, real rho_b, real length, real extinction) {
  return exp(-extinction * 0.5 * (rho_a + rho_b) * length);
}

// What a step of a march adds to the light scattered towards the eye, per unit of the light's
// colour: the transmittance before it times the step's opacity 1 - segment times its source,
// held at the mean of the step's ends (MODEL.md section 6).
FORMULA real stepScattered(real transmittance, real segment, real source_a, real source_b) {
  return transmittance * (1.0 - segment) * (0.5 * (source_a + source_b));
}

// The light a point scatters towards the viewer, per unit of the sun's: the unscattered
// sunlight `sun_direct` through the phase function, the rest of the sunlight there,
// `sun_diffuse` less sun_direct, scattered evenly, and the sky light `ambient` x `sky`. The
// difference is held at 0 or more: exact values never go below it, interpolated ones might.
FORMULA real scatteredLight(real phase, real sun_direct, real sun_diffuse, real ambient, real sky) {
  return phase * sun_direct + max(sun_diffuse - sun_direct, 0.0) + ambient * sky;
}

#ifdef __cplusplus
}  // namespace nephele::formulas
#endif
