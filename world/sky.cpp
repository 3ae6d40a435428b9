#include "world/sky.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace nephele {

glm::dvec3 skyBackground(const Sky& sky, glm::dvec3 direction) {
  const glm::dvec3 d = glm::normalize(direction);
  if (d.z < 0.0) return sky.ground;
  return sky.horizon + (sky.zenith - sky.horizon) * std::sqrt(d.z);
}

glm::dvec3 sunDirection(const Sun& sun) {
  const double az = sun.azimuth_deg * std::numbers::pi / 180.0;
  const double el = sun.elevation_deg * std::numbers::pi / 180.0;
  return {std::sin(az) * std::cos(el), std::cos(az) * std::cos(el), std::sin(el)};
}

double extinctionForVisibility(double visibility_m) {
  return -std::log(0.02) / visibility_m;
}

double visibilityForExtinction(double sigma) {
  return sigma > 0.0 ? -std::log(0.02) / sigma : std::numeric_limits<double>::infinity();
}

double fogExtinction(const Fog& fog) {
  return extinctionForVisibility(fog.visibility_m);
}

double fogDensity(const Fog& fog, double z) {
  if (z >= fog.bottom_m && z <= fog.top_m) return 1.0;
  const double out = z < fog.bottom_m ? fog.bottom_m - z : z - fog.top_m;
  return fog.band_m > 0.0 ? std::max(0.0, 1.0 - out / fog.band_m) : 0.0;
}

namespace {

// Its integral from below the slab to height z (+-infinity allowed).
double fogColumn(const Fog& fog, double z) {
  const double b = fog.band_m, low = fog.bottom_m - b, thick = fog.top_m - fog.bottom_m;
  if (!(z > low)) return 0.0;
  if (z <= fog.bottom_m) return (z - low) * (z - low) / (2.0 * b);
  if (z <= fog.top_m) return 0.5 * b + (z - fog.bottom_m);
  if (z <= fog.top_m + b) {
    const double u = z - fog.top_m;
    return 0.5 * b + thick + u - u * u / (2.0 * b);
  }
  return b + thick;
}

}  // namespace

double fogPathLength(const Fog& fog, glm::dvec3 origin, glm::dvec3 direction, double distance) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!(distance > 0.0)) return 0.0;
  // Level, or so nearly that the column's difference would lose its digits: the density at
  // the middle of the path times its length.
  const double rise = distance * direction.z;
  if (direction.z == 0.0 || (std::isfinite(rise) && std::abs(rise) < 1e-3)) {
    const double rho = fogDensity(fog, direction.z == 0.0 ? origin.z : origin.z + 0.5 * rise);
    return rho > 0.0 ? (distance == kInf ? kInf : rho * distance) : 0.0;
  }
  const double end = std::isfinite(rise) ? origin.z + rise : (rise > 0.0 ? kInf : -kInf);
  return std::abs(fogColumn(fog, end) - fogColumn(fog, origin.z)) / std::abs(direction.z);
}

double hazeOpticalDepth(const Haze& haze, glm::dvec3 origin, glm::dvec3 direction,
                        double distance) {
  // A flat Earth sees an endless level path; 1e9 m keeps tau finite, and the horizon seen from
  // sea level the haze's colour (tau > 390 there for every legal visibility).
  const double s = std::min(distance, 1.0e9);
  if (!(s > 0.0)) return 0.0;
  const double h = haze.scale_height_m, sigma0 = extinctionForVisibility(haze.visibility_m);
  // tau = sigma0 integral_0^s exp(-(z0 + u dz) / H) du = sigma0 H (e^-a - e^-(a + x)) / dz with
  // a = z0 / H and x = s dz / H; near x = 0, where the difference cancels, the series
  // sigma0 s e^-a (1 - x/2 + x^2/6). The end height is held above -50 H: only a ray past the
  // ground goes lower, and its tau is then e^50 times any real one.
  const double a = origin.z / h, x = s * direction.z / h;
  if (std::abs(x) < 1e-2) return sigma0 * s * std::exp(-a) * (1.0 - x / 2.0 + x * x / 6.0);
  return sigma0 * h / direction.z * (std::exp(-a) - std::exp(-std::max(a + x, -50.0)));
}

double shaftOpticalDepth(const RainShaft& shaft, glm::dvec3 origin, glm::dvec3 direction,
                         double distance) {
  if (!(shaft.sigma > 0.0) || !(distance > 0.0) || !(shaft.top_m > 0.0)) return 0.0;
  // The chord [t0, t1] inside the cylinder |o + t d| < R (horizontal parts) and 0 <= Z <= top.
  const glm::dvec2 o = glm::dvec2(origin) - shaft.centre, d(direction);
  const double r2 = shaft.radius_m * shaft.radius_m;
  const double a = glm::dot(d, d), b = glm::dot(o, d);
  double t0 = 0.0, t1 = distance;
  if (a < 1e-12) {
    if (glm::dot(o, o) >= r2) return 0.0;
  } else {
    // b^2 - a (|o|^2 - R^2) = a R^2 - (o x d)^2, the form that keeps far shafts' digits.
    const double cross = o.x * d.y - o.y * d.x, quarter_delta = a * r2 - cross * cross;
    if (quarter_delta <= 0.0) return 0.0;
    const double root = std::sqrt(quarter_delta);
    t0 = std::max(t0, (-b - root) / a);
    t1 = std::min(t1, (-b + root) / a);
  }
  if (direction.z == 0.0) {
    if (origin.z < 0.0 || origin.z > shaft.top_m) return 0.0;
  } else {
    const double at_ground = -origin.z / direction.z;
    const double at_top = (shaft.top_m - origin.z) / direction.z;
    t0 = std::max(t0, std::min(at_ground, at_top));
    t1 = std::min(t1, std::max(at_ground, at_top));
  }
  if (!(t1 > t0)) return 0.0;
  // About the chord's middle m, t = m + u with |u| <= h: the radial factor is
  // G0 + G1 u + G2 u^2 and the height factor L0 + L1 u, so the odd terms of their product
  // vanish over [-h, h]: the integral is 2 h G0 L0 + (2 h^3 / 3)(G2 L0 + G1 L1).
  const double m = 0.5 * (t0 + t1), h = 0.5 * (t1 - t0);
  const glm::dvec2 q = o + m * d;
  const double g0 = 1.0 - glm::dot(q, q) / r2, g1 = -2.0 * glm::dot(q, d) / r2, g2 = -a / r2;
  const double fade = (1.0 - kShaftGroundShare) / shaft.top_m;
  const double l0 = kShaftGroundShare + fade * (origin.z + m * direction.z);
  const double l1 = fade * direction.z;
  const double column = 2.0 * h * g0 * l0 + (2.0 * h * h * h / 3.0) * (g2 * l0 + g1 * l1);
  return shaft.sigma * std::max(column, 0.0);
}

double precipitationTransmittance(std::span<const Fog> slabs, std::span<const RainShaft> shafts,
                                  glm::dvec3 origin, glm::dvec3 direction, double distance) {
  double tau = 0.0;
  for (const Fog& f : slabs)
    tau += fogExtinction(f) * fogPathLength(f, origin, direction, distance);
  for (const RainShaft& s : shafts) tau += shaftOpticalDepth(s, origin, direction, distance);
  return std::isfinite(tau) ? std::exp(-tau) : 0.0;
}

glm::dvec3 throughAir(glm::dvec3 colour, const std::optional<Fog>& fog,
                      const std::optional<Fog>& veil, const std::optional<Haze>& haze,
                      glm::dvec3 horizon, glm::dvec3 origin, glm::dvec3 direction, double distance,
                      std::span<const Fog> precipitation, std::span<const RainShaft> shafts) {
  // Each depth is capped where its transmittance is already 0 in double, so the weights of the
  // colours stay finite.
  constexpr double kOpaque = 1.0e3;
  auto depth = [&](const std::optional<Fog>& f) {
    return f ? std::min(fogExtinction(*f) * fogPathLength(*f, origin, direction, distance), kOpaque)
             : 0.0;
  };
  const double tau_fog = depth(fog), tau_veil = depth(veil);
  const double tau_haze =
      haze ? std::min(hazeOpticalDepth(*haze, origin, direction, distance), kOpaque) : 0.0;
  double tau = tau_fog + tau_veil + tau_haze;
  glm::dvec3 weighted = tau_fog * (fog ? fog->colour : glm::dvec3(0.0)) +
                        tau_veil * (veil ? veil->colour : glm::dvec3(0.0)) + tau_haze * horizon;
  for (const Fog& p : precipitation) {
    const double tau_p = depth(p);
    tau += tau_p;
    weighted += tau_p * p.colour;
  }
  for (const RainShaft& s : shafts) {
    const double tau_s = std::min(shaftOpticalDepth(s, origin, direction, distance), kOpaque);
    tau += tau_s;
    weighted += tau_s * s.colour;
  }
  if (!(tau > 0.0)) return colour;
  const glm::dvec3 air = weighted / tau;
  const double t = std::exp(-tau);
  return t * colour + (1.0 - t) * air;
}

}  // namespace nephele
