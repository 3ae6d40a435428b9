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

namespace {

// The unit east and north at a latitude and longitude, Earth-centred.
void eastNorth(double latitude_deg, double longitude_deg, glm::dvec3& east, glm::dvec3& north) {
  const double lat = latitude_deg * kDeg, lon = longitude_deg * kDeg;
  east = {-std::sin(lon), std::cos(lon), 0.0};
  north = {-std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon), std::cos(lat)};
}

}  // namespace

LocalFrame::LocalFrame(const Site& site)
    : origin_(earthCentred({site.latitude_deg, site.longitude_deg, 0.0})) {
  glm::dvec3 east, north;
  eastNorth(site.latitude_deg, site.longitude_deg, east, north);
  up_ = glm::cross(east, north);
  // +Y points along true bearing grid_deg, +X a right angle clockwise from it.
  const double c = std::cos(site.grid_deg * kDeg), s = std::sin(site.grid_deg * kDeg);
  x_ = c * east - s * north;
  y_ = s * east + c * north;
}

glm::dvec3 LocalFrame::toLocal(const Geodetic& g) const {
  const glm::dvec3 d = earthCentred({g.latitude_deg, g.longitude_deg, 0.0}) - origin_;
  return {glm::dot(d, x_), glm::dot(d, y_), g.height_m};
}

double LocalFrame::northBearing(const Geodetic& g) const {
  // The foot map is linear in Earth-centred coordinates, so a step north along the ellipsoid
  // at g maps to that step's tangent projected on the database's axes.
  glm::dvec3 east, north;
  eastNorth(g.latitude_deg, g.longitude_deg, east, north);
  return std::atan2(glm::dot(north, x_), glm::dot(north, y_)) / kDeg;
}

Recentring recentred(const Site& from, double latitude_deg, double longitude_deg) {
  const LocalFrame old(from);
  const Geodetic origin{latitude_deg, longitude_deg, 0.0};
  Recentring r;
  r.shift = glm::dvec2(old.toLocal(origin));
  // The old +Y at the new origin keeps its database bearing: the new grid north is its true
  // bearing there, so that a heading in the old database is the same heading in the new one.
  r.to = Site{latitude_deg, longitude_deg, -old.northBearing(origin)};
  return r;
}

Geodetic LocalFrame::toGeodetic(glm::dvec3 local) const {
  // The point of the tangent plane, then down the site's vertical to the ellipsoid: the
  // nearer root of |S (q + t u)|^2 = 1, S = diag(1/a, 1/a, 1/b).
  const glm::dvec3 q = origin_ + local.x * x_ + local.y * y_;
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
