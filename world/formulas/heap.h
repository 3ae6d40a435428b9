// Light through a heap (MODEL.md section 14): the depths towards the sun and the sky of a point
// on a lobe, the two-stream transmittance they take, the lobe's skin and its bent normal.
// Shared by world/formations/heap_light.cpp (heapLightAt, heapLitNormal, skinDiffuse),
// world/automaton/cloud_density.h (diffuseTransmittance) and the GL renderer's
// renderer/gl/shaders/ellipsoid/cloud.glsl (see prelude.h).
#ifdef __cplusplus
#pragma once
#include "world/formulas/prelude.h"
#include "world/formulas/shading.h"

namespace nephele::formulas {
#endif

// The asymmetry of cloud droplets' scattering for diffuse light (MODEL.md section 6, sky light).
CONSTANT real kDiffuseAsymmetry = 0.85;

// The share of diffuse light a non-absorbing cloud of optical depth tau lets through, two-stream
// with asymmetry g: 1 / (1 + 3/4 (1 - g) tau) (MODEL.md section 6, sky light). 1 at tau = 0,
// falling as 1 / tau, never to 0.
FORMULA real diffuseTransmittance(real tau, real g) {
  return 1.0 / (1.0 + 0.75 * (1.0 - g) * tau);
}

// The optical depth from a point of unit normal n towards the light along unit v, through its
// heap's envelope: the envelope's extinction times its chord along v, times (1 - n.v) / 2, since
// a face turned towards the light looks out of the heap, not through it.
FORMULA real heapDepth(real extinction, real chord, real n_dot_v) {
  return extinction * (0.5 * (1.0 - clamp(n_dot_v, -1.0, 1.0))) * chord;
}

// The light the heap lets reach the point (HeapLight): the sun's share S = T(sun_depth), the
// sky's K = 1/2 + 1/2 T(sky_depth), the depth straight up (half the sky light comes from
// overhead through the heap, half from the horizon and the ground, which it does not hide),
// and the unscattered sunbeam exp(-sun_depth); T the two-stream transmittance, asymmetry g.
FORMULA vec3 heapLight(real sun_depth, real sky_depth, real g) {
  return vec3(diffuseTransmittance(sun_depth, g), 0.5 + 0.5 * diffuseTransmittance(sky_depth, g),
              exp(-sun_depth));
}

// The lobe's unit normal n bent towards its heap's outward normal (along `gradient`, not zero)
// by `bend`: normalize((1 - bend) n + bend normalize(gradient)), so that the heap, not each
// lobe, has the terminator (heapLitNormal).
FORMULA vec3 bentNormal(vec3 n, vec3 gradient, real bend) {
  return normalize(mix(n, normalize(gradient), bend));
}

// Sunlight through the lobe's own skin: max(0, (N.L + w) / (1 + w)) for the wrap w, Lambert's
// max(0, N.L) at w = 0 (skinDiffuse).
FORMULA real skinDiffuse(real n_dot_l, real wrap) {
  return max((n_dot_l + wrap) / (1.0 + wrap), 0.0);
}

// Gardner eq. 8 lit through a heap (MODEL.md section 14): the sun's terms (`diffuse`,
// `highlight`) times the sun's share S, the ambient term a times the sky's K, with shading =
// (a, t, s, e): gardnerIntensity + a (K - 1). The sunbeam scattered forward through the skin is
// the caller's to add.
FORMULA real heapLitIntensity(vec4 shading, real sun, real sky, real diffuse, real highlight,
                              real it) {
  return gardnerIntensity(shading, sun * diffuse, sun * highlight, it) + shading.x * (sky - 1.0);
}

#ifdef __cplusplus
}  // namespace nephele::formulas
#endif
