#include "world/formations/ellipsoid_cloud.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "world/counter_random.h"

namespace nephele {
namespace {
double smoothstep(double edge0, double edge1, double x) {
  const double t = std::clamp((x - edge0) / (edge1 - edge0), 0.0, 1.0);
  return t * t * (3.0 - 2.0 * t);
}
}  // namespace

BoundingBox boundingBox(const EllipsoidCloud& cloud) {
  BoundingBox box{glm::dvec3(std::numeric_limits<double>::infinity()),
                  glm::dvec3(-std::numeric_limits<double>::infinity())};
  for (const Ellipsoid& e : cloud.ellipsoids) {
    const double r = std::max({e.radii.x, e.radii.y, e.radii.z});
    box.lo = glm::min(box.lo, e.centre - r);
    box.hi = glm::max(box.hi, e.centre + r);
  }
  return box;
}

BoundingSphere boundingSphere(const EllipsoidCloud& cloud) {
  const BoundingBox box = boundingBox(cloud);
  BoundingSphere s;
  s.centre = 0.5 * (box.lo + box.hi);
  for (const Ellipsoid& e : cloud.ellipsoids)
    s.radius = std::max(
        s.radius, glm::length(e.centre - s.centre) + std::max({e.radii.x, e.radii.y, e.radii.z}));
  return s;
}

std::pair<double, double> cloudVerticalExtent(const EllipsoidCloud& cloud) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const Ellipsoid& e : cloud.ellipsoids) {
    const double half = verticalHalfExtent(e);
    lo = std::min(lo, e.centre.z - half);
    hi = std::max(hi, e.centre.z + half);
  }
  return {lo, hi};
}

double cloudAltitude(const EllipsoidCloud& cloud) {
  const auto [lo, hi] = cloudVerticalExtent(cloud);
  return 0.5 * (lo + hi);
}

std::vector<Ellipsoid> cumulusEllipsoids(int count, glm::dvec3 base_centre, double width_m,
                                         std::uint64_t seed) {
  auto random = [&](int i, int purpose) {
    return unitFromBits(
        hashCounters(seed, 0x43756d75ull, std::uint64_t(i), std::uint64_t(purpose)));
  };
  // Three tiers, as fractions of the width: lobe radius, flatness (z / horizontal), radius of
  // the disc the lobes spread over, and height of their centres above the base.
  struct Tier {
    double radius, flatness, spread, height;
  };
  const Tier tiers[3] = {
      {0.24, 0.5, 0.30, 0.12}, {0.19, 0.75, 0.20, 0.30}, {0.14, 0.9, 0.11, 0.46}};
  const int base_count = std::max(1, (count + 2) / 3);
  const int middle_count = std::max(0, std::min(count - base_count, count / 3));
  const int tier_counts[3] = {base_count, middle_count, count - base_count - middle_count};
  std::vector<Ellipsoid> out;
  constexpr double kGoldenAngle = 2.399963229728653;  // even spread around each disc
  for (int tier = 0, i = 0; tier < 3; ++tier)
    for (int k = 0; k < tier_counts[tier]; ++k, ++i) {
      const Tier& t = tiers[tier];
      const double angle = kGoldenAngle * k + 0.5 * random(i, 0);
      const double distance = width_m * t.spread * std::sqrt((k + 0.5) / tier_counts[tier]) *
                              (0.8 + 0.4 * random(i, 1));
      const double size = width_m * t.radius * (0.85 + 0.3 * random(i, 2));
      Ellipsoid e;
      e.radii = {size * (0.9 + 0.25 * random(i, 3)), size * (0.9 + 0.25 * random(i, 4)),
                 size * t.flatness};
      e.centre = base_centre + glm::dvec3(distance * std::cos(angle), distance * std::sin(angle),
                                          width_m * t.height);
      e.orientation.heading_deg = 360.0 * random(i, 5);
      out.push_back(e);
    }
  return out;
}

double surfaceFade(double eye_radius) {
  return smoothstep(1.0, 1.0 + kInCloudBand, eye_radius);
}

double veilOpacity(double eye_radius) {
  return 1.0 - smoothstep(1.0 - kInCloudBand, 1.0 + kInCloudBand, eye_radius);
}

Veil inCloudVeil(const std::vector<EllipsoidCloud>& clouds,
                 const std::function<const SolidTexture&(std::size_t)>& texture, glm::dvec3 eye,
                 const Sun& sun) {
  std::vector<const EllipsoidCloud*> listed;
  for (const EllipsoidCloud& cloud : clouds) listed.push_back(&cloud);
  return inCloudVeil(listed, texture, eye, sun);
}

Veil inCloudVeil(std::span<const EllipsoidCloud* const> clouds,
                 const std::function<const SolidTexture&(std::size_t)>& texture, glm::dvec3 eye,
                 const Sun& sun) {
  double transmittance = 1.0, weight = 0.0;
  glm::dvec3 weighted(0.0);
  const double lit_from_above = std::max(0.0, sunDirection(sun).z);
  for (std::size_t c = 0; c < clouds.size(); ++c) {
    const EllipsoidCloud& cloud = *clouds[c];
    double cloud_transmittance = 1.0;
    for (const Ellipsoid& e : cloud.ellipsoids) {
      // Outside the ball of (1 + band) times the longest semi-axis the unit-sphere radius
      // exceeds 1 + band, where the veil is 0.
      const double reach = (1.0 + kInCloudBand) * std::max({e.radii.x, e.radii.y, e.radii.z});
      const glm::dvec3 d = eye - e.centre;
      if (glm::dot(d, d) > reach * reach) continue;
      const glm::dvec3 o = worldToUnitSphere(e) * d;
      cloud_transmittance *= 1.0 - veilOpacity(glm::length(o));
    }
    if (cloud_transmittance == 1.0) continue;
    const double it = texture(c).value(eye - cloud.drift_m);
    const double intensity = gardnerIntensity(cloud.shading, lit_from_above, 0.0, it);
    const double opacity = 1.0 - cloud_transmittance;
    weighted += opacity * intensity * cloud.colour * sun.colour;
    weight += opacity;
    transmittance *= cloud_transmittance;
  }
  Veil veil;
  if (weight > 0.0) {
    veil.colour = weighted / weight;
    veil.opacity = 1.0 - transmittance;
  }
  return veil;
}

}  // namespace nephele
