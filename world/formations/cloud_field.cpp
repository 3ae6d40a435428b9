#include "world/formations/cloud_field.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <list>
#include <map>
#include <mutex>
#include <numbers>
#include <span>
#include <sstream>
#include <tuple>

#include "world/camera.h"
#include "world/counter_random.h"
#include "world/formations/cloud_shadow.h"
#include "world/formations/cluster.h"
#include "world/formations/genus.h"
#include "world/formations/heap_light.h"
#include "world/formations/weather.h"
#include "world/limits.h"
#include "world/scene.h"
#include "world/sky.h"
#include "world/textures/solid_texture.h"

namespace nephele {
namespace {

// Purposes of the counter-based draws (hashCounters' third key).
enum Draw : std::uint64_t { kCount = 1, kX, kY, kSize, kHeight, kShape, kKeep, kCover, kRise };

bool isCb(const CloudField& f) {
  return f.type == CloudType::kCumulonimbus;
}
const HeapLook& lookOf(const CloudField& f) {
  return genus(f.type).heap_look;
}

// Where the field's thickness falls among its genus's species rows (genus.h, Species): between
// rows lo and hi = lo + 1, s of the way in log thickness; at an end, lo = hi and s = 0.
struct SpeciesSpan {
  std::size_t lo, hi;
  double s;
};
SpeciesSpan speciesSpan(const CloudField& f) {
  const std::span<const Species> rows = genus(f.type).species;
  const double t = f.thickness_m;
  if (rows.empty() || !(t > rows.front().thickness_m)) return {0, 0, 0.0};
  for (std::size_t i = 1; i < rows.size(); ++i)
    if (t <= rows[i].thickness_m)
      return {i - 1, i,
              std::log(t / rows[i - 1].thickness_m) /
                  std::log(rows[i].thickness_m / rows[i - 1].thickness_m)};
  return {rows.size() - 1, rows.size() - 1, 0.0};
}

// A heap's width over its height for the field's thickness: a power law between the rows.
double widthOverHeight(const CloudField& f) {
  const std::span<const Species> rows = genus(f.type).species;
  if (rows.empty()) return 1.8;  // fields are only made of genera with species
  const SpeciesSpan at = speciesSpan(f);
  const double a = rows[at.lo].width_over_height, b = rows[at.hi].width_over_height;
  return a * std::pow(b / a, at.s);
}

// Typical horizontal radius of a heap's base, metres.
double heapRadius(const CloudField& f) {
  return 0.5 * widthOverHeight(f) * f.thickness_m;
}
constexpr double kSizeVariation = 0.3;  // radius times 1 + v (2u - 1)

// Size and height factors of heap k among those drawn from `seed` (a tile's, or the footprint
// measurement's): size 1 +- kSizeVariation, height 0.8 to 1.2 of the layer's thickness.
struct HeapScale {
  double size, height;
};
HeapScale heapScale(std::uint64_t seed, std::uint64_t k) {
  auto u = [&](Draw d) { return unitFromBits(hashCounters(seed, d, k)); };
  return {1.0 + kSizeVariation * (2.0 * u(kSize) - 1.0), 0.8 + 0.4 * u(kHeight)};
}

// How heaps take the wind shear (MODEL.md section 10): they lean downwind by kLean times the
// shear's share metres per metre of height, and a cumulonimbus's anvil is carried downwind;
// the share is |shear| / kFullShear, at most 1.
constexpr double kLean = 0.15;
constexpr double kFullShear = 15.0;  // m/s between the heaps' top and the wind carrying them
struct Shear {
  glm::dvec2 direction;  // unit, downwind at the top relative to the heap
  double amount;         // 0 (none) to 1
};
Shear shearOf(const CloudField& f) {
  const double speed = glm::length(f.shear);
  if (!(speed > 1e-3)) return {{1.0, 0.0}, 0.0};
  return {f.shear / speed, std::min(speed / kFullShear, 1.0)};
}
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

// The ellipsoids of one heap standing on `base` (the middle of its flat bottom); those from
// `anvil_from` on are a cumulonimbus's anvil, lit as a heap of its own (MODEL.md section 14).
std::vector<Ellipsoid> heapEllipsoids(const CloudField& f, glm::dvec3 base, double size,
                                      double height, std::uint64_t seed, bool detailed,
                                      std::size_t& anvil_from) {
  const double r = heapRadius(f) * size;
  const double h = f.thickness_m * height;
  const double squash = 0.8 + 0.2 * unitFromBits(hashCounters(seed, kShape));
  if (isCb(f)) return cumulonimbusEllipsoids(f, base, r, h, squash, seed, detailed, anvil_from);
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

// Appends one heap to `cloud`, its ellipsoids and their parts (EllipsoidCloud::parts): the heap
// one part, a cumulonimbus's anvil another.
void addHeap(EllipsoidCloud& cloud, std::vector<Ellipsoid> heap, std::size_t anvil_from) {
  const std::uint32_t part = cloud.parts.empty() ? 0 : cloud.parts.back() + 1;
  for (std::size_t i = 0; i < heap.size(); ++i) {
    cloud.parts.push_back(i < anvil_from ? part : part + 1);
    cloud.ellipsoids.push_back(heap[i]);
  }
}

EllipsoidCloud heapCloud(const CloudField& f, std::string name) {
  const HeapLook& look = lookOf(f);
  EllipsoidCloud cloud;
  cloud.name = std::move(name);
  cloud.colour = glm::dvec3(look.colour);
  cloud.threshold_centre = look.t1;
  cloud.threshold_limb = look.t2;
  cloud.transition = look.d;
  cloud.shading.ambient = look.ambient;
  cloud.shading.texture_fraction = look.texture_fraction;
  cloud.light_extinction = look.light_extinction;
  // One of kHeapTextures textures per genus, chosen by the field's seed: the texture is solid
  // and repeats about once per heap radius, so every heap shows a different part of it, and a
  // few seeds give fields all the variety a seed per field did. The renderer bakes each once and
  // keeps it while fields come and go (a dataset's samples, a host's weather), whatever their
  // scale, where a seed per field meant a 128^3 bake per field.
  constexpr std::uint64_t kHeapTextures = 4;
  cloud.texture.seed = hashCounters(0x54657874ull, std::uint64_t(f.type), f.seed % kHeapTextures);
  cloud.texture.gardner.fx1 = cloud.texture.gardner.fy1 = look.texture_cycles / heapRadius(f);
  cloud.texture.gardner.t0 = look.texture_offset;
  cloud.texture.gardner.terms = look.texture_terms;
  return cloud;
}

// A lobe as the quadric of its surface, computed once for the many rays across a heap.
struct LobeQuadric {
  glm::dmat3 m;  // (p - centre)^T m (p - centre) = 1 on the surface
  glm::dvec3 centre;
};
std::vector<LobeQuadric> lobeQuadrics(const EllipsoidCloud& cloud) {
  std::vector<LobeQuadric> out;
  for (const Ellipsoid& e : cloud.ellipsoids) {
    const glm::dmat3 w = worldToUnitSphere(e);
    out.push_back({glm::transpose(w) * w, e.centre});
  }
  return out;
}

// Opacity of one cloud along the line through `point` seen from far away looking along unit
// `view`: SPEC section 4 in its orthographic limit, where the limb function g of a ray is the
// depth of the ray quadratic's minimum below zero (its discriminant over 4a), and the texture
// is read where the ray enters.
double orthographicOpacity(const EllipsoidCloud& cloud, const std::vector<LobeQuadric>& lobes,
                           const SolidTexture& texture, glm::dvec3 point, glm::dvec3 view) {
  double transmittance = 1.0;
  for (const LobeQuadric& lobe : lobes) {
    const glm::dmat3& m = lobe.m;
    const glm::dvec3 d = point - lobe.centre;
    // Q(s) = a s^2 + b s + c at point + s view.
    const double a = glm::dot(view, m * view);
    const double b = 2.0 * glm::dot(view, m * d);
    const double c = glm::dot(d, m * d) - 1.0;
    const double delta = b * b - 4.0 * a * c;
    if (delta <= 0.0) continue;
    const double g = std::clamp(delta / (4.0 * a), 0.0, 1.0);
    const double enter = (-b - std::sqrt(delta)) / (2.0 * a);
    const double it = texture.value(point + enter * view - cloud.drift_m);
    const double excess =
        it - cloud.threshold_centre - (cloud.threshold_limb - cloud.threshold_centre) * (1.0 - g);
    const double tr = cloud.transition <= 0.0
                          ? (excess <= 0.0 ? 1.0 : 0.0)
                          : std::clamp(1.0 - excess / cloud.transition, 0.0, 1.0);
    transmittance *= tr;
  }
  return 1.0 - transmittance;
}

// Mean area seen straight down (`side` false) or from the side, horizontally, (`side` true)
// with opacity >= 1/2 of one heap, in units of heapRadius^2, measured on 16 heaps whose sizes
// and heights are drawn as the tiles draw theirs. A heap's shape scales with its radius (the
// texture with it) but for its width over height, so the area is measured once per species
// row, at its thickness, on first use, and interpolated between rows in log thickness.
double unitArea(const CloudField& field, bool side) {
  auto measure = [side](CloudType t, double thickness) {
    CloudField f;
    f.type = t;
    f.thickness_m = thickness;
    const double r = heapRadius(f);
    const SolidTexture texture(heapCloud(f, "").texture);
    constexpr int kHeaps = 16, kGrid = 48;
    double area = 0.0;
    for (int k = 0; k < kHeaps; ++k) {
      // Sizes and heights drawn as the tiles draw them (makeTile).
      const HeapScale scale = heapScale(77, std::uint64_t(k));
      EllipsoidCloud cloud = heapCloud(f, "");
      std::size_t anvil_from = 0;
      cloud.ellipsoids = heapEllipsoids(f, {0.0, 0.0, 1000.0}, scale.size, scale.height,
                                        hashCounters(77, k), true, anvil_from);
      const std::vector<LobeQuadric> lobes = lobeQuadrics(cloud);
      // A square around the heap: across it (x) and down through it (y) or along its height.
      const double half = (isCb(f) ? 3.6 : 2.5) * r * scale.size, cell = 2.0 * half / kGrid;
      const double height = 2.0 * f.thickness_m * scale.height, step_up = height / kGrid;
      int inside = 0;
      for (int y = 0; y < kGrid; ++y)
        for (int x = 0; x < kGrid; ++x) {
          const double across = -half + (x + 0.5) * cell;
          inside += side ? orthographicOpacity(cloud, lobes, texture,
                                               {across, -10.0 * r, 1000.0 + (y + 0.5) * step_up},
                                               {0.0, 1.0, 0.0}) >= 0.5
                         : orthographicOpacity(cloud, lobes, texture,
                                               {across, -half + (y + 0.5) * cell, 1.0e5},
                                               {0.0, 0.0, -1.0}) >= 0.5;
        }
      area += inside * cell * (side ? step_up : cell) / (r * r);
    }
    return area / kHeaps;
  };
  // Each row measured on first use only: a sky of cumulus never pays for the cumulonimbus, a
  // view that shows no far deck never measures a side.
  static std::mutex mutex;
  static std::map<std::tuple<CloudType, std::size_t, bool>, double> measured;
  const std::span<const Species> rows = genus(field.type).species;
  auto row = [&](std::size_t i) {
    std::lock_guard lock(mutex);
    auto [it, added] = measured.try_emplace({field.type, i, side}, 0.0);
    if (added) it->second = measure(field.type, rows[i].thickness_m);
    return it->second;
  };
  const SpeciesSpan at = speciesSpan(field);
  return at.lo == at.hi ? row(at.lo) : (1.0 - at.s) * row(at.lo) + at.s * row(at.hi);
}

// The most any point asks for.
double peakCoverage(const CloudField& f) {
  return std::clamp(f.coverage * (1.0 + (f.clusters.none() ? 0.0 : f.clusters.amount)), 0.0,
                    CloudField::kMaxFieldCoverage);
}

// Heaps per square metre giving cover c (Boolean model: 1 - exp(-density * mean footprint)).
double heapDensity(const CloudField& f, double c) {
  const double r = heapRadius(f);
  const double mean_area = unitArea(f, false) * r * r;
  return -std::log1p(-c) / mean_area;
}

// Poisson count with mean `mean` from one uniform draw (inverse CDF; exact for means up to a
// few hundred, which tiles stay well below).
int poisson(double mean, double u) {
  double p = std::exp(-mean), cumulative = p;
  int k = 0;
  while (u > cumulative && k < 10000) {
    ++k;
    p *= mean / k;
    cumulative += p;
    if (p < 1e-300 && cumulative < u) break;
  }
  return k;
}

struct TileKey {
  std::string field;
  std::int64_t i, j;
  bool detailed;
  auto operator<=>(const TileKey&) const = default;
};

// Tiles already built (they are pure functions of their key), most recent first; bounded by
// the ellipsoids they hold (about 10 MiB), many times what one view within the heap range
// needs, so a long flight's memory levels off (docs/ACCURACY.md, "Long flights").
class TileCache {
 public:
  template <class Make>
  std::shared_ptr<const EllipsoidCloud> get(const TileKey& key, Make make) {
    {
      std::lock_guard lock(mutex_);
      if (auto it = index_.find(key); it != index_.end()) {
        order_.splice(order_.begin(), order_, it->second);
        return it->second->second;
      }
    }
    auto made = std::make_shared<const EllipsoidCloud>(make());
    std::lock_guard lock(mutex_);
    if (index_.count(key)) return made;
    order_.emplace_front(key, made);
    index_[key] = order_.begin();
    held_ += cost(*made);
    while (held_ > kCapacity && order_.size() > 1) {
      held_ -= cost(*order_.back().second);
      index_.erase(order_.back().first);
      order_.pop_back();
    }
    return made;
  }

 private:
  // In ellipsoids of 72 bytes; a tile, even an empty one, costs about eight more (its key,
  // name and texture).
  static constexpr std::size_t kCapacity = 1 << 17;
  static std::size_t cost(const EllipsoidCloud& tile) { return tile.ellipsoids.size() + 8; }
  std::size_t held_ = 0;
  std::mutex mutex_;
  std::list<std::pair<TileKey, std::shared_ptr<const EllipsoidCloud>>> order_;
  std::map<TileKey, decltype(order_)::iterator> index_;
};

std::string fieldKey(const CloudField& f) {
  std::ostringstream key;
  key.precision(17);
  key << f.name << '/' << int(f.type) << '/' << f.base_m << '/' << f.thickness_m << '/'
      << f.coverage << '/' << f.seed << '/' << f.shear.x << ',' << f.shear.y;
  const Region& r = f.region;
  if (!r.everywhere())
    key << "/r" << r.centre.x << ',' << r.centre.y << ',' << r.half_size.x << ',' << r.half_size.y
        << ',' << r.heading_deg << ',' << r.edge_m << ',' << r.side << ',' << r.transition_m;
  if (!f.clusters.none()) key << "/v" << f.clusters.spacing_m << ',' << f.clusters.amount;
  return key.str();
}

// One heap of a tile: where its flat bottom's middle stands (field frame, before drift), its
// size and height factors, and the seed of its shape.
struct HeapPlacement {
  glm::dvec3 base;
  HeapScale scale;
  std::uint64_t seed;
};

// The heaps of tile (i, j): a pure function of (field, i, j).
std::vector<HeapPlacement> heapPlacements(const CloudField& f, std::int64_t i, std::int64_t j) {
  const double size = fieldTileSize(f);
  const std::uint64_t tile_seed = hashCounters(f.seed, std::uint64_t(i), std::uint64_t(j));
  // Heaps are drawn for the highest cover anywhere, and each is kept with the ratio of the
  // density its place asks for to that (thinning a Poisson process gives a Poisson process of
  // the thinned density), so cover follows the region and the clusters without seams.
  const double peak = peakCoverage(f);
  const double peak_density = heapDensity(f, peak);
  const int count =
      poisson(peak_density * size * size, unitFromBits(hashCounters(tile_seed, kCount)));
  const bool uniform = f.region.everywhere() && f.clusters.none();
  std::vector<HeapPlacement> out;
  for (int k = 0; k < count; ++k) {
    auto u = [&](Draw d) { return unitFromBits(hashCounters(tile_seed, d, std::uint64_t(k))); };
    const glm::dvec3 base((double(i) + u(kX)) * size, (double(j) + u(kY)) * size, f.base_m);
    if (!uniform &&
        !(u(kKeep) < heapDensity(f, fieldCoverageAt(f, glm::dvec2(base))) / peak_density))
      continue;
    HeapScale scale = heapScale(tile_seed, std::uint64_t(k));
    scale.height *= clusterFactor(f.clusters, f.seed, kRise, glm::dvec2(base));
    out.push_back({base, scale, hashCounters(tile_seed, kShape, std::uint64_t(k))});
  }
  return out;
}

EllipsoidCloud makeTile(const CloudField& f, std::int64_t i, std::int64_t j, bool detailed) {
  EllipsoidCloud cloud = heapCloud(f, f.name + "/" + std::to_string(i) + "," + std::to_string(j));
  for (const HeapPlacement& p : heapPlacements(f, i, j)) {
    std::size_t anvil_from = 0;
    std::vector<Ellipsoid> heap =
        heapEllipsoids(f, p.base, p.scale.size, p.scale.height, p.seed, detailed, anvil_from);
    if (cloud.ellipsoids.size() + heap.size() > std::size_t(Limits::kMaxEllipsoidsPerCloud)) break;
    addHeap(cloud, std::move(heap), anvil_from);
  }
  return cloud;
}

TileCache& tileCache() {
  static TileCache cache;
  return cache;
}

}  // namespace

std::string_view cloudTypeName(CloudType type) {
  const int i = int(type);
  return i >= 0 && i < kCloudTypeCount ? genus(type).name : "unknown";
}

std::optional<CloudType> cloudTypeFromName(std::string_view name) {
  for (int i = 0; i < kCloudTypeCount; ++i)
    if (genus(CloudType(i)).name == name) return CloudType(i);
  return std::nullopt;
}

std::string weatherLayerError(const WeatherLayer& w) {
  std::ostringstream out;
  auto outside = [&](const char* name, double value, Range range) {
    return outOfRange(out, name, value, range);
  };
  if (int(w.type) < 0 || int(w.type) >= kCloudTypeCount) {
    out << "type: " << int(w.type) << " is not a genus (allowed: 0 none, 1 to "
        << kCloudTypeCount - 1 << ", the genus table's rows)";
    return out.str();
  }
  if (outside("base", w.base_m, {0.0, Limits::kMaxBase}) ||
      outside("thickness", w.thickness_m, Limits::kThickness) ||
      outside("coverage", w.coverage, Limits::kFraction))
    return out.str();
  if (w.wind && (outside("wind x", w.wind->x, {-Limits::kMaxWind, Limits::kMaxWind}) ||
                 outside("wind y", w.wind->y, {-Limits::kMaxWind, Limits::kMaxWind})))
    return out.str();
  if ((w.visibility_m != 0.0 && outside("visibility", w.visibility_m, Limits::kLayerVisibility)) ||
      outside("transition_band", w.transition_band_m, Limits::kTransitionBand) ||
      outside("scud", 100.0 * w.scud, Limits::kCoveragePercent))
    return out.str() + (w.visibility_m != 0.0 ? " (0 takes the genus's visibility)" : "");
  const Precipitation& p = w.precipitation;
  if (int(p.kind) < 0 || int(p.kind) >= kPrecipitationKindCount) {
    out << "precipitation: " << int(p.kind)
        << " is not a kind (allowed: none, rain, snow, sleet, hail, sand, dust)";
    return out.str();
  }
  if (outside("precipitation_rate", p.rate_mm_h, Limits::kPrecipitationRate) ||
      (p.visibility_m != 0.0 &&
       outside("precipitation_visibility", p.visibility_m, Limits::kPrecipitationVisibility)))
    return out.str() + (p.visibility_m != 0.0 ? " (0 takes the rate's visibility)" : " mm/h");
  if ((p.kind == PrecipitationKind::kSand || p.kind == PrecipitationKind::kDust) &&
      !(p.visibility_m > 0.0))
    return "precipitation_visibility: " + std::string(kPrecipitationNames[int(p.kind)]) +
           " needs one (allowed: " + formatNumber(Limits::kPrecipitationVisibility.lo) + " to " +
           formatNumber(Limits::kPrecipitationVisibility.hi) + " m; it has no rate)";
  if (std::string error = regionError(w.region); !error.empty()) return error;
  if (std::string error = clusterVariationError(w.clusters); !error.empty()) return error;
  if (w.region.transition_m > 0.0 && w.region.side == 0)
    return "transition: applies to one side of a front only (front left or right)";
  if ((w.clusters.spacing_m > 0.0 || w.clusters.amount > 0.0) && !genus(w.type).heaps)
    return "variation: applies to heaps only (type cumulus or cumulonimbus), not " +
           std::string(cloudTypeName(w.type));
  if (w.clusters.amount > 0.0 && !(w.clusters.spacing_m > 0.0))
    return "variation: needs spacing, the distance between the clusters it varies";
  return "";
}

double fieldCoverageAt(const CloudField& f, glm::dvec2 xy) {
  const double c =
      f.coverage * regionWeight(f.region, xy) * clusterFactor(f.clusters, f.seed, kCover, xy);
  return std::clamp(c, 0.0, CloudField::kMaxFieldCoverage);
}

double fieldTileSize(const CloudField& f) {
  return 4.0 * heapRadius(f);
}

std::vector<EllipsoidCloud> tileClouds(const CloudField& f, std::int64_t i, std::int64_t j) {
  std::vector<EllipsoidCloud> out;
  EllipsoidCloud cloud = makeTile(f, i, j, true);
  if (!cloud.ellipsoids.empty()) out.push_back(std::move(cloud));
  return out;
}

std::string_view heapSpecies(const CloudField& f) {
  const std::span<const Species> rows = genus(f.type).species;
  std::string_view nearest = "";
  double best = std::numeric_limits<double>::infinity();
  for (const Species& s : rows)
    if (const double d = std::abs(std::log(f.thickness_m / s.thickness_m)); d < best)
      best = d, nearest = s.name;
  return nearest;
}

EllipsoidCloud typicalHeap(const CloudField& f, glm::dvec3 base) {
  EllipsoidCloud heap = heapCloud(f, f.name + "/typical");
  std::size_t anvil_from = 0;
  // Made before addHeap reads anvil_from (an argument's order of evaluation is unspecified).
  std::vector<Ellipsoid> lobes = heapEllipsoids(f, base, 1.0, 1.0, f.seed, true, anvil_from);
  addHeap(heap, std::move(lobes), anvil_from);
  return heap;
}

double fieldTop(const CloudField& f) {
  const double rise = f.clusters.none() ? 1.0 : 1.0 + f.clusters.amount;
  return f.base_m + 1.3 * f.thickness_m * rise;
}

double heapRange(const CloudField& f, const Camera& camera, double range_m) {
  // From high up the view reaches further: the automatic range grows with the height above the
  // heaps.
  const double asked =
      range_m > 0.0 ? range_m : CloudField::kRangeM + 2.0 * std::abs(camera.position.z - f.base_m);
  return std::min(asked, CloudField::kMaxRangeTiles * fieldTileSize(f));
}

namespace {

// Calls visit(i, j, lo, hi) for each tile (i, j) within heapRange of the camera where the
// field's region leaves some cover, with the tile's box in the field's own frame (its X and Y
// grown by the largest heap that can reach out of it, its Z from the heaps' base to their top).
template <class Visit>
void forTilesAround(const CloudField& f, const Camera& camera, const HeapDrawing& drawing,
                    Visit visit) {
  if (!(peakCoverage(f) > 0.0)) return;
  const double size = fieldTileSize(f);
  // The eye in the field's own frame (the field has drifted by drift_m).
  const glm::dvec2 eye = glm::dvec2(camera.position) - f.drift_m;
  const double range = heapRange(f, camera, drawing.range_m);
  const double top = fieldTop(f);
  const double reach = 3.6 * heapRadius(f) * (1.0 + kSizeVariation);
  const auto lo = glm::floor((eye - range) / size), hi = glm::floor((eye + range) / size);
  for (double jy = lo.y; jy <= hi.y; ++jy)
    for (double ix = lo.x; ix <= hi.x; ++ix) {
      if (glm::length(glm::dvec2(ix + 0.5, jy + 0.5) * size - eye) > range) continue;
      // Tiles where the region leaves no cover are never built.
      if (regionExcludesDisc(f.region, glm::dvec2(ix + 0.5, jy + 0.5) * size,
                             std::sqrt(0.5) * size))
        continue;
      const glm::dvec2 min_xy = glm::dvec2(ix, jy) * size - reach;
      const glm::dvec2 max_xy = glm::dvec2(ix + 1.0, jy + 1.0) * size + reach;
      visit(std::int64_t(ix), std::int64_t(jy), glm::dvec3(min_xy, f.base_m),
            glm::dvec3(max_xy, top));
    }
}

// The heaps of the tiles around the camera (forTilesAround) that `keep` takes by their box,
// drifted into place; `detailed` says from the box whether a tile's heaps are drawn with every
// lobe.
template <class Keep, class Detailed>
std::vector<EllipsoidCloud> tilesAround(const CloudField& f, const Camera& camera,
                                        const HeapDrawing& drawing, Keep keep, Detailed detailed) {
  std::vector<EllipsoidCloud> out;
  const std::string key = fieldKey(f);
  forTilesAround(f, camera, drawing,
                 [&](std::int64_t i, std::int64_t j, glm::dvec3 box_min, glm::dvec3 box_max) {
                   if (!keep(box_min, box_max)) return;
                   const bool fine = detailed(box_min, box_max);
                   const auto tile =
                       tileCache().get({key, i, j, fine}, [&] { return makeTile(f, i, j, fine); });
                   if (tile->ellipsoids.empty()) return;
                   EllipsoidCloud cloud = *tile;
                   const glm::dvec3 drift(f.drift_m, 0.0);
                   for (Ellipsoid& e : cloud.ellipsoids) e.centre += drift;
                   cloud.drift_m = drift;
                   out.push_back(std::move(cloud));
                 });
  return out;
}

// Where a heap's precipitation falls (MODEL.md section 17): a shaft of a share of the heap's
// radius, its axis moved downwind of the heap's by another share, where the upper wind carries
// the falling precipitation out of the updraft; a cumulonimbus's updraft keeps a rain-free base
// upwind of its shaft.
struct ShaftShape {
  double radius, offset;  // times the heap's radius
};
ShaftShape shaftShape(const CloudField& f) {
  return isCb(f) ? ShaftShape{0.3, 0.2} : ShaftShape{0.5, 0.1};
}

}  // namespace

std::vector<EllipsoidCloud> fieldClouds(const CloudField& f, const Camera& camera,
                                        const HeapDrawing& drawing) {
  const ViewBasis basis = viewBasis(camera);
  const glm::dvec3 eye(glm::dvec2(camera.position) - f.drift_m, camera.position.z);
  // Pixels per metre at unit distance: a heap of radius r at distance d spans r focal / d.
  const double focal_px = 0.5 * camera.height / basis.tan_half_vfov;
  return tilesAround(
      f, camera, drawing,
      // A tile is kept when its box is not wholly outside the view frustum (the renderer's
      // test for clouds).
      [&](glm::dvec3 lo, glm::dvec3 hi) { return boxMayBeInView(basis, eye, lo, hi); },
      // The nearest point of the tile's box stands for its heaps, so a tile is detailed when
      // its nearest heap would be.
      [&](glm::dvec3 lo, glm::dvec3 hi) {
        const double distance = glm::length(glm::clamp(eye, lo, hi) - eye);
        return heapRadius(f) * focal_px >= drawing.detail_px * distance;
      });
}

std::vector<EllipsoidCloud> fieldShadowClouds(const CloudField& f, const Camera& camera,
                                              const HeapDrawing& drawing) {
  return tilesAround(
      f, camera, drawing, [](glm::dvec3, glm::dvec3) { return true; },
      [](glm::dvec3, glm::dvec3) { return false; });
}

RainShaft heapRainShaft(const CloudField& f, glm::dvec3 base, double size) {
  const ShaftShape shape = shaftShape(f);
  const Shear shear = shearOf(f);
  const double r = heapRadius(f) * size;
  RainShaft shaft;
  shaft.centre = glm::dvec2(base) + shear.direction * (shear.amount * shape.offset * r);
  shaft.radius_m = shape.radius * r;
  shaft.top_m = base.z;
  shaft.sigma = precipitationExtinction(f.precipitation);
  // In its heap's shadow, lit by the sky alone, as the ground there (MODEL.md section 16).
  shaft.colour = kGroundSkyShare * precipitationColour(f.precipitation.kind);
  return shaft;
}

std::vector<RainShaft> fieldRainShafts(const CloudField& f, const Camera& camera,
                                       const HeapDrawing& drawing) {
  std::vector<RainShaft> out;
  if (!(precipitationExtinction(f.precipitation) > 0.0)) return out;
  const ViewBasis basis = viewBasis(camera);
  forTilesAround(f, camera, drawing, [&](std::int64_t i, std::int64_t j, glm::dvec3, glm::dvec3) {
    for (const HeapPlacement& heap : heapPlacements(f, i, j)) {
      const RainShaft shaft =
          heapRainShaft(f, heap.base + glm::dvec3(f.drift_m, 0.0), heap.scale.size);
      const glm::dvec3 lo(shaft.centre - shaft.radius_m, 0.0),
          hi(shaft.centre + shaft.radius_m, shaft.top_m);
      if (boxMayBeInView(basis, camera.position, lo, hi)) out.push_back(shaft);
    }
  });
  return out;
}

namespace {

// True when the camera sees the plane Z = altitude further than `range` horizontally from
// itself: some corner ray of the view meets it beyond that, or runs parallel to or away from
// it (the plane's horizon is then in view). The view's footprint on the plane is the convex
// hull of the corner rays' hits, so its farthest point is a corner.
bool planeSeenBeyond(const Camera& camera, double altitude, double range) {
  const ViewBasis b = viewBasis(camera);
  const double dz = altitude - camera.position.z;
  for (double sx : {-1.0, 1.0})
    for (double sy : {-1.0, 1.0}) {
      const glm::dvec3 d =
          b.forward + sx * b.tan_half_vfov * b.aspect * b.right + sy * b.tan_half_vfov * b.up;
      if (!(d.z * dz > 0.0)) return true;
      if ((dz / d.z) * glm::length(glm::dvec2(d)) > range) return true;
    }
  return false;
}

// The far deck standing for a field's heaps beyond `range` (MODEL.md section 11): a sky plane
// of the stratocumulus look a metre under the heaps' base (so that no heap spans it and the
// renderer need not draw the heaps once per side of it), drawn for the field's coverage in its
// region, lit like the heaps, drifting with them, with a hole of `range` around the camera.
// Its threshold is calibrated once per field (a few milliseconds).
// The far deck's look: the heap's eq. 8 with the mean light its lobes take (MODEL.md section
// 14, meanHeapLight: the sunlight as a multiple of the Lambertian mean), lobes weighted by
// their horizontal cross-section, for one typical heap of the field.
// I = (1 - a)(1 - t) S Id + (1 - a) t It + a K is eq. 8 with a' = a K / c, t' = (1 - a) t /
// ((1 - a)((1 - t) S + t)) and the colour times c = (1 - a)((1 - t) S + t) + a K.
void lightFarDeck(const CloudField& f, glm::dvec3 to_sun, CloudLayer& deck) {
  const MeanHeapLight mean = meanHeapLight(typicalHeap(f, glm::dvec3(0.0, 0.0, f.base_m)), to_sun);
  const double sun = mean.sun_over_lambert, sky = mean.sky;
  ShadingParams& s = deck.shading;
  const double a = s.ambient, t = s.texture_fraction;
  const double c = (1.0 - a) * ((1.0 - t) * sun + t) + a * sky;
  if (!((1.0 - a) * ((1.0 - t) * sun + t) > 0.0)) return;
  s.ambient = a * sky / c;
  s.texture_fraction = (1.0 - a) * t / ((1.0 - a) * ((1.0 - t) * sun + t));
  deck.colour *= c;
}

CloudLayer farDeck(const CloudField& f, double range, glm::dvec3 to_sun) {
  static std::mutex mutex;
  static std::map<std::string, CloudLayer> decks;
  const std::string key = fieldKey(f);
  CloudLayer deck;
  {
    std::lock_guard lock(mutex);
    auto it = decks.find(key);
    if (it == decks.end()) {
      const WeatherLayer w{CloudType::kStratocumulus,
                           std::max(f.base_m - 1.0, 0.0),
                           f.thickness_m,
                           std::min(f.coverage, CloudField::kMaxFieldCoverage),
                           {},
                           f.region,
                           {}};
      // One of kDeckTextures textures, chosen by the field's seed, as a field's heaps take one
      // of a few (heapCloud): the deck's periodic table is a 512^2 bake of tens of
      // milliseconds, which a seed per field made every dataset sample pay.
      constexpr std::uint64_t kDeckTextures = 4;
      const std::vector<CloudLayer> layers =
          weatherClouds(w, f.name + "/far", hashCounters(0x466172ull, f.seed % kDeckTextures))
              .layers;
      if (decks.size() > 256) decks.clear();
      CloudLayer deck = layers.empty() ? CloudLayer{} : layers.front();
      // Gardner's periodic lattice, which the renderer bakes: a far deck is seen at a grazing
      // angle, where its period foreshortens below the heaps' own spacing.
      deck.texture.gardner.rotation_deg = deck.texture.gardner.jitter_octaves = 0.0;
      // It stands for distant heaps, not for the stratocumulus genus whose texture it
      // borrows: Gardner's amplitude ratio, with which its cover was matched to the heaps'
      // (docs/ACCURACY.md, "Scale"), whatever ratio that genus takes for its own spectrum.
      deck.texture.gardner.amplitude_ratio = GardnerTextureParams{}.amplitude_ratio;
      // Its cover rises towards the horizon as the heaps' sides fill the gaps: the ratio of a
      // heap's side silhouette to its footprint, both measured (unitArea).
      deck.far.coverage = w.coverage;
      deck.far.side_ratio = unitArea(f, true) / unitArea(f, false);
      calibrateFarCover(deck.texture, deck.transition, deck.far);
      deck.threshold = deck.far.threshold[0];  // unused while far.side_ratio > 0
      it = decks.emplace(key, deck).first;
    }
    deck = it->second;
  }
  const HeapLook& look = lookOf(f);
  deck.colour = glm::dvec3(look.colour);
  deck.shading.ambient = look.ambient;
  deck.shading.texture_fraction = look.texture_fraction;
  lightFarDeck(f, to_sun, deck);
  deck.texture.drift_offset_m = f.drift_m;
  // Heaps stand in the tiles whose middle is within the range, so their density falls from
  // full to none over a tile either side of it; the deck rises over the same band.
  const double tile = fieldTileSize(f);
  deck.hole_radius_m = std::max(range - 0.5 * tile, kRegionMinBand);
  deck.hole_band_m = tile;
  return deck;
}

}  // namespace

FieldContent fieldContent(const Scene& scene, const HeapDrawing& drawing) {
  FieldContent out;
  for (const CloudField& field : scene.fields) {
    std::vector<EllipsoidCloud> heaps = fieldClouds(field, scene.camera, drawing);
    out.heaps.insert(out.heaps.end(), std::make_move_iterator(heaps.begin()),
                     std::make_move_iterator(heaps.end()));
    const double range = heapRange(field, scene.camera, drawing.range_m);
    if (field.coverage > 0.0 && planeSeenBeyond(scene.camera, field.base_m, range))
      out.far_decks.push_back(farDeck(field, range, sunDirection(scene.sun)));
  }
  out.rain_shafts = rainShaftsInView(scene, drawing);
  return out;
}

Scene withFieldClouds(const Scene& scene, const HeapDrawing& drawing) {
  FieldContent content = fieldContent(scene, drawing);
  Scene out = scene;
  out.clouds.insert(out.clouds.end(), std::make_move_iterator(content.heaps.begin()),
                    std::make_move_iterator(content.heaps.end()));
  out.layers.insert(out.layers.end(), content.far_decks.begin(), content.far_decks.end());
  out.rain_shafts = std::move(content.rain_shafts);
  out.fields.clear();
  return out;
}

}  // namespace nephele
