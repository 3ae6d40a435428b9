#include "world/shading.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace nephele {
namespace {

// clamp(1 - excess / D, 0, 1), with D = 0 meaning a step at excess = 0.
double translucenceFromExcess(double excess, double transition) {
  if (transition <= 0.0) return excess <= 0.0 ? 1.0 : 0.0;
  return std::clamp(1.0 - excess / transition, 0.0, 1.0);
}

}  // namespace

double gardnerIntensity(const ShadingParams& shading, double diffuse, double highlight,
                        double texture_value) {
  const double a = shading.ambient, t = shading.texture_fraction, s = shading.specular;
  return (1.0 - a) * ((1.0 - t) * ((1.0 - s) * diffuse + s * highlight) + t * texture_value) +
         a;  // Gardner eq. 8
}

DiffuseHighlight diffuseHighlight(const ShadingParams& shading, glm::dvec3 normal,
                                  glm::dvec3 to_sun, glm::dvec3 to_viewer, bool turn) {
  glm::dvec3 n = glm::normalize(normal);
  if (turn && glm::dot(n, to_viewer) < 0.0) n = -n;
  const double n_dot_l = glm::dot(n, to_sun);
  DiffuseHighlight out{std::max(0.0, n_dot_l), 0.0, n_dot_l};
  if (n_dot_l > 0.0 && shading.specular > 0.0) {
    const glm::dvec3 reflected = 2.0 * n_dot_l * n - to_sun;
    out.highlight = std::pow(std::max(0.0, glm::dot(reflected, to_viewer)), shading.shininess);
  }
  return out;
}

double gardnerIntensity(const ShadingParams& shading, double texture_value, glm::dvec3 normal,
                        glm::dvec3 to_sun, glm::dvec3 to_viewer) {
  const DiffuseHighlight d = diffuseHighlight(shading, normal, to_sun, to_viewer);
  return gardnerIntensity(shading, d.diffuse, d.highlight, texture_value);
}

double sphereDiffuse(double cos_alpha) {
  const double alpha = std::acos(std::clamp(cos_alpha, -1.0, 1.0));
  return (2.0 / 3.0) * (std::sin(alpha) + (std::numbers::pi - alpha) * cos_alpha) /
         std::numbers::pi;
}

double skyPlaneTranslucence(double texture_value, double threshold, double transition) {
  return translucenceFromExcess(texture_value - threshold, transition);  // Gardner eq. 9
}

double ellipsoidTranslucence(double texture_value, double threshold_centre, double threshold_limb,
                             double limb_g, double transition) {
  const double threshold = threshold_centre + (threshold_limb - threshold_centre) * (1.0 - limb_g);
  return translucenceFromExcess(texture_value - threshold, transition);  // Gardner eq. 11
}

}  // namespace nephele
