#pragma once
// Where a weather layer lies (MODEL.md section 11, "Macroclusters and fronts"): a rectangle
// of any size and heading whose cover fades out over a band inside its edge, optionally cut
// by a front along its middle into one side, the two sides blending across a transition band.
// A layer with the default region covers the whole plane. Pure functions of position, so
// every renderer, every tile and every thread sees the same boundary.
#include <cstdint>
#include <limits>
#include <string>

#include <glm/glm.hpp>

#include "world/formulas/far_deck.h"
#include "world/formulas/region.h"

namespace nephele {

struct Region {
  static constexpr double kUnbounded = std::numeric_limits<double>::infinity();
  glm::dvec2 centre{0.0, 0.0};  // east, north, m
  // Half the rectangle's extent along its across-front (x) and along-front (y) axes, m.
  glm::dvec2 half_size{kUnbounded, kUnbounded};
  double heading_deg = 0.0;   // of the y axis (the front line), clockwise from north
  double edge_m = 0.0;        // cover fades from full to none over this band inside the edge
  int side = 0;               // 0 the whole rectangle; -1 left of the front line, +1 right
  double transition_m = 0.0;  // band across the front line over which the sides blend

  bool operator==(const Region&) const = default;
  bool everywhere() const { return *this == Region{}; }
};

// Bands narrower than this count as this wide (a step, without dividing by zero).
using formulas::kRegionMinBand;

// The region's coordinates of world point `xy`: x across the front line (positive to the
// right of the heading), y along it.
glm::dvec2 regionLocal(const Region& region, glm::dvec2 xy);

// How much of the layer's cover is present at `xy`, 0..1: smoothstep ramps over the edge band
// on each axis times, for one side of a front, a smoothstep across the transition band.
double regionWeight(const Region& region, glm::dvec2 xy);

// True when regionWeight is 0 everywhere within `radius` of `xy` (conservative: false when
// unsure), so that tiles and clouds there need not be built.
bool regionExcludesDisc(const Region& region, glm::dvec2 xy, double radius);

// Smoothstep of x / width clamped to [0, 1] (width at least kRegionMinBand): every band of a
// region, and a far deck's hole, ramps this way (world/formulas/region.h).
using formulas::bandRamp;

// A sky plane's T1 where the region's weight is w, raised towards 1 as w falls (MODEL.md
// section 11; world/formulas/region.h).
using formulas::regionThreshold;

// Empty when usable, else what is wrong and what is allowed (ranges in world/limits.h).
std::string regionError(const Region& region);

// The cover a far deck stands for (MODEL.md section 11): heaps covering `coverage` of the
// ground seen straight down hide more of it seen obliquely, their sides filling the gaps.
// Along a ray at elevation angle e the apparent cover is 1 - (1 - coverage)^(1 + k cot e), k
// the ratio of a heap's side silhouette to its footprint (a Boolean model whose shapes are
// seen from the side over a path cot e times as long). T1 for a cover c is interpolated in a
// table of T1 at c = 0, 1/16, ..., 1 calibrated on the deck's texture. side_ratio 0: none.
struct FarCover {
  static constexpr int kSteps = formulas::kFarCoverSteps;
  double coverage = 0.0;
  double side_ratio = 0.0;
  double threshold[kSteps + 1]{};
};
// Apparent cover along view ray `ray` (any length; |ray.z| counts as at least 1e-9 |ray|),
// the GL's formula too (world/formulas/far_deck.h).
double farApparentCover(const FarCover& far, glm::dvec3 ray);
// T1 for that cover.
double farThreshold(const FarCover& far, glm::dvec3 ray);

// Gardner's macrocluster variation (MODEL.md section 11): inside a region, clusters on a grid
// of this spacing each draw their own cover and vertical development, as factors
// 1 + amount u with u in [-1, 1]; between the grid's points the factors blend smoothly, so
// there is no seam. Spacing 0 or amount 0: every cluster alike.
struct ClusterVariation {
  double spacing_m = 0.0;
  double amount = 0.0;
  bool operator==(const ClusterVariation&) const = default;
  bool none() const { return !(spacing_m > 0.0 && amount > 0.0); }
};

// The factor 1 + amount u of draw `purpose` at `xy`: u is a counter-based draw of (seed,
// purpose, grid point) at each grid point, blended with smoothstep weights between the four
// around `xy`. 1 when the variation is none.
double clusterFactor(const ClusterVariation& variation, std::uint64_t seed, std::uint64_t purpose,
                     glm::dvec2 xy);
std::string clusterVariationError(const ClusterVariation& variation);

}  // namespace nephele
