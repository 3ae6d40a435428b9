#include "world/formations/heap_light.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "world/automaton/cloud_density.h"

namespace nephele {
namespace {

// Length of the ray p + s dir (dir unit, s >= 0) inside the ellipsoid `e`, metres.
double chordLength(const Ellipsoid& e, glm::dvec3 p, glm::dvec3 dir) {
  const glm::dmat3 w = worldToUnitSphere(e);
  const glm::dvec3 o = w * (p - e.centre), d = w * dir;
  const double a = glm::dot(d, d), half_b = glm::dot(o, d), c = glm::dot(o, o) - 1.0;
  const double quarter_delta = half_b * half_b - a * c;
  if (quarter_delta <= 0.0 || a <= 0.0) return 0.0;
  const double root = std::sqrt(quarter_delta);
  const double near = (-half_b - root) / a, far = (-half_b + root) / a;
  return std::max(0.0, far - std::max(near, 0.0));
}

// Optical depth from point p of ellipsoid i along `dir` through the others.
double depthThroughOthers(const EllipsoidCloud& cloud, std::size_t i, glm::dvec3 p,
                          glm::dvec3 dir) {
  double length = 0.0;
  for (std::size_t j = 0; j < cloud.ellipsoids.size(); ++j) {
    if (j == i) continue;
    const Ellipsoid& e = cloud.ellipsoids[j];
    // A ball of the longest semi-axis first: most ellipsoids are far off the ray.
    const double reach = std::max({e.radii.x, e.radii.y, e.radii.z});
    const glm::dvec3 to = e.centre - p;
    const double along = glm::dot(to, dir);
    if (along < -reach || glm::dot(to, to) - along * along > reach * reach) continue;
    length += chordLength(e, p, dir);
  }
  return cloud.light_extinction * length;
}

}  // namespace

std::vector<LobeLight> lobeLights(const EllipsoidCloud& cloud, glm::dvec3 to_sun) {
  std::vector<LobeLight> out(cloud.ellipsoids.size());
  if (cloud.light_extinction <= 0.0) return out;
  for (std::size_t i = 0; i < out.size(); ++i) {
    // MODEL.md section 14: light inside a cloud is scattered on, not removed, so it falls as the
    // two-stream transmittance of the depth, not exp(-depth).
    const Ellipsoid& e = cloud.ellipsoids[i];
    // The sunward point: where the normal is to_sun, centre + M L / sqrt(L.M L) with
    // M = T T^T, T the body-to-world matrix times the radii.
    const glm::dmat3 t = unitSphereToWorld(e);
    const glm::dvec3 tl = glm::transpose(t) * to_sun;
    const glm::dvec3 face = e.centre + t * tl / std::max(glm::length(tl), 1e-300);
    auto sunlight = [&](glm::dvec3 from) {
      return to_sun.z > -1.0 ? diffuseTransmittance(depthThroughOthers(cloud, i, from, to_sun))
                             : 0.0;
    };
    out[i].sun = sunlight(e.centre);
    out[i].sun_face = sunlight(face);
    // Half the sky light comes from the sky overhead, through the heap; half from the horizon
    // and the ground, which the heap does not hide.
    out[i].sky =
        0.5 + 0.5 * diffuseTransmittance(depthThroughOthers(cloud, i, e.centre, {0.0, 0.0, 1.0}));
  }
  return out;
}

double surfaceSunlight(const LobeLight& light, double n_dot_l) {
  return light.sun + (light.sun_face - light.sun) * 0.5 * (1.0 + std::clamp(n_dot_l, -1.0, 1.0));
}

double skinDiffuse(double n_dot_l) {
  return std::max(0.0, (n_dot_l + kSkinWrap) / (1.0 + kSkinWrap));
}

double lobeSunlightOverLambert(const LobeLight& light) {
  const double l = 1.0 + kSkinWrap, d = light.sun_face - light.sun;
  return (light.sun + d * (1.0 - kSkinWrap) / 2.0) * l + d * l * l / 3.0;
}

double forwardScattered(double sun, double cos_theta) {
  return sun * cornetteShanksPhase(cos_theta, kDiffuseAsymmetry) / (4.0 * std::numbers::pi);
}

double heapIntensity(const EllipsoidCloud& cloud, const LobeLight& light, double texture_value,
                     glm::dvec3 normal, glm::dvec3 to_sun, glm::dvec3 direction,
                     double translucence) {
  const ShadingParams& shading = cloud.shading;
  const DiffuseHighlight d = diffuseHighlight(shading, normal, to_sun, -direction);
  if (cloud.light_extinction <= 0.0)
    return gardnerIntensity(shading, d.diffuse, d.highlight, texture_value);
  // Gardner eq. 8 with the sun's terms times S(n) and the ambient term times L.sky.
  const double sun = surfaceSunlight(light, d.n_dot_l);
  const double eq8 =
      gardnerIntensity(shading, sun * skinDiffuse(d.n_dot_l), sun * d.highlight, texture_value) +
      shading.ambient * (light.sky - 1.0);
  return eq8 + forwardScattered(sun, glm::dot(direction, to_sun)) * translucence;
}

}  // namespace nephele
