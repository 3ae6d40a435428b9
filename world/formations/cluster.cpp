#include "world/formations/cluster.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "world/counter_random.h"
#include "world/limits.h"

namespace nephele {
namespace {

// The lattice's half extent in cells along one boundary axis.
long long halfCells(double radius, double spacing) {
  return static_cast<long long>(std::floor(radius / spacing));
}

}  // namespace

std::string clusterError(const ClusterSpec& s) {
  std::ostringstream out;
  auto outside = [&](const char* name, double value, Range range) {
    return outOfRange(out, name, value, range);
  };
  if (std::string e = ellipsoidError(s.element); !e.empty()) return "element: " + e;
  if (outside("spacing x", s.spacing.x, Limits::kClusterSpacing) ||
      outside("spacing y", s.spacing.y, Limits::kClusterSpacing) ||
      outside("boundary x", s.boundary_radii.x, Limits::kClusterBoundary) ||
      outside("boundary y", s.boundary_radii.y, Limits::kClusterBoundary) ||
      outside("size_variation", s.size_variation, Limits::kSizeVariation) ||
      outside("position_variation", s.position_variation, Limits::kPositionVariation) ||
      outside("heading_variation", s.heading_variation_deg, Limits::kHeadingVariation) ||
      outside("vertical_scale", s.vertical_scale, Limits::kVerticalScale) ||
      outside("altitude", s.altitude_m, {0.0, Limits::kMaxAltitude}) ||
      outside("centre x", s.centre.x, {-Limits::kMaxCoordinate, Limits::kMaxCoordinate}) ||
      outside("centre y", s.centre.y, {-Limits::kMaxCoordinate, Limits::kMaxCoordinate}) ||
      outside("boundary heading", s.boundary_heading_deg,
              {-Limits::kMaxHeading, Limits::kMaxHeading}))
    return out.str();
  const double cells = double(2 * halfCells(s.boundary_radii.x, s.spacing.x) + 1) *
                       double(2 * halfCells(s.boundary_radii.y, s.spacing.y) + 1);
  if (cells > Limits::kMaxEllipsoidsPerCloud) {
    out << "boundary / spacing: " << cells << " lattice cells (allowed: at most "
        << Limits::kMaxEllipsoidsPerCloud << "; widen the spacing or shrink the boundary)";
    return out.str();
  }
  return "";
}

double terrainHeight(const std::vector<Ellipsoid>& terrain, glm::dvec2 xy) {
  double height = 0.0;
  for (const Ellipsoid& e : terrain) {
    // Look straight down from above the ellipsoid's bounding sphere.
    const double above = e.centre.z + std::max({e.radii.x, e.radii.y, e.radii.z}) + 1.0;
    const EllipsoidView view(e, glm::dvec3(xy, above));
    if (const auto span = view.intersect({0.0, 0.0, -1.0}))
      height = std::max(height, above - span->near);
  }
  return height;
}

std::vector<Ellipsoid> clusterEllipsoids(const ClusterSpec& s,
                                         const std::vector<Ellipsoid>& terrain) {
  std::vector<Ellipsoid> out;
  if (!clusterError(s).empty()) return out;
  // The boundary's frame: its x axis points east and y north when its heading is 0, both
  // turned clockwise by the heading.
  const double h = glm::radians(s.boundary_heading_deg);
  const glm::dvec2 axis_x(std::cos(h), -std::sin(h)), axis_y(std::sin(h), std::cos(h));
  const long long ni = halfCells(s.boundary_radii.x, s.spacing.x);
  const long long nj = halfCells(s.boundary_radii.y, s.spacing.y);
  for (long long j = -nj; j <= nj; ++j)
    for (long long i = -ni; i <= ni; ++i) {
      auto uniform = [&](std::uint64_t which) {  // in [-1, 1), a pure function of (seed, i, j)
        return 2.0 * unitFromBits(hashCounters(s.seed, std::uint64_t(i), std::uint64_t(j), which)) -
               1.0;
      };
      const glm::dvec2 local((double(i) + s.position_variation * uniform(0)) * s.spacing.x,
                             (double(j) + s.position_variation * uniform(1)) * s.spacing.y);
      const glm::dvec2 q = local / s.boundary_radii;
      if (glm::dot(q, q) > 1.0) continue;
      const glm::dvec2 xy = s.centre + local.x * axis_x + local.y * axis_y;
      Ellipsoid e = s.element;
      e.radii *= 1.0 + s.size_variation * uniform(2);
      e.radii.z *= s.vertical_scale;
      e.orientation.heading_deg += s.heading_variation_deg * uniform(3);
      e.centre = glm::dvec3(xy, s.altitude_m + terrainHeight(terrain, xy));
      out.push_back(e);
    }
  return out;
}

}  // namespace nephele
