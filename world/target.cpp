#include "world/target.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "world/formations/ellipsoid.h"
#include "world/formulas/shading.h"
#include "world/formulas/shadow.h"

namespace nephele {
namespace {

std::optional<TargetHit> intersectBox(glm::dvec3 half, glm::dvec3 o, glm::dvec3 d) {
  // Slabs in body coordinates.
  double enter = -std::numeric_limits<double>::infinity();
  double leave = std::numeric_limits<double>::infinity();
  int enter_axis = 0;
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0.0) {
      if (std::abs(o[i]) > half[i]) return std::nullopt;
      continue;
    }
    double t0 = (-half[i] - o[i]) / d[i], t1 = (half[i] - o[i]) / d[i];
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > enter) enter = t0, enter_axis = i;
    leave = std::min(leave, t1);
  }
  if (enter > leave || leave <= 0.0) return std::nullopt;
  if (enter <= 0.0) return std::nullopt;  // eye inside the box: its faces face away
  glm::dvec3 normal(0.0);
  normal[enter_axis] = d[enter_axis] > 0.0 ? -1.0 : 1.0;
  return TargetHit{enter, normal};
}

// Moller-Trumbore, both faces.
std::optional<double> intersectTriangle(glm::dvec3 o, glm::dvec3 d, glm::dvec3 a, glm::dvec3 b,
                                        glm::dvec3 c) {
  const glm::dvec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
  const double det = glm::dot(e1, p);
  if (std::abs(det) < 1e-300) return std::nullopt;
  const glm::dvec3 t = o - a;
  const double u = glm::dot(t, p) / det;
  if (u < 0.0 || u > 1.0) return std::nullopt;
  const glm::dvec3 q = glm::cross(t, e1);
  const double v = glm::dot(d, q) / det;
  if (v < 0.0 || u + v > 1.0) return std::nullopt;
  const double s = glm::dot(e2, q) / det;
  if (s <= 0.0) return std::nullopt;
  return s;
}

}  // namespace

glm::dvec3 targetRadiance(const Target& target, glm::dvec3 normal, glm::dvec3 to_sun,
                          glm::dvec3 to_viewer, const Sun& sun, double sunlight) {
  normal = formulas::facingViewer(normal, -to_viewer);
  return target.colour * sun.colour * formulas::targetLight(sunlight, glm::dot(normal, to_sun));
}

std::vector<glm::dvec3> scaledMeshVertices(const Target& target) {
  std::vector<glm::dvec3> out;
  if (!target.mesh) return out;
  out.reserve(target.mesh->vertices.size());
  for (const glm::dvec3& v : target.mesh->vertices) out.push_back(v * target.size);
  return out;
}

std::optional<TargetHit> intersectTarget(const Target& target, glm::dvec3 eye,
                                         glm::dvec3 direction) {
  const glm::dmat3 rotation = bodyToWorld(target.orientation);
  const glm::dmat3 to_body = glm::transpose(rotation);
  const glm::dvec3 o = to_body * (eye - target.centre), d = to_body * direction;
  switch (target.shape) {
    case TargetShape::kBox: {
      auto hit = intersectBox(target.size, o, d);
      if (hit) hit->normal = rotation * hit->normal;
      return hit;
    }
    case TargetShape::kEllipsoid: {
      Ellipsoid e{target.size, target.centre, target.orientation};
      const EllipsoidView view(e, eye);
      const auto span = view.intersect(direction);
      if (!span || span->near <= 0.0) return std::nullopt;
      return TargetHit{span->near, view.normalAt(direction, span->near)};
    }
    case TargetShape::kMesh: {
      if (!target.mesh) return std::nullopt;
      // Intersect in unscaled body space: dividing the ray by the scale keeps its parameter.
      const glm::dvec3 ou = o / target.size, du = d / target.size;
      const std::vector<glm::dvec3>& v = target.mesh->vertices;
      std::optional<TargetHit> best;
      for (const auto& tri : target.mesh->triangles) {
        const auto s = intersectTriangle(ou, du, v[tri[0]], v[tri[1]], v[tri[2]]);
        if (s && (!best || *s < best->distance)) {
          // Normals take the inverse transpose of the scale.
          const glm::dvec3 n = glm::cross(v[tri[1]] - v[tri[0]], v[tri[2]] - v[tri[0]]);
          best = TargetHit{*s, rotation * glm::normalize(n / target.size)};
        }
      }
      return best;
    }
  }
  return std::nullopt;
}

}  // namespace nephele
