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

namespace {

// The fog's slab as the shared formulas take it: bottom, top, band.
glm::dvec3 slabOf(const Fog& fog) {
  return {fog.bottom_m, fog.top_m, fog.band_m};
}

}  // namespace

double fogDensity(const Fog& fog, double z) {
  return formulas::slabDensity(slabOf(fog), z);
}

double fogPathLength(const Fog& fog, glm::dvec3 origin, glm::dvec3 direction, double distance) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (!(distance > 0.0)) return 0.0;
  const double rise = distance * direction.z;
  if (std::isfinite(rise)) return formulas::slabPath(slabOf(fog), origin.z, direction.z, distance);
  // An endless path: level, at the density of its start all the way, or to +-infinity.
  if (direction.z == 0.0) return fogDensity(fog, origin.z) > 0.0 ? kInf : 0.0;
  const double end = rise > 0.0 ? kInf : -kInf;
  return std::abs(formulas::slabColumn(slabOf(fog), end) -
                  formulas::slabColumn(slabOf(fog), origin.z)) /
         std::abs(direction.z);
}

double hazeOpticalDepth(const Haze& haze, glm::dvec3 origin, glm::dvec3 direction,
                        double distance) {
  if (!(distance > 0.0)) return 0.0;
  return formulas::hazeDepth(extinctionForVisibility(haze.visibility_m), haze.scale_height_m,
                             origin.z, direction.z, distance);
}

double shaftOpticalDepth(const RainShaft& shaft, glm::dvec3 origin, glm::dvec3 direction,
                         double distance) {
  if (!(shaft.sigma > 0.0) || !(distance > 0.0) || !(shaft.top_m > 0.0)) return 0.0;
  const glm::dvec2 axis = shaft.centre - glm::dvec2(origin);
  return formulas::shaftDepth(glm::dvec4(axis, shaft.radius_m, shaft.top_m), shaft.sigma, origin.z,
                              direction, distance);
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
  // Each depth capped (kOpaqueDepth), weighted by its colour and mixed as the GL's applyAir
  // does (formulas::airOver).
  constexpr double kOpaque = formulas::kOpaqueDepth;
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
  return formulas::airOver(colour, weighted, tau);
}

}  // namespace nephele
