#include "world/sky.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "world/formulas/air.h"

namespace nephele {

glm::dvec3 skyBackground(const Sky& sky, glm::dvec3 direction) {
  const glm::dvec3 d = glm::normalize(direction);
  if (d.z < 0.0) return sky.ground;
  return formulas::skyGradient(sky.horizon, sky.zenith, d.z);
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
  // The media summed and mixed by the formulas the GL's applyAir takes (world/formulas/air.h).
  // Only the inputs differ: here absent media are optionals (there, sigma 0) and an endless path
  // is +infinity, which fogPathLength's guards take (there, kFar = 1e30).
  auto fogDepth = [&](const Fog& f) {
    return fogExtinction(f) * fogPathLength(f, origin, direction, distance);
  };
  glm::dvec4 air = formulas::withMedium(glm::dvec4(0.0), fog ? fogDepth(*fog) : 0.0,
                                        fog ? fog->colour : glm::dvec3(0.0));
  air = formulas::withMedium(air, veil ? fogDepth(*veil) : 0.0,
                             veil ? veil->colour : glm::dvec3(0.0));
  air = formulas::withMedium(air, haze ? hazeOpticalDepth(*haze, origin, direction, distance) : 0.0,
                             horizon);
  for (const Fog& p : precipitation) air = formulas::withMedium(air, fogDepth(p), p.colour);
  for (const RainShaft& s : shafts)
    air = formulas::withMedium(air, shaftOpticalDepth(s, origin, direction, distance), s.colour);
  return formulas::airOver(colour, glm::dvec3(air), air.w);
}

}  // namespace nephele
