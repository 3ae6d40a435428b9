#include "world/formations/cloud_shadow.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>
#include <sstream>
#include <string>

#include "world/automaton/cloud_density.h"
#include "world/counter_random.h"
#include "world/formations/cloud_field.h"
#include "world/formulas/ellipsoid.h"
#include "world/formulas/table.h"
#include "world/scene.h"
#include "world/shading.h"
#include "world/textures/solid_texture.h"

namespace nephele {
namespace {

// The texture and thresholds a table depends on, as text.
std::string tableKey(const EllipsoidCloud& cloud) {
  const SolidTextureSpec& t = cloud.texture;
  const GardnerTextureParams& g = t.gardner;
  std::ostringstream key;
  key.precision(17);
  key << cloud.threshold_centre << '/' << cloud.threshold_limb << '/' << cloud.transition << '/'
      << int(t.source) << '/' << t.seed << '/' << g.terms << ',' << g.fx1 << ',' << g.fy1 << ','
      << g.t0 << ',' << g.seeded_phases << ',' << g.seed << ',' << g.amplitude_ratio << '/'
      << t.perlin_period_m << ',' << t.perlin_size_log2 << ',' << t.perlin_cells << ','
      << t.perlin_octaves << ',' << t.perlin_persistence;
  return key.str();
}

ShadowTable computeTable(const EllipsoidCloud& cloud) {
  const SolidTexture texture(cloud.texture);
  const glm::dvec3 period = texture.period();
  std::array<double, kShadowTextureSamples> values{};
  for (int k = 0; k < kShadowTextureSamples; ++k) {
    auto u = [&](int axis) { return unitFromBits(hashCounters(0x5ad0, std::uint64_t(k), axis)); };
    values[std::size_t(k)] = texture.value(glm::dvec3(u(0), u(1), u(2)) * period);
  }
  ShadowTable table{};
  for (int i = 0; i < kShadowTableSize; ++i) {
    const double g = double(i) / (kShadowTableSize - 1);
    double sum = 0.0;
    for (double v : values)
      sum += 1.0 - ellipsoidTranslucence(v, cloud.threshold_centre, cloud.threshold_limb, g,
                                         cloud.transition);
    table[std::size_t(i)] = float(sum / kShadowTextureSamples);
  }
  return table;
}

}  // namespace

ShadowTable meanOpacityTable(const EllipsoidCloud& cloud) {
  // A field's tiles share a texture; a bounded cache keeps a table per texture and thresholds.
  static std::mutex mutex;
  static std::map<std::string, ShadowTable> cache;
  const std::string key = tableKey(cloud);
  {
    const std::lock_guard lock(mutex);
    if (auto it = cache.find(key); it != cache.end()) return it->second;
  }
  const ShadowTable table = computeTable(cloud);
  const std::lock_guard lock(mutex);
  if (cache.size() >= 1024) cache.clear();
  cache.emplace(key, table);
  return table;
}

double meanOpacity(const ShadowTable& table, double g) {
  const glm::dvec2 cell = formulas::tableCell(g, kShadowTableSize - 1);
  const std::size_t i = std::size_t(cell.x);
  return (1.0 - cell.y) * table[i] + cell.y * table[i + 1];
}

double casterSunlight(const ShadowCaster& caster, const ShadowTable& table, glm::dvec3 p,
                      glm::dvec3 to_sun) {
  const glm::dvec3 o = caster.to_unit * (p - caster.centre), w = caster.to_unit * to_sun;
  const double chord = formulas::unitSphereChord(o, w);  // 0 where the ray misses
  if (!(chord > 0.0)) return 1.0;
  return formulas::lobeSunlight(meanOpacity(table, formulas::sunRayLimb(o, w)),
                                caster.extinction * chord, kDiffuseAsymmetry);
}

std::vector<std::size_t> castingPlanes(const Scene& scene) {
  std::vector<std::size_t> out;
  if (!(scene.sun.elevation_deg >= kMinShadowElevationDeg)) return out;
  for (std::size_t i = 0; i < scene.layers.size(); ++i)
    if (!(scene.layers[i].far.side_ratio > 0.0)) out.push_back(i);
  std::stable_sort(out.begin(), out.end(), [&](std::size_t a, std::size_t b) {
    return scene.layers[a].altitude_m < scene.layers[b].altitude_m;
  });
  if (out.size() > std::size_t(kMaxCastingPlanes)) out.resize(std::size_t(kMaxCastingPlanes));
  return out;
}

double shadowRange(double camera_z) {
  constexpr double kMin = 24000.0;
  double range = kMin;
  while (range < 4.0 * camera_z && range < 64.0 * kMin) range *= 2.0;
  return range;
}

CloudShadows::CloudShadows(const Scene& scene, const HeapDrawing& heaps, bool lookups) {
  if (!(scene.sun.elevation_deg >= kMinShadowElevationDeg)) return;
  to_sun_ = sunDirection(scene.sun);
  std::map<std::string, int> table_of;
  auto add = [&](const EllipsoidCloud& cloud) {
    if (!(cloud.light_extinction > 0.0) || cloud.ellipsoids.empty()) return;
    const std::string key = tableKey(cloud);
    auto [it, fresh] = table_of.emplace(key, int(tables_.size()));
    if (fresh) tables_.push_back(meanOpacityTable(cloud));
    for (const Ellipsoid& e : cloud.ellipsoids) {
      const double reach = std::max({e.radii.x, e.radii.y, e.radii.z});
      if (!(e.centre.z + reach > 0.0)) continue;  // wholly underground
      floor_ = std::min(floor_, e.centre.z - verticalHalfExtent(e));
      casters_.push_back(
          {e.centre, worldToUnitSphere(e), reach, cloud.light_extinction, it->second});
    }
  };
  for (const EllipsoidCloud& cloud : scene.clouds) add(cloud);
  for (const CloudField& field : scene.fields) {
    HeapDrawing near = heaps;
    const double reach = shadowRange(scene.camera.position.z) +
                         fieldTop(field) * std::sqrt(1.0 - to_sun_.z * to_sun_.z) / to_sun_.z;
    near.range_m = std::min(heapRange(field, scene.camera, heaps.range_m), reach);
    for (const EllipsoidCloud& cloud : fieldShadowClouds(field, scene.camera, near)) add(cloud);
  }
  if (casters_.empty()) return;

  lo_ = glm::dvec2(std::numeric_limits<double>::infinity());
  hi_ = -lo_;
  for (const ShadowCaster& caster : casters_) {
    glm::dvec2 a, b;
    footprint(caster, a, b);
    lo_ = glm::min(lo_, a);
    hi_ = glm::max(hi_, b);
  }
  if (!lookups) return;
  // Cells of at least 200 m, at most 512 a side, and at least a quarter of the mean footprint's
  // side, so that a caster is listed in about 25 cells at most (a cumulonimbus's anvil lobes
  // throw footprints of 10 km).
  const glm::dvec2 extent = hi_ - lo_;
  double mean_side = 0.0;
  for (const ShadowCaster& caster : casters_) mean_side += 2.0 * caster.reach / to_sun_.z;
  mean_side /= double(casters_.size());
  cell_ = std::max({200.0, extent.x / 512.0, extent.y / 512.0, 0.25 * mean_side});
  cells_ = glm::max(glm::ivec2(glm::ceil(extent / cell_)), glm::ivec2(1));
  first_.assign(std::size_t(cells_.x) * cells_.y + 1, 0);
  auto each = [&](auto visit) {
    for (std::size_t i = 0; i < casters_.size(); ++i) {
      glm::ivec2 c0, c1;
      footprintCells(casters_[i], c0, c1);
      for (int y = c0.y; y <= c1.y; ++y)
        for (int x = c0.x; x <= c1.x; ++x) visit(std::size_t(y) * cells_.x + x, int(i));
    }
  };
  each([&](std::size_t k, int) { ++first_[k + 1]; });
  for (std::size_t k = 1; k < first_.size(); ++k) first_[k] += first_[k - 1];
  listed_.resize(std::size_t(first_.back()));
  std::vector<int> next(first_.begin(), first_.end() - 1);
  each([&](std::size_t k, int i) { listed_[std::size_t(next[k]++)] = i; });
}

void CloudShadows::footprintCells(const ShadowCaster& caster, glm::ivec2& c0,
                                  glm::ivec2& c1) const {
  glm::dvec2 a, b;
  footprint(caster, a, b);
  c0 = glm::clamp(glm::ivec2(glm::floor((a - lo_) / cell_)), glm::ivec2(0), cells_ - 1);
  c1 = glm::clamp(glm::ivec2(glm::floor((b - lo_) / cell_)), glm::ivec2(0), cells_ - 1);
}

void CloudShadows::footprint(const ShadowCaster& caster, glm::dvec2& lo, glm::dvec2& hi) const {
  // The bounding sphere's shadow on Z = 0 is an ellipse about the centre's shadow with semi-axes
  // reach and reach / sin(elevation); the square of half side reach / to_sun.z holds it.
  const glm::dvec2 centre = planeCrossing(caster.centre, 0.0, to_sun_);
  const double half = caster.reach / to_sun_.z;
  lo = centre - half;
  hi = centre + half;
}

double CloudShadows::sunlightAt(glm::dvec3 p, const HeapEnvelope* own) const {
  if (casters_.empty() || first_.empty()) return 1.0;
  // Every point of the sun's line through p lands on the ground where p's does.
  const glm::dvec2 ground = planeCrossing(p, 0.0, to_sun_);
  if (!(ground.x >= lo_.x && ground.y >= lo_.y && ground.x <= hi_.x && ground.y <= hi_.y))
    return 1.0;
  const glm::ivec2 c =
      glm::clamp(glm::ivec2(glm::floor((ground - lo_) / cell_)), glm::ivec2(0), cells_ - 1);
  double light = 1.0;
  const std::size_t k = std::size_t(c.y) * cells_.x + c.x;
  for (int n = first_[k]; n < first_[k + 1]; ++n) {
    const ShadowCaster& caster = casters_[std::size_t(listed_[std::size_t(n)])];
    if (own && insideEnvelope(*own, caster.centre)) continue;
    light *= casterSunlight(caster, tables_[std::size_t(caster.table)], p, to_sun_);
  }
  return light;
}

PlaneShadows::PlaneShadows(const Scene& scene)
    : to_sun_(sunDirection(scene.sun)), time_s_(scene.time_s), eye_(scene.camera.position) {
  for (std::size_t i : castingPlanes(scene))
    planes_.push_back({&scene.layers[i], LayerTexture(scene.layers[i].texture)});
}

double PlaneShadows::sunlight(glm::dvec3 p, double top) const {
  double light = 1.0;
  for (const Plane& plane : planes_) {
    const CloudLayer& layer = *plane.layer;
    if (!(layer.altitude_m > p.z) || !(layer.altitude_m > top)) continue;
    const glm::dvec2 q = planeCrossing(p, layer.altitude_m, to_sun_);
    const double t1 = layerThreshold(layer, q, to_sun_, time_s_, eye_);
    if (t1 >= 1.0) continue;
    light *= skyPlaneTranslucence(plane.texture.value(q, time_s_), t1, layer.transition);
  }
  return light;
}

}  // namespace nephele
