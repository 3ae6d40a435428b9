#pragma once
// Weather as host simulators describe it (CIGI Weather Control: per layer a cloud type, base,
// thickness, coverage and wind), and the convective part of it: a field of cumulus or
// cumulonimbus heaps that exists everywhere, generated per ground tile around whichever view
// is rendered (MODEL.md section 10). A tile's heaps depend only on (field seed, tile index),
// so the sky is the same whatever order tiles are visited in and whichever view asks.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "world/camera.h"
#include "world/formations/ellipsoid_cloud.h"
#include "world/formations/region.h"
#include "world/precipitation.h"

namespace nephele {

// The genera, in the order of their table (genus.cpp), "none" first. The numbers hosts send
// for them are the protocols' (protocol/cloud_codes.h); snapshots store this order, so a new
// genus goes at the end.
enum class CloudType : int {
  kNone,
  kAltocumulus,
  kAltostratus,
  kCirrocumulus,
  kCirrostratus,
  kCirrus,
  kCumulonimbus,
  kCumulus,
  kNimbostratus,
  kStratocumulus,
  kStratus,
};
inline constexpr int kCloudTypeCount = 11;
std::string_view cloudTypeName(CloudType type);
// The type named `name` (as cloudTypeName spells it), or nullopt.
std::optional<CloudType> cloudTypeFromName(std::string_view name);

struct WeatherLayer {
  CloudType type = CloudType::kNone;
  double base_m = 1000.0;          // cloud base above the ground
  double thickness_m = 500.0;      // base to top
  double coverage = 0.5;           // cloud fraction (SPEC section 9), 0..1
  std::optional<glm::dvec2> wind;  // east, north m/s at this layer; unset keeps the world's
  Region region;                   // where the layer lies; the default is everywhere
  ClusterVariation clusters;       // heaps only: Gardner's macrocluster variation
  // Stratiform genera: the visibility inside the layer (0: the genus's), and the band above
  // its top and below its base over which it thins out (MODEL.md section 5, the in-layer veil).
  double visibility_m = 0.0;
  double transition_band_m = 0.0;
  // Scud (MODEL.md section 10): the cloud fraction, 0..1, of ragged fragments drawn under the
  // base (CIGI's scud frequency); 0 draws none.
  double scud = 0.0;
  // Rain, snow and the rest (MODEL.md section 17): a layer of clouds lets it fall from its
  // base to the ground; a layer of type none (CIGI's layers 4 to 9) holds it from base to top.
  Precipitation precipitation{};
  bool operator==(const WeatherLayer&) const = default;
};

// Empty when the layer can be drawn, else what is wrong and what is allowed (ranges in
// world/limits.h).
std::string weatherLayerError(const WeatherLayer& layer);

// Heaps of one convective layer, everywhere.
struct CloudField {
  std::string name;
  CloudType type = CloudType::kCumulus;  // cumulus or cumulonimbus
  double base_m = 1000.0;
  double thickness_m = 1500.0;
  double coverage = 0.3;  // the heaps' own cloud fraction, 0..kMaxFieldCoverage
  std::uint64_t seed = 1;
  glm::dvec2 drift_m{0.0, 0.0};  // how far the field has moved with the wind since time 0
  // Where the heaps stand, in the field's own frame (it drifts with them), and how their
  // cover and height vary from cluster to cluster (MODEL.md section 11).
  Region region;
  ClusterVariation clusters;
  // The wind at the heaps' top less the wind that carries them, east and north, m/s (set from
  // the world's wind profile when the scene is taken): heaps lean with it and a cumulonimbus's
  // anvil spreads along it (MODEL.md section 10).
  glm::dvec2 shear{0.0, 0.0};
  // Its weather layer's rain or snow, falling in a shaft under each heap (MODEL.md section 17).
  Precipitation precipitation{};

  // Heaps are a Boolean model (Poisson centres, random sizes): the fraction they cover is
  // 1 - exp(-density * mean footprint) for any coverage up to 1, but above this their
  // overlaps merge into one mass; weather layers asking for more add a deck (weather.h).
  static constexpr double kMaxFieldCoverage = 0.6;
  // Heaps are generated in tiles within this horizontal distance of the eye, plus twice the
  // eye's height above the field.
  static constexpr double kRangeM = 40000.0;
  // And within this many tiles (four heap radii each) of it, whatever the range asked: a thin
  // layer's small heaps would otherwise fill the range with millions of tiles (a legal 10 m
  // cumulonimbus layer took 34 s a frame); the far deck stands for the heaps beyond. About
  // 4,000 tiles; a mediocris field's tiles are 4 km, so its cap is 160 km.
  static constexpr double kMaxRangeTiles = 36.0;
};

// The cover the field's heaps are drawn for at `xy` (field frame, before drift): its coverage
// times its region's weight and its cluster's cover factor there, at most kMaxFieldCoverage.
double fieldCoverageAt(const CloudField& field, glm::dvec2 xy);

// Size of one heap's tile, metres (a few heaps per tile at any coverage).
double fieldTileSize(const CloudField& field);

// The heaps of tile (i, j), tile (0, 0) starting at the field's origin (before drift): a pure
// function of (field, i, j). Names are `<field name>/<i>,<j>/<k>`.
std::vector<EllipsoidCloud> tileClouds(const CloudField& field, std::int64_t i, std::int64_t j);

// The species the field's heaps are of (genus.h, Species): the row of its genus nearest its
// thickness in log thickness, e.g. "humilis", "mediocris" or "congestus" for cumulus.
std::string_view heapSpecies(const CloudField& field);

// The altitude whose wind carries the field: the middle of its heaps.
inline double fieldAltitude(const CloudField& field) {
  return field.base_m + 0.5 * field.thickness_m;
}

// One heap of the field, of typical size and height, standing on `base`: lit and textured as
// the field's heaps are (the far deck takes its light from it; the look figures measure it).
EllipsoidCloud typicalHeap(const CloudField& field, glm::dvec3 base);

// How a render draws a field's heaps, by their distance and their size in the view (two knobs of
// the error/time sweep, docs/ACCURACY.md): as ellipsoids out to `range_m` and as a far deck beyond
// (MODEL.md section 11; 0: CloudField::kRangeM plus twice the camera's height above the field's
// base); every lobe of a heap whose radius spans at least `detail_px` pixels of the view, and
// below that only the ellipsoids that set its outline (its base, one mound for its lobes, a
// cumulonimbus's anvil); 0 draws every lobe at any distance.
struct HeapDrawing {
  double range_m = 0.0;
  double detail_px = 32.0;
};

// The highest a field's heaps reach: 1.3 times its thickness above its base, times 1 + the
// clusters' variation (which raises the heaps of the tallest clusters).
double fieldTop(const CloudField& field);

// The range of heaps drawn as ellipsoids: `range_m` when positive, else the automatic one;
// at most CloudField::kMaxRangeTiles tiles.
double heapRange(const CloudField& field, const Camera& camera, double range_m = 0.0);

// The heaps of every tile within heapRange of the camera whose bounds meet its view, drifted
// into place.
std::vector<EllipsoidCloud> fieldClouds(const CloudField& field, const Camera& camera,
                                        const HeapDrawing& drawing = {});
// The heaps of every tile within heapRange of the camera, in view or not, drifted into place
// and coarse: what shadows the ground (MODEL.md section 16), the same for every view from one
// eye.
std::vector<EllipsoidCloud> fieldShadowClouds(const CloudField& field, const Camera& camera,
                                              const HeapDrawing& drawing = {});

// The shafts of the field's precipitation under its heaps within heapRange of the camera whose
// box (ground to base) the camera may see, drifted into place (MODEL.md section 17): none
// without precipitation.
std::vector<RainShaft> fieldRainShafts(const CloudField& field, const Camera& camera,
                                       const HeapDrawing& drawing = {});
// The shaft under one heap of the field standing on `base` (world frame) at `size` times the
// typical radius: a share of its radius wide, downwind of its middle with the shear.
RainShaft heapRainShaft(const CloudField& field, glm::dvec3 base, double size = 1.0);

}  // namespace nephele
