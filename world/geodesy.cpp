#include "world/geodesy.h"

#include <cmath>
#include <numbers>

namespace nephele {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;
constexpr double kE2 = kWgs84F * (2.0 - kWgs84F);  // first eccentricity squared
constexpr double kB = kWgs84A * (1.0 - kWgs84F);   // semi-minor axis

}  // namespace

glm::dvec3 earthCentred(const Geodetic& g) {
  const double lat = g.latitude_deg * kDeg, lon = g.longitude_deg * kDeg;
  const double s = std::sin(lat), c = std::cos(lat);
  const double n = kWgs84A / std::sqrt(1.0 - kE2 * s * s);  // prime vertical radius
  return {(n + g.height_m) * c * std::cos(lon), (n + g.height_m) * c * std::sin(lon),
          (n * (1.0 - kE2) + g.height_m) * s};
}

Geodetic geodeticFromEarthCentred(glm::dvec3 p) {
  Geodetic g;
  g.longitude_deg = std::atan2(p.y, p.x) / kDeg;
  const double r = std::hypot(p.x, p.y);
  // Bowring: iterate the parametric latitude; three turns reach 1e-12 rad anywhere on Earth.
  const double ep2 = kE2 / (1.0 - kE2);  // second eccentricity squared
  double beta = std::atan2(p.z, (1.0 - kWgs84F) * r);
  double lat = 0.0;
  for (int i = 0; i < 5; ++i) {
    const double sb = std::sin(beta), cb = std::cos(beta);
    lat = std::atan2(p.z + ep2 * kB * sb * sb * sb, r - kE2 * kWgs84A * cb * cb * cb);
    const double next = std::atan2((1.0 - kWgs84F) * std::sin(lat), std::cos(lat));
    if (std::abs(next - beta) < 1e-15) break;
    beta = next;
  }
  const double s = std::sin(lat), c = std::cos(lat);
  const double n = kWgs84A / std::sqrt(1.0 - kE2 * s * s);
  // Height along the normal, from whichever of the two forms is well conditioned.
  g.height_m = std::abs(c) > 0.5 ? r / c - n : p.z / s - n * (1.0 - kE2);
  g.latitude_deg = lat / kDeg;
  return g;
}

LocalFrame::LocalFrame(double latitude_deg, double longitude_deg)
    : origin_(earthCentred({latitude_deg, longitude_deg, 0.0})) {
  const double lat = latitude_deg * kDeg, lon = longitude_deg * kDeg;
  east_ = {-std::sin(lon), std::cos(lon), 0.0};
  north_ = {-std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon), std::cos(lat)};
  up_ = {std::cos(lat) * std::cos(lon), std::cos(lat) * std::sin(lon), std::sin(lat)};
}

glm::dvec3 LocalFrame::toLocal(const Geodetic& g) const {
  const glm::dvec3 d = earthCentred({g.latitude_deg, g.longitude_deg, 0.0}) - origin_;
  return {glm::dot(d, east_), glm::dot(d, north_), g.height_m};
}

Geodetic LocalFrame::toGeodetic(glm::dvec3 local) const {
  // The point of the tangent plane, then down the site's vertical to the ellipsoid: the
  // nearer root of |S (q + t u)|^2 = 1, S = diag(1/a, 1/a, 1/b).
  const glm::dvec3 q = origin_ + local.x * east_ + local.y * north_;
  const glm::dvec3 s(1.0 / kWgs84A, 1.0 / kWgs84A, 1.0 / kB);
  const glm::dvec3 sq = s * q, su = s * up_;
  const double a = glm::dot(su, su), half_b = glm::dot(sq, su), c = glm::dot(sq, sq) - 1.0;
  const double disc = half_b * half_b - a * c;
  double t = -half_b / a;  // beyond the horizon: the closest approach
  if (disc >= 0.0) {
    // Both roots lie below the plane; the foot is the upper one, -half_b + sqrt(disc) over a,
    // written as c / (-half_b - sqrt(disc)) where half_b > 0 cancels.
    const double root = std::sqrt(disc);
    t = half_b > 0.0 ? c / (-half_b - root) : (-half_b + root) / a;
  }
  Geodetic g = geodeticFromEarthCentred(q + t * up_);
  g.height_m = local.z;
  return g;
}

}  // namespace nephele
