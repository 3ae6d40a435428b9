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

// The share of the sun's light and of the sky's light that reaches one ellipsoid: the sun's
// at its centre and at its most sunward point, the sky's at its centre.
struct LobeLight {
  double sun = 1.0;
  double sky = 1.0;
  double sun_face = 1.0;
};

// For each ellipsoid of `cloud`: the two-stream transmittance (diffuseTransmittance) of the
// optical depth through the cloud's other ellipsoids, at the cloud's light_extinction, from
// its centre towards the sun (`to_sun`, unit) and straight up, and from the point of its
// surface whose normal is to_sun towards the sun. All 1 when light_extinction is 0.
std::vector<LobeLight> lobeLights(const EllipsoidCloud& cloud, glm::dvec3 to_sun);

// The sunlight at a surface point of a lobe with unit normal n: from the centre's share where
// n turns from the sun to the sunward point's where it faces it,
//   S(n) = S_centre + (S_face - S_centre) (1 + n.L) / 2.
double surfaceSunlight(const LobeLight& light, double n_dot_l);

// Gardner eq. 8 with the heap's light (MODEL.md section 14): the diffuse and highlight terms
// take the sunlight reaching the surface (surfaceSunlight; the diffuse term through the skin,
// skinDiffuse), the
// ambient term the sky light, and light scattered forward through the surface's translucent
// part is added,
//   I = (1 - a){(1 - t)[(1 - s) S Id' + s S Is] + t It} + a L.sky + S P(cos theta) / (4 pi) TR,
// P the Cornette-Shanks phase function with the droplets' asymmetry, cos theta = d . to_sun
// for the view direction d, TR the surface's translucence (Gardner eq. 11). With the cloud's
// light_extinction 0 it is eq. 8 unchanged.
double heapIntensity(const EllipsoidCloud& cloud, const LobeLight& light, double texture_value,
                     glm::dvec3 normal, glm::dvec3 to_sun, glm::dvec3 direction,
                     double translucence);

// Sunlight through a lobe's own skin (MODEL.md section 14): a heap-lit lobe takes the diffuse
// term as max(0, (N.L + w) / (1 + w)) instead of max(0, N.L), since light entering its sunlit
// face is scattered on round the lobe before it leaves, and the face turned from the sun is
// lit through the lobe's edge. w = kSkinWrap.
inline constexpr double kSkinWrap = 0.6;
double skinDiffuse(double n_dot_l);

// A lobe's sunlit diffuse term over its whole surface, S(n) skinDiffuse(n.L) averaged over
// normals spread evenly over the sphere (n.L uniform on [-1, 1]), as a multiple of the
// Lambertian mean max(0, n.L), 1/4: with L = 1 + w and D = S_face - S_centre,
//   [S_centre + D (1 - w) / 2] L + D L^2 / 3.
// What a surface standing for many lobes (the far deck) multiplies its own diffuse term by.
double lobeSunlightOverLambert(const LobeLight& light);

// L.sun P(cos theta) / (4 pi): the forward-scattered term alone.
double forwardScattered(double sun, double cos_theta);

}  // namespace nephele
