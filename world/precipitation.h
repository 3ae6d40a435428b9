#pragma once
// Precipitation and obscurants (MODEL.md section 17): rain, snow, sleet, hail, sand and dust as
// a medium filling a slab of air or a shaft under a heap, of an extinction set by the rate (or by
// the visibility a host gives), seen in its own colour like the ground fog. CIGI 3.3's Weather
// Control layers 4 to 9 are these six kinds in this order.
#include <array>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "world/sky.h"

namespace nephele {

struct Scene;
struct HeapDrawing;

enum class PrecipitationKind { kNone, kRain, kSnow, kSleet, kHail, kSand, kDust };
inline constexpr int kPrecipitationKindCount = 7;
inline constexpr std::array<std::string_view, kPrecipitationKindCount> kPrecipitationNames{
    "none", "rain", "snow", "sleet", "hail", "sand", "dust"};

struct Precipitation {
  PrecipitationKind kind = PrecipitationKind::kNone;
  // Liquid-water-equivalent rate, mm/h (rain, snow, sleet, hail); sand and dust have none.
  double rate_mm_h = 0.0;
  // The visibility inside it, metres; 0 takes the rate's (sand and dust need one).
  double visibility_m = 0.0;
  bool operator==(const Precipitation&) const = default;
};

// The CIGI severity 0 to 5 as a rate: 0.5, 1, 2.5, 8, 25 and 75 mm/h, from drizzle through the
// WMO's light (below 2.5), moderate (2.5 to 7.6), heavy (above 7.6) and violent (above 50).
double rateForSeverity(int severity);
// Sand and dust by severity: 5,000, 2,000, 1,000, 500, 200 and 100 m of visibility (a
// sandstorm below 1 km, a severe one below 200 m, in the WMO's terms).
double obscurantVisibilityForSeverity(int severity);

// The extinction per metre: from the visibility when one is given (Koschmieder, 2 %), else
// from the rate R (mm/h) over a drop-size distribution, each particle taking twice its
// cross-section from the beam (extinction efficiency 2 for particles far larger than the
// wavelength): rain, sleet and hail 0.365e-3 R^0.63 (Marshall and Palmer 1948), snow
// 3.3e-3 R^0.57 (Gunn and Marshall 1958, its melted diameters widened to flakes of density
// 0.1). 0 for none, or for sand and dust without a visibility.
double precipitationExtinction(const Precipitation& p);
// Its visibility, metres (infinite where the extinction is 0).
double precipitationVisibility(const Precipitation& p);
// The colour it is seen in (linear RGB): grey for rain, white for snow, ochre for sand.
glm::dvec3 precipitationColour(PrecipitationKind kind);

// The rain shafts a view holds at most: those nearest the camera (rainShaftsInView). The GL's
// uniform arrays hold this many.
inline constexpr int kMaxRainShafts = 16;

struct PrecipitationMedia {
  std::vector<Fog> slabs;
  std::vector<RainShaft> shafts;
  bool empty() const { return slabs.empty() && shafts.empty(); }
};

// The media the scene's precipitation fills, at the visibility above and in the kind's colour:
// - a stratiform layer rains from its base to the ground, and a layer without clouds (CIGI's
//   layers 4 to 9) fills its own base to top, each a Fog slab with no band; a region's slab is
//   not drawn;
// - a layer of heaps rains in a shaft under each heap (fieldRainShafts): those of the scene's
//   fields (rainShaftsInView, with `heaps`' range) and those already drawn out of them
//   (Scene::rain_shafts, withFieldClouds).
PrecipitationMedia precipitationMedia(const Scene& scene, const HeapDrawing& heaps);
// The same with the automatic heap range.
PrecipitationMedia precipitationMedia(const Scene& scene);

// The shafts under the heaps of the scene's fields within heap range (HeapDrawing) whose box
// the camera may see, the kMaxRainShafts nearest it.
std::vector<RainShaft> rainShaftsInView(const Scene& scene, const HeapDrawing& heaps);

// Whether the scene has any precipitation to draw (without walking its fields' tiles).
bool hasPrecipitation(const Scene& scene);
// Which of its media precipitationMedia may give (without walking the fields' tiles): slabs of
// stratiform layers, shafts under heaps.
bool hasPrecipitationSlabs(const Scene& scene);
bool hasPrecipitationShafts(const Scene& scene);

}  // namespace nephele
