#include "world/shading.h"

#include <algorithm>

#include "world/formulas/heap.h"
#include "world/formulas/shading.h"

namespace nephele {
namespace {

glm::dvec4 termsOf(const ShadingParams& shading) {
  return {shading.ambient, shading.texture_fraction, shading.specular, shading.shininess};
}

}  // namespace

double gardnerIntensity(const ShadingParams& shading, double diffuse, double highlight,
                        double texture_value) {
  return formulas::gardnerIntensity(termsOf(shading), diffuse, highlight, texture_value);
}

double heapLitIntensity(const ShadingParams& shading, double sun, double sky, double diffuse,
                        double highlight, double texture_value) {
  return formulas::heapLitIntensity(termsOf(shading), sun, sky, diffuse, highlight, texture_value);
}

DiffuseHighlight diffuseHighlight(const ShadingParams& shading, glm::dvec3 normal,
                                  glm::dvec3 to_sun, glm::dvec3 to_viewer, bool turn) {
  glm::dvec3 n = glm::normalize(normal);
  if (turn) n = formulas::facingViewer(n, -to_viewer);
  const double n_dot_l = glm::dot(n, to_sun);
  DiffuseHighlight out{std::max(0.0, n_dot_l), 0.0, n_dot_l};
  if (n_dot_l > 0.0 && shading.specular > 0.0)
    out.highlight = formulas::phongHighlight(n, n_dot_l, to_sun, to_viewer, shading.shininess);
  return out;
}

double gardnerIntensity(const ShadingParams& shading, double texture_value, glm::dvec3 normal,
                        glm::dvec3 to_sun, glm::dvec3 to_viewer) {
  const DiffuseHighlight d = diffuseHighlight(shading, normal, to_sun, to_viewer);
  return gardnerIntensity(shading, d.diffuse, d.highlight, texture_value);
}

double sphereDiffuse(double cos_alpha) {
  return formulas::sphereDiffuse(cos_alpha);
}

double skyPlaneTranslucence(double texture_value, double threshold, double transition) {
  return formulas::translucence(texture_value - threshold, transition);  // Gardner eq. 9
}

double ellipsoidTranslucence(double texture_value, double threshold_centre, double threshold_limb,
                             double limb_g, double transition) {
  return formulas::translucence(
      formulas::limbExcess(texture_value, threshold_centre, threshold_limb, limb_g),
      transition);  // Gardner eq. 11
}

}  // namespace nephele
