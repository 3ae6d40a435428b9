#pragma once
// Gardner's cluster generator (MODEL.md section 5, "Clusters"): a template ellipsoid repeated
// on a jittered lattice of typical X and Y spacing inside a horizontal elliptical boundary,
// at a layer altitude, with seeded variation of size, position and heading, and optionally
// raised by "terrain" (earlier ellipsoids under it) the way Gardner builds towers and
// anvils. Counter-based randomness: ellipsoid (i, j) depends only on (seed, i, j), so the
// list is the same on every machine and thread count.
#include <cstdint>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "world/formations/ellipsoid.h"

namespace nephele {

struct ClusterSpec {
  Ellipsoid element;                          // size and orientation; its centre is unused
  glm::dvec2 centre{0.0, 0.0};                // of the boundary, m
  glm::dvec2 boundary_radii{2000.0, 1500.0};  // semi-axes of the horizontal boundary, m
  double boundary_heading_deg = 0.0;          // of the boundary's first axis, clockwise from north
  glm::dvec2 spacing{600.0, 600.0};           // typical X and Y spacing of the lattice, m
  double altitude_m = 1500.0;                 // of the elements' centres before terrain
  double size_variation = 0.2;                // each radius times 1 + v (2u - 1)
  double position_variation = 0.3;            // offsets up to this fraction of the spacing
  double heading_variation_deg = 20.0;        // heading offsets up to this
  double vertical_scale = 1.0;                // vertical development: rz times this
  std::uint64_t seed = 1;
};

// Empty when usable, else what is wrong and what is allowed.
std::string clusterError(const ClusterSpec& spec);

// Height of `terrain` above the vertical through `xy`: the highest top surface of the
// ellipsoids that line meets, or 0 where it meets none ([G]: an object placed over earlier
// objects is raised by their height at its X, Y).
double terrainHeight(const std::vector<Ellipsoid>& terrain, glm::dvec2 xy);

// The cluster's ellipsoids, each raised by terrainHeight(terrain, its X, Y). Lattice order
// (row by row from the boundary's south-west), so equal specs give equal lists.
std::vector<Ellipsoid> clusterEllipsoids(const ClusterSpec& spec,
                                         const std::vector<Ellipsoid>& terrain = {});

}  // namespace nephele
