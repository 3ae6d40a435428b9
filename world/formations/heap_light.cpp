#include "world/formations/heap_light.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include <glm/gtc/matrix_access.hpp>

#include "world/automaton/cloud_density.h"
#include "world/formulas/ellipsoid.h"
#include "world/formulas/heap.h"

namespace nephele {
namespace {

// Two ellipsoids belong to one heap when the centre of either lies within this multiple of
// the other (MODEL.md section 14).
constexpr double kJoin = 1.25;

// The root of i's group, halving the path on the way.
std::size_t groupOf(std::vector<std::size_t>& parent, std::size_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

}  // namespace

std::vector<std::size_t> heapGroups(const EllipsoidCloud& cloud) {
  const std::vector<Ellipsoid>& lobes = cloud.ellipsoids;
  const std::size_t n = lobes.size();
  // Heaps: the parts the cloud names, or else groups joined pairwise, the candidate pairs
  // found by a sweep along x over the ellipsoids' bounding spheres.
  std::vector<std::size_t> parent(n), order;
  std::iota(parent.begin(), parent.end(), 0);
  if (cloud.parts.size() == n) {
    // The parts the cloud names: each part's first ellipsoid stands for it.
    std::vector<std::size_t> first(n, n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t part = std::min<std::size_t>(cloud.parts[i], n - 1);
      if (first[part] == n) first[part] = i;
      parent[i] = first[part];
    }
    return parent;
  }
  std::vector<double> reach(n);
  std::vector<glm::dmat3> to_unit(n);
  for (std::size_t i = 0; i < n; ++i) {
    reach[i] = std::max({lobes[i].radii.x, lobes[i].radii.y, lobes[i].radii.z});
    to_unit[i] = worldToUnitSphere(lobes[i]);
  }
  order.resize(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return lobes[a].centre.x - reach[a] < lobes[b].centre.x - reach[b];
  });
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t a = order[k];
    for (std::size_t m = k + 1; m < order.size(); ++m) {
      const std::size_t b = order[m];
      if (lobes[b].centre.x - reach[b] > lobes[a].centre.x + reach[a]) break;
      const double together = reach[a] + reach[b];
      const glm::dvec3 between = lobes[a].centre - lobes[b].centre;
      if (glm::dot(between, between) >= together * together) continue;
      // Joined when either centre lies within kJoin times the other ellipsoid: lobes that sit
      // on or in one another, not ones that merely touch.
      const glm::dvec3 in_b = to_unit[b] * between, in_a = to_unit[a] * between;
      if (glm::dot(in_b, in_b) < kJoin * kJoin || glm::dot(in_a, in_a) < kJoin * kJoin)
        parent[groupOf(parent, a)] = groupOf(parent, b);
    }
  }
  for (std::size_t i = 0; i < n; ++i) parent[i] = groupOf(parent, i);
  return parent;
}

void SecondMoments::add(const Ellipsoid& e) {
  // A solid ellipsoid of volume V with T = body-to-world times radii has moments V T T^T / 5
  // about its centre; along the axes, V diag(T T^T) / 5.
  const glm::dmat3 t = unitSphereToWorld(e);
  const glm::dvec3 spread(glm::dot(glm::row(t, 0), glm::row(t, 0)),
                          glm::dot(glm::row(t, 1), glm::row(t, 1)),
                          glm::dot(glm::row(t, 2), glm::row(t, 2)));
  const double v = 4.0 / 3.0 * std::numbers::pi * std::abs(glm::determinant(t));
  volume += v;
  first += v * e.centre;
  second += v * (spread / 5.0 + e.centre * e.centre);
}

std::optional<Ellipsoid> SecondMoments::ellipsoid() const {
  if (!(volume > 0.0)) return std::nullopt;
  // The axis-aligned ellipsoid of the same second moments: semi-axes sqrt(5 variance).
  Ellipsoid e;
  e.centre = first / volume;
  const glm::dvec3 variance = glm::max(second / volume - e.centre * e.centre, 0.0);
  e.radii = glm::max(glm::sqrt(5.0 * variance), glm::dvec3(1e-3));
  return e;
}

std::vector<HeapEnvelope> heapEnvelopes(const EllipsoidCloud& cloud) {
  const std::vector<Ellipsoid>& lobes = cloud.ellipsoids;
  const std::size_t n = lobes.size();
  std::vector<HeapEnvelope> out(n);
  if (!(cloud.light_extinction > 0.0) || n == 0) return out;
  const std::vector<std::size_t> group = heapGroups(cloud);
  std::vector<SecondMoments> moments(n);
  for (std::size_t i = 0; i < n; ++i) moments[group[i]].add(lobes[i]);
  for (std::size_t i = 0; i < n; ++i) {
    const SecondMoments& g = moments[group[i]];
    const std::optional<Ellipsoid> body = g.ellipsoid();
    if (!body) continue;
    HeapEnvelope& e = out[i];
    e.centre = body->centre;
    e.radii = body->radii;
    const double volume = 4.0 / 3.0 * std::numbers::pi * e.radii.x * e.radii.y * e.radii.z;
    e.extinction = cloud.light_extinction * std::min(g.volume / volume, 1.0);
  }
  return out;
}

double envelopeChord(const HeapEnvelope& envelope, glm::dvec3 p, glm::dvec3 dir) {
  return formulas::unitSphereChord((p - envelope.centre) / envelope.radii, dir / envelope.radii);
}

HeapLight heapLightAt(const HeapEnvelope& envelope, glm::dvec3 p, glm::dvec3 normal,
                      glm::dvec3 to_sun) {
  if (!(envelope.extinction > 0.0)) return {};
  // MODEL.md section 14: light inside a cloud is scattered on, not removed, so it falls as the
  // two-stream transmittance of the depth, not exp(-depth); the GL's cloud.glsl takes the same
  // formulas (world/formulas/heap.h).
  const glm::dvec3 up(0.0, 0.0, 1.0);
  const double sun = formulas::heapDepth(envelope.extinction, envelopeChord(envelope, p, to_sun),
                                         glm::dot(normal, to_sun));
  const double sky = formulas::heapDepth(envelope.extinction, envelopeChord(envelope, p, up),
                                         glm::dot(normal, up));
  const glm::dvec3 light = formulas::heapLight(sun, sky, kDiffuseAsymmetry);
  return {light.x, light.y, light.z};
}

glm::dvec3 heapLitNormal(const HeapEnvelope& envelope, glm::dvec3 p, glm::dvec3 normal) {
  if (!(envelope.extinction > 0.0)) return normal;
  // The envelope's outward normal: the gradient of its quadric, (p - c) / radii^2.
  const glm::dvec3 gradient = (p - envelope.centre) / (envelope.radii * envelope.radii);
  const double length = glm::length(gradient);
  if (!(length > 0.0) || !std::isfinite(length)) return normal;
  // Both unit, and 1 - b != b: the blend is at least |1 - 2b| long, never zero.
  return formulas::bentNormal(normal, gradient, kHeapNormalBend);
}

double skinDiffuse(double n_dot_l) {
  return formulas::skinDiffuse(n_dot_l, kSkinWrap);
}

MeanHeapLight meanHeapLight(const EllipsoidCloud& cloud, glm::dvec3 to_sun) {
  if (!(cloud.light_extinction > 0.0) || cloud.ellipsoids.empty()) return {};
  const std::vector<HeapEnvelope> envelopes = heapEnvelopes(cloud);
  constexpr int kNormals = 64;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  double sun = 0.0, sky = 0.0, weight = 0.0;
  for (std::size_t i = 0; i < cloud.ellipsoids.size(); ++i) {
    const Ellipsoid& e = cloud.ellipsoids[i];
    const glm::dmat3 t = unitSphereToWorld(e), m = t * glm::transpose(t);
    const double w = e.radii.x * e.radii.y;
    for (int k = 0; k < kNormals; ++k) {
      // Normals evenly over the sphere (a Fibonacci lattice); the surface point whose normal
      // is n is centre + M n / sqrt(n . M n).
      const double z = 1.0 - (2.0 * k + 1.0) / kNormals, ring = std::sqrt(1.0 - z * z);
      const glm::dvec3 n(ring * std::cos(golden * k), ring * std::sin(golden * k), z);
      const glm::dvec3 p = e.centre + m * n / std::sqrt(glm::dot(n, m * n));
      const glm::dvec3 lit = heapLitNormal(envelopes[i], p, n);
      const HeapLight light = heapLightAt(envelopes[i], p, lit, to_sun);
      sun += w * light.sun * skinDiffuse(glm::dot(lit, to_sun));
      sky += w * light.sky;
    }
    weight += w * kNormals;
  }
  return {sun / weight / 0.25, sky / weight};
}

double forwardScattered(double sun, double cos_theta) {
  return formulas::forwardScattered(sun, cos_theta, kDiffuseAsymmetry);
}

double heapIntensity(const EllipsoidCloud& cloud, const HeapLight& light, double texture_value,
                     glm::dvec3 normal, glm::dvec3 to_sun, glm::dvec3 direction,
                     double translucence) {
  const ShadingParams& shading = cloud.shading;
  // A heap-lit normal is turned towards the viewer before it is bent (heapLitNormal), not after.
  const DiffuseHighlight d =
      diffuseHighlight(shading, normal, to_sun, -direction, !(cloud.light_extinction > 0.0));
  if (!(cloud.light_extinction > 0.0))
    return gardnerIntensity(shading, light.sun * d.diffuse, light.sun * d.highlight, texture_value);
  // Gardner eq. 8 with the sun's terms times S and the ambient term times K.
  const double eq8 = heapLitIntensity(shading, light.sun, light.sky, skinDiffuse(d.n_dot_l),
                                      d.highlight, texture_value);
  return eq8 + forwardScattered(light.direct, glm::dot(direction, to_sun)) * translucence;
}

}  // namespace nephele
