#include "world/formations/region.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "world/counter_random.h"
#include "world/formulas/far_deck.h"
#include "world/formulas/region.h"
#include "world/formulas/table.h"
#include "world/limits.h"

namespace nephele {

glm::dvec2 regionLocal(const Region& r, glm::dvec2 xy) {
  const double h = r.heading_deg * std::numbers::pi / 180.0;
  // y along the heading (clockwise from north), x a quarter turn further clockwise.
  return formulas::regionAxes(xy - r.centre, std::cos(h), std::sin(h));
}

double regionWeight(const Region& r, glm::dvec2 xy) {
  if (r.everywhere()) return 1.0;
  return formulas::regionWeightAt(regionLocal(r, xy), r.half_size, r.edge_m, double(r.side),
                                  r.transition_m);
}

bool regionExcludesDisc(const Region& r, glm::dvec2 xy, double radius) {
  if (r.everywhere()) return false;
  const glm::dvec2 p = regionLocal(r, xy);
  if (std::abs(p.x) - radius >= r.half_size.x || std::abs(p.y) - radius >= r.half_size.y)
    return true;
  return r.side != 0 && r.side * p.x + radius <= -0.5 * r.transition_m;
}

std::string regionError(const Region& r) {
  std::ostringstream out;
  auto outside = [&](const char* name, double value, Range range) {
    return outOfRange(out, name, value, range);
  };
  const double c = Limits::kMaxCoordinate;
  const auto size = [&](const char* name, double half) {
    return half != Region::kUnbounded && outside(name, 2.0 * half, Limits::kRegionSize);
  };
  if (outside("centre x", r.centre.x, {-c, c}) || outside("centre y", r.centre.y, {-c, c}) ||
      size("size x", r.half_size.x) || size("size y", r.half_size.y) ||
      outside("heading", r.heading_deg, {-Limits::kMaxHeading, Limits::kMaxHeading}) ||
      outside("edge", r.edge_m, Limits::kRegionBand) ||
      outside("transition", r.transition_m, Limits::kRegionBand))
    return out.str();
  if (r.side < -1 || r.side > 1) return "side: " + std::to_string(r.side) + " (allowed: -1, 0, 1)";
  return "";
}

double farApparentCover(const FarCover& far, glm::dvec3 ray) {
  return formulas::farApparentCover(far.coverage, far.side_ratio, ray);
}

double farThreshold(const FarCover& far, glm::dvec3 ray) {
  const glm::dvec2 cell = formulas::tableCell(farApparentCover(far, ray), FarCover::kSteps);
  const int k = int(cell.x);
  return glm::mix(far.threshold[k], far.threshold[k + 1], cell.y);
}

double clusterFactor(const ClusterVariation& v, std::uint64_t seed, std::uint64_t purpose,
                     glm::dvec2 xy) {
  if (v.none()) return 1.0;
  const glm::dvec2 g = xy / v.spacing_m;
  const glm::dvec2 cell = glm::floor(g), f = g - cell;
  auto u = [&](double i, double j) {
    const auto bits = hashCounters(hashCounters(seed, purpose), std::uint64_t(std::int64_t(i)),
                                   std::uint64_t(std::int64_t(j)));
    return 2.0 * unitFromBits(bits) - 1.0;
  };
  const glm::dvec2 s = f * f * (3.0 - 2.0 * f);
  const double bottom = glm::mix(u(cell.x, cell.y), u(cell.x + 1.0, cell.y), s.x);
  const double top = glm::mix(u(cell.x, cell.y + 1.0), u(cell.x + 1.0, cell.y + 1.0), s.x);
  return 1.0 + v.amount * glm::mix(bottom, top, s.y);
}

std::string clusterVariationError(const ClusterVariation& v) {
  std::ostringstream out;
  if (!(v.spacing_m == 0.0) && outOfRange(out, "spacing", v.spacing_m, Limits::kClusterSpacing))
    return out.str();
  if (outOfRange(out, "variation", v.amount, Limits::kClusterVariation)) return out.str();
  return "";
}

}  // namespace nephele
