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

double fogExtinction(const Fog& fog) {
  return -std::log(0.02) / fog.visibility_m;
}

double fogPathLength(const Fog& fog, glm::dvec3 origin, glm::dvec3 direction, double distance) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double enter = 0.0, leave = distance;
  if (direction.z == 0.0) {
    if (origin.z < 0.0 || origin.z > fog.top_m) return 0.0;
  } else {
    double s0 = (0.0 - origin.z) / direction.z, s1 = (fog.top_m - origin.z) / direction.z;
    if (s0 > s1) std::swap(s0, s1);
    enter = std::max(enter, s0);
    leave = std::min(leave, s1);
  }
  if (!(leave > enter)) return 0.0;
  return leave == kInf ? kInf : leave - enter;
}

}  // namespace nephele
