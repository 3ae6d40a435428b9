#include "world/formations/heap_shape.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "world/counter_random.h"
#include "world/formations/cluster.h"

namespace nephele {

// Heaps take the wind shear (MODEL.md section 10): they lean downwind by kLean times the
// shear's share metres per metre of height, and a cumulonimbus's anvil is carried downwind;
// the share is |shear| / kFullShear, at most 1.
constexpr double kLean = 0.15;
constexpr double kFullShear = 15.0;  // m/s between the heaps' top and the wind carrying them
Shear shearOf(const CloudField& f) {
  const double speed = glm::length(f.shear);
  if (!(speed > 1e-3)) return {{1.0, 0.0}, 0.0};
  return {f.shear / speed, std::min(speed / kFullShear, 1.0)};
}

namespace {

// How far downwind the shear moves a heap's part `height` metres above its base.
glm::dvec3 leanAt(const Shear& shear, double height) {
  return glm::dvec3(shear.direction * (kLean * shear.amount * height), 0.0);
}
// The heading (clockwise from north, of the body or boundary x axis) that points x along `d`.
double headingAlong(glm::dvec2 d) {
  return glm::degrees(std::atan2(-d.y, d.x));
}

// Far away a heap's lobes merge into one mound: an ellipsoid filling the box that holds them
// (four fifths of its half-extents, so that it covers about what they cover).
Ellipsoid mound(const std::vector<Ellipsoid>& lobes) {
  glm::dvec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const Ellipsoid& e : lobes) {
    const double reach = std::max({e.radii.x, e.radii.y});
    lo = glm::min(lo, e.centre - glm::dvec3(reach, reach, e.radii.z));
    hi = glm::max(hi, e.centre + glm::dvec3(reach, reach, e.radii.z));
  }
  Ellipsoid out;
  out.centre = 0.5 * (lo + hi);
  out.radii = 0.4 * (hi - lo);
  return out;
}

// The parts of one cumulonimbus (cumulonimbusEllipsoids below), each drawn from its own
// counters of the heap's seed.
class Cumulonimbus {
 public:
  Cumulonimbus(const CloudField& f, glm::dvec3 base, double r, double h, double squash,
               std::uint64_t seed)
      : shear_(shearOf(f)), base_(base), r_(r), h_(h), squash_(squash), seed_(seed) {}

  Ellipsoid bottom() const;
  void addFloor(std::vector<Ellipsoid>& out) const;
  std::vector<Ellipsoid> tower() const;
  void addRings(std::vector<Ellipsoid>& tower, std::vector<Ellipsoid>& rings,
                std::vector<Ellipsoid>& shoulder) const;
  void addAnvil(std::vector<Ellipsoid>& out) const;

 private:
  double u(std::uint64_t a, std::uint64_t b = 0) const {
    return unitFromBits(hashCounters(seed_, 0x4362ull, a, b));
  }
  // The updraft's axis, leaning downwind with height.
  glm::dvec3 axis(double z) const { return base_ + glm::dvec3(0.0, 0.0, z) + leanAt(shear_, z); }

  const Shear shear_;
  const glm::dvec3 base_;
  const double r_, h_, squash_;
  const std::uint64_t seed_;
};

// Flat, its bottom on the cloud base.
Ellipsoid Cumulonimbus::bottom() const {
  Ellipsoid bottom;
  bottom.radii = {0.4 * r_, 0.4 * r_ * squash_, 0.1 * h_};
  bottom.centre = base_ + glm::dvec3(0.0, 0.0, bottom.radii.z);
  bottom.orientation.heading_deg = 360.0 * u(1);
  return bottom;
}

// The flat base at the condensation level: pancake lobes over the tower's foot, their middles
// a little above the base, so that the opaque core of each (its limb is translucent, Gardner
// eq. 11) ends level just above it, seen from the side and from below alike. The bottom
// ellipsoid, seen from the side, ends in a translucent rounded limb 1 to 2 km up.
void Cumulonimbus::addFloor(std::vector<Ellipsoid>& out) const {
  ClusterSpec floor;
  floor.element.radii = {0.2 * r_, 0.2 * r_, 0.07 * h_};
  floor.centre = glm::dvec2(base_);
  floor.boundary_radii = {0.3 * r_, 0.3 * r_ * squash_};
  floor.spacing = glm::dvec2(0.18 * r_);
  floor.altitude_m = base_.z;
  floor.size_variation = 0.15;
  floor.position_variation = 0.2;
  floor.heading_variation_deg = 90.0;
  floor.seed = hashCounters(seed_, kShape, 4);
  for (Ellipsoid e : clusterEllipsoids(floor)) {
    e.centre.z = base_.z + 0.5 * e.radii.z;
    out.push_back(e);
  }
}

// The tower: a column of lobes each about 0.5 h tall, 0.13 h apart from the base up, so that
// no gap opens from the base to the anvil and no seam shows between them, with bulges half
// sunk into its faces that grow upward.
std::vector<Ellipsoid> Cumulonimbus::tower() const {
  std::vector<Ellipsoid> tower;
  constexpr int kLevels = 5;
  for (int i = 0; i < kLevels; ++i) {
    const double z = (0.26 + 0.13 * i) * h_, rise = double(i) / (kLevels - 1);
    Ellipsoid core;
    core.radii = glm::dvec3(0.42 * r_, 0.42 * r_ * squash_, 0.26 * h_) * (0.95 + 0.1 * u(2, i));
    core.centre = axis(z);
    core.orientation.heading_deg = 360.0 * u(3, i);
    tower.push_back(core);
    const double turn = 2.0 * std::numbers::pi * u(4, i);
    for (int q = 0; q < 3; ++q) {
      const std::uint64_t k = 8 * std::uint64_t(i) + std::uint64_t(q);
      const double azimuth = turn + 2.0 * std::numbers::pi * (q + 0.5 * u(5, k)) / 3.0;
      const double size = (0.22 + 0.08 * rise) * r_ * (0.85 + 0.3 * u(6, k));
      Ellipsoid bulge;
      bulge.radii = {size, size, 0.15 * h_ * (0.85 + 0.3 * u(7, k))};
      bulge.centre =
          axis(z + 0.08 * h_ * (2.0 * u(8, k) - 1.0)) +
          (0.26 + 0.06 * u(9, k)) * r_ * glm::dvec3(std::cos(azimuth), std::sin(azimuth), 0.0);
      bulge.orientation.heading_deg = 360.0 * u(10, k);
      tower.push_back(bulge);
    }
  }
  return tower;
}

// The incus: above 0.6 of its height the tower spreads out into the anvil, rings of lobes
// reaching further out (mostly downwind) at each level, their outer ends tilted up, so that
// the column widens into the anvil as one mass (an inverted cone under it) instead of a stem
// under a plate. The top ring (`shoulder`) joins the anvil and is kept at every distance, as
// the anvil is: from above it widens the anvil's edge, and merged into the far mound the heaps
// drew less cover than their measured footprint (0.444 against 0.463 over eight seeds). The
// upper rings are lit with the anvil they spread into (its part, MODEL.md section 14): in the
// tower's, they widened its envelope to the anvil's width, and the sunlit tower's face took
// its light through kilometres of it (0.149 of the sun's luminance, 0.41 without). The lowest,
// within the tower's width, stays with the tower: in the anvil's, its lobes showed as dark
// crescents between the sunlit tower's.
void Cumulonimbus::addRings(std::vector<Ellipsoid>& tower, std::vector<Ellipsoid>& rings,
                            std::vector<Ellipsoid>& shoulder) const {
  constexpr int kRings = 3, kAround = 7;
  const double turn = 2.0 * std::numbers::pi * u(11);
  for (int ring = 0; ring < kRings; ++ring) {
    const double step = double(ring) / (kRings - 1);
    const double reach = (0.30 + 0.40 * step) * r_, size = (0.30 + 0.08 * step) * r_;
    for (int q = 0; q < kAround; ++q) {
      const std::uint64_t k = 8 * std::uint64_t(ring) + std::uint64_t(q);
      const double azimuth =
          turn + 2.0 * std::numbers::pi * (q + 0.5 * ring + 0.5 * u(12, k)) / kAround;
      const glm::dvec2 out_dir(std::cos(azimuth), std::sin(azimuth));
      // Further out downwind, where the upper wind carries the spreading top.
      const double stretch =
          1.0 + 0.6 * shear_.amount * std::max(glm::dot(out_dir, shear_.direction), 0.0);
      const double z = (0.63 + 0.08 * ring + 0.04 * (u(16, k) - 0.5)) * h_;
      Ellipsoid lobe;
      lobe.radii = {size, size, 0.11 * h_ * (0.85 + 0.3 * u(13, k))};
      lobe.centre =
          axis(z) + glm::dvec3(out_dir * (reach * stretch * (0.85 + 0.3 * u(14, k))), 0.0);
      // Body y (forward) along out_dir, pitched up by 10 to 25 degrees.
      lobe.orientation.heading_deg = headingAlong({out_dir.y, -out_dir.x});
      lobe.orientation.pitch_deg = 10.0 + 15.0 * u(15, k);
      (ring == 0 ? tower : ring + 1 < kRings ? rings : shoulder).push_back(lobe);
    }
  }
}

// The anvil: flat-topped at the tropopause (0.97 h), thickest where the tower feeds it (0.2 h)
// and thinning downwind to 0.07 h in full shear (upwind, where it overhangs less, to 0.12 h),
// longer along the shear and carried downwind; lobes hang from its flat top to a lumpy
// underside, over a thin sheet that fills between them. The overshooting dome, over the
// updraft, is sunk into it and lit with it.
void Cumulonimbus::addAnvil(std::vector<Ellipsoid>& out) const {
  const double along = (1.5 + 0.5 * shear_.amount) * r_, across = 1.2 * r_;
  const glm::dvec3 crown = axis(0.97 * h_);  // the updraft's axis at the anvil's top
  const double top = crown.z;
  const glm::dvec2 middle =
      glm::dvec2(axis(0.88 * h_)) + shear_.direction * (0.9 * shear_.amount * r_);
  auto thickness = [&](glm::dvec2 at) {
    const glm::dvec2 from_axis = at - glm::dvec2(crown);
    const double t = std::min(glm::length(from_axis) / along, 1.0);
    const bool downwind = glm::dot(from_axis, shear_.direction) > 0.0;
    return h_ * (0.2 - (downwind ? 0.13 * shear_.amount + 0.05 * (1.0 - shear_.amount) : 0.08) * t);
  };
  const double heading = headingAlong(shear_.direction);
  Ellipsoid dome;
  dome.radii = {0.3 * r_, 0.3 * r_, 0.1 * h_};  // sunk into the anvil, its top at 1.05 h
  dome.centre = axis(0.95 * h_);
  out.push_back(dome);
  Ellipsoid sheet;
  sheet.radii = {along, across, 0.05 * h_};
  sheet.centre = glm::dvec3(middle, top - sheet.radii.z);
  sheet.orientation.heading_deg = heading;
  out.push_back(sheet);
  ClusterSpec cap;
  const double cap_depth = 0.1 * h_;  // before each lobe takes the anvil's thickness below
  cap.element.radii = {0.4 * r_, 0.4 * r_, cap_depth};
  cap.centre = middle;
  cap.boundary_radii = {along - 0.35 * r_, across - 0.35 * r_};
  cap.boundary_heading_deg = heading;
  cap.spacing = glm::dvec2(0.45 * r_);  // the anvil sets the outline: kept at every distance
  cap.altitude_m = top;
  cap.size_variation = 0.2;
  cap.position_variation = 0.3;
  cap.heading_variation_deg = 90.0;
  cap.seed = hashCounters(seed_, kShape, 3);
  for (Ellipsoid e : clusterEllipsoids(cap)) {
    // Hanging from the flat top, as thick as the anvil is there, drooping a little downwind.
    const double t = glm::dot(glm::dvec2(e.centre) - middle, shear_.direction) / along;
    e.radii.z = 0.5 * thickness(glm::dvec2(e.centre)) * (e.radii.z / cap_depth);
    e.centre.z = top - e.radii.z - 0.03 * h_ * std::max(t, 0.0) * t * shear_.amount;
    out.push_back(e);
  }
}

// A cumulonimbus of tower radius about half r and height h on `base` (WMO International Cloud
// Atlas, Cb incus): one continuous tower from a flat base to the tropopause, where it spreads
// into an anvil several times its width, carried downwind by the shear, with an overshooting
// dome over the updraft (MODEL.md section 10). The base is dark through the light model
// (section 14). Far away the tower and its lower rings merge into one mound.
std::vector<Ellipsoid> cumulonimbusEllipsoids(const CloudField& f, glm::dvec3 base, double r,
                                              double h, double squash, std::uint64_t seed,
                                              bool detailed, std::size_t& anvil_from) {
  const Cumulonimbus cb(f, base, r, h, squash, seed);
  std::vector<Ellipsoid> out{cb.bottom()};
  if (detailed) cb.addFloor(out);
  std::vector<Ellipsoid> tower = cb.tower(), rings, shoulder;
  cb.addRings(tower, rings, shoulder);
  if (!detailed) {
    tower.insert(tower.end(), rings.begin(), rings.end());
    tower = {mound(tower)};
    rings.clear();
  }
  out.insert(out.end(), tower.begin(), tower.end());
  anvil_from = out.size();
  out.insert(out.end(), rings.begin(), rings.end());
  out.insert(out.end(), shoulder.begin(), shoulder.end());
  cb.addAnvil(out);
  return out;
}

}  // namespace

std::vector<Ellipsoid> heapEllipsoids(const CloudField& f, glm::dvec3 base, double r, double h,
                                      std::uint64_t seed, bool detailed, std::size_t& anvil_from) {
  const double squash = 0.8 + 0.2 * unitFromBits(hashCounters(seed, kShape));
  if (f.type == CloudType::kCumulonimbus)
    return cumulonimbusEllipsoids(f, base, r, h, squash, seed, detailed, anvil_from);
  std::vector<Ellipsoid> out;
  // A heap taller than about its width (congestus) is a tower of tiers, each a mound as a
  // mediocris heap is, narrowing upwards (MODEL.md section 10).
  const int tiers = std::clamp(int(std::lround(h / (1.1 * r))), 1, 4);
  const double tier_h = h / tiers;
  // The flat base: wide, a third of the (lowest tier's) height, its bottom on the cloud base.
  // It sets the footprint whether the lobes or their mound are drawn (a narrower base under a
  // tower lets the far mound cover less than the lobes: 0.22 drawn for 0.3 asked).
  Ellipsoid bottom;
  bottom.radii = {r, r * squash, 0.3 * tier_h};
  bottom.centre = base + glm::dvec3(0.0, 0.0, bottom.radii.z);
  bottom.orientation.heading_deg = 360.0 * unitFromBits(hashCounters(seed, kShape, 1));
  out.push_back(bottom);
  // Gardner's towers: per tier, lobes on a jittered lattice raised by a dummy dome under the
  // middle, leaning downwind with the shear.
  const Shear shear = shearOf(f);
  std::vector<Ellipsoid> tower;
  for (int k = 0; k < tiers; ++k) {
    const double floor = base.z + k * tier_h;
    const double w = r * (tiers > 1 ? 1.0 - 0.25 * k / (tiers - 1) : 1.0);
    Ellipsoid dome;
    dome.radii = {0.45 * w, 0.45 * w, 0.55 * tier_h};
    dome.centre = glm::dvec3(glm::dvec2(base), 0.0);  // terrainHeight counts from z = 0
    ClusterSpec lobes;
    lobes.element.radii = {0.38 * w, 0.38 * w, 0.3 * tier_h};
    lobes.centre = glm::dvec2(base);
    lobes.boundary_radii = glm::dvec2(0.42 * w);
    lobes.spacing = glm::dvec2(0.3 * w);
    lobes.altitude_m = floor + 0.18 * tier_h;
    lobes.size_variation = 0.25;
    lobes.position_variation = 0.4;
    lobes.heading_variation_deg = 90.0;
    lobes.seed = hashCounters(seed, kShape, 2 + std::uint64_t(k));
    for (Ellipsoid e : clusterEllipsoids(lobes, {dome})) {
      // Nothing hangs below the condensation level or its tier: a lobe the dome does not
      // raise rests on the flat base or the tier under it.
      e.centre.z = std::max(e.centre.z, floor + e.radii.z);
      e.centre += leanAt(shear, e.centre.z - base.z);
      tower.push_back(e);
    }
  }
  if (!detailed && !tower.empty()) tower = {mound(tower)};
  out.insert(out.end(), tower.begin(), tower.end());
  anvil_from = out.size();
  return out;
}

}  // namespace nephele
