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
#include "world/formations/heap_shape.h"
#include "world/formations/weather.h"
#include "world/limits.h"
#include "world/scene.h"
#include "world/sky.h"
#include "world/textures/solid_texture.h"

namespace nephele {
namespace {

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
      cloud.ellipsoids =
          heapEllipsoids(f, {0.0, 0.0, 1000.0}, r * scale.size, f.thickness_m * scale.height,
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
        heapEllipsoids(f, p.base, heapRadius(f) * p.scale.size, f.thickness_m * p.scale.height,
                       p.seed, detailed, anvil_from);
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
  std::vector<Ellipsoid> lobes =
      heapEllipsoids(f, base, heapRadius(f), f.thickness_m, f.seed, true, anvil_from);
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
