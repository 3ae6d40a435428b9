#pragma once
// Light through a heap (MODEL.md section 14): how much sunlight and sky light reaches each
// ellipsoid of a cloud through the cloud's other ellipsoids, computed once per cloud and sun
// direction (per-particle attenuation in the manner of Harris and Lastra 2001, applied to
// Gardner's ellipsoids), and the forward-scattered light a thin edge gives off with the sun
// behind it (the silver lining).
#include <vector>

#include <glm/glm.hpp>

#include "world/formations/ellipsoid_cloud.h"

namespace nephele {

// The share of the sun's light and of the sky's light that reaches one ellipsoid.
struct LobeLight {
  double sun = 1.0;
  double sky = 1.0;
};

// For each ellipsoid of `cloud`: the two-stream transmittance (diffuseTransmittance) of the
// optical depth from its centre towards the sun (`to_sun`, unit) and straight up through the
// cloud's other ellipsoids, at the cloud's light_extinction. All 1 when that is 0.
std::vector<LobeLight> lobeLights(const EllipsoidCloud& cloud, glm::dvec3 to_sun);

// Gardner eq. 8 with the heap's light (MODEL.md section 14): the diffuse and highlight terms
// take the sunlight reaching the lobe, the ambient term the sky light, and light scattered
// forward through the surface's translucent part is added,
//   I = (1 - a){(1 - t)[(1 - s) L.sun Id + s L.sun Is] + t It} + a L.sky
//       + L.sun P(cos theta) / (4 pi) TR,
// P the Cornette-Shanks phase function with the droplets' asymmetry, cos theta = d . to_sun
// for the view direction d, TR the surface's translucence (Gardner eq. 11). With the cloud's
// light_extinction 0 it is eq. 8 unchanged.
double heapIntensity(const EllipsoidCloud& cloud, const LobeLight& light, double texture_value,
                     glm::dvec3 normal, glm::dvec3 to_sun, glm::dvec3 direction,
                     double translucence);

// L.sun P(cos theta) / (4 pi): the forward-scattered term alone.
double forwardScattered(double sun, double cos_theta);

}  // namespace nephele
