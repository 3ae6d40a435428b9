#pragma once
// Sky background, ground, sun (MODEL.md sections 1 and 5), ground fog and distance haze.
#include <glm/glm.hpp>

#include <optional>
#include <span>

#include "world/formulas/air.h"

namespace nephele {

struct Sky {
  glm::dvec3 zenith{0.16, 0.32, 0.75};  // linear RGB
  glm::dvec3 horizon{0.62, 0.74, 0.90};
  glm::dvec3 ground{0.20, 0.22, 0.18};
};

// The "gradient" model: horizon + (zenith - horizon) sqrt(d.z) above the horizon, the
// ground colour below. `direction` need not be normalised.
glm::dvec3 skyBackground(const Sky& sky, glm::dvec3 direction);

struct Sun {
  double azimuth_deg = 135.0;   // clockwise from north, like a heading
  double elevation_deg = 40.0;  // above the horizon
  glm::dvec3 colour{1.0, 0.98, 0.94};
};

glm::dvec3 sunDirection(const Sun& sun);  // unit vector towards the sun

// A medium filling the slab bottom <= Z <= top (McReynolds and Blythe's ground fog, with
// bottom 0), its density falling linearly to none over `band` below the bottom and above the
// top (the in-layer veil, MODEL.md section 5). Extinction follows the meteorological
// visibility: 2 % contrast left after `visibility_m`, sigma = -ln(0.02) / visibility, where the
// density is 1. Fog is unlit: it adds its own colour.
struct Fog {
  double top_m = 100.0;
  double visibility_m = 1000.0;
  glm::dvec3 colour{0.75, 0.77, 0.80};
  double bottom_m = 0.0;
  double band_m = 0.0;
  bool operator==(const Fog&) const = default;
};

// Koschmieder: the extinction per metre that leaves 2 % contrast after `visibility_m`, and the
// visibility of an extinction (infinite for 0).
double extinctionForVisibility(double visibility_m);
double visibilityForExtinction(double sigma);
double fogExtinction(const Fog& fog);  // per metre

// The fog's density at height z: 1 in [bottom, top], falling linearly to 0 over the band.
double fogDensity(const Fog& fog, double z);

// The density-weighted length of the ray origin + s * direction, 0 <= s <= distance, through
// the fog (its length inside the slab when band is 0); distance may be +infinity, giving
// +infinity for a level ray where the density is above 0. `direction` must be normalised.
double fogPathLength(const Fog& fog, glm::dvec3 origin, glm::dvec3 direction, double distance);

// Distance haze (MODEL.md section 5): aerosol whose extinction falls with height as
// exp(-Z / scale_height), sigma0 = -ln(0.02) / visibility at Z = 0, seen in the sky's horizon
// colour. Unlit, like the fog.
struct Haze {
  double visibility_m = 40000.0;
  double scale_height_m = 1200.0;
  bool operator==(const Haze&) const = default;
};

// The haze's optical depth along origin + s * direction for 0 <= s <= distance (distance may
// be +infinity; `direction` must be normalised). Finite or +infinity, never NaN.
double hazeOpticalDepth(const Haze& haze, glm::dvec3 origin, glm::dvec3 direction, double distance);

// A shaft of precipitation under a heap (MODEL.md section 17): a vertical cylinder of radius R
// about the axis through `centre`, from the ground up to `top_m` (the heap's base), of extinction
// sigma times its density (1 - rho^2 / R^2) (kShaftGroundShare + (1 - kShaftGroundShare) Z / top)
// at distance rho from the axis and height Z: densest in its core under the cloud, soft at its
// edge and thinning towards the ground, where part of it has evaporated. Unlit, like the fog.
struct RainShaft {
  glm::dvec2 centre{0.0};  // world X, Y of its axis
  double radius_m = 1000.0;
  double top_m = 1000.0;
  double sigma = 0.0;  // per metre, at density 1
  glm::dvec3 colour{0.45, 0.48, 0.52};
  bool operator==(const RainShaft&) const = default;
};
inline constexpr double kShaftGroundShare = formulas::kShaftGroundShare;

// The shaft's optical depth along origin + s * direction, 0 <= s <= distance (+infinity allowed;
// `direction` unit): exact, the density being a polynomial of degree 3 in s along the chord.
double shaftOpticalDepth(const RainShaft& shaft, glm::dvec3 origin, glm::dvec3 direction,
                         double distance);

// The transmittance exp(-tau) of precipitation slabs and shafts (precipitationMedia) along
// origin + s direction, 0 <= s <= distance (+infinity allowed; `direction` unit).
double precipitationTransmittance(std::span<const Fog> slabs, std::span<const RainShaft> shafts,
                                  glm::dvec3 origin, glm::dvec3 direction, double distance);

// `colour` seen at `distance` along the unit `direction` from `origin` through the fog, the
// in-layer veil, the haze and the precipitation of a scene (any may be absent; precipitation
// as slabs and shafts, precipitationMedia): mixed in proportion to their optical depths, T =
// exp(-tau), tau their sum, colour T + (1 - T) (sum of tau_i colour_i) / tau, the haze's colour the
// horizon's.
glm::dvec3 throughAir(glm::dvec3 colour, const std::optional<Fog>& fog,
                      const std::optional<Fog>& veil, const std::optional<Haze>& haze,
                      glm::dvec3 horizon, glm::dvec3 origin, glm::dvec3 direction, double distance,
                      std::span<const Fog> precipitation = {},
                      std::span<const RainShaft> shafts = {});

}  // namespace nephele
