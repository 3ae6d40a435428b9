#include "world/precipitation.h"

#include <algorithm>
#include <cmath>

#include "world/formations/genus.h"
#include "world/scene.h"

namespace nephele {

double rateForSeverity(int severity) {
  constexpr double kRates[] = {0.5, 1.0, 2.5, 8.0, 25.0, 75.0};
  return kRates[std::clamp(severity, 0, 5)];
}

double obscurantVisibilityForSeverity(int severity) {
  constexpr double kVisibility[] = {5000.0, 2000.0, 1000.0, 500.0, 200.0, 100.0};
  return kVisibility[std::clamp(severity, 0, 5)];
}

double precipitationExtinction(const Precipitation& p) {
  if (p.kind == PrecipitationKind::kNone) return 0.0;
  if (p.visibility_m > 0.0) return extinctionForVisibility(p.visibility_m);
  if (!(p.rate_mm_h > 0.0)) return 0.0;
  // pi N0 / Lambda^3 for N(D) = N0 exp(-Lambda D), D in mm, N0 per m^3 per mm: twice the
  // cross-section pi D^2 / 4 summed over the drops, in m^2 per m^3.
  switch (p.kind) {
    case PrecipitationKind::kSnow:  // N0 = 3800 R^-0.87, Lambda = 2.55 R^-0.48; flakes 4.6 x
      return 3.3e-3 * std::pow(p.rate_mm_h, 0.57);
    case PrecipitationKind::kRain:
    case PrecipitationKind::kSleet:
    case PrecipitationKind::kHail:  // N0 = 8000, Lambda = 4.1 R^-0.21
      return 0.365e-3 * std::pow(p.rate_mm_h, 0.63);
    default:
      return 0.0;
  }
}

double precipitationVisibility(const Precipitation& p) {
  return visibilityForExtinction(precipitationExtinction(p));
}

glm::dvec3 precipitationColour(PrecipitationKind kind) {
  switch (kind) {
    case PrecipitationKind::kRain:
      return {0.45, 0.48, 0.52};
    case PrecipitationKind::kSnow:
      return {0.80, 0.82, 0.85};
    case PrecipitationKind::kSleet:
      return {0.55, 0.58, 0.62};
    case PrecipitationKind::kHail:
      return {0.60, 0.62, 0.66};
    case PrecipitationKind::kSand:
      return {0.62, 0.50, 0.33};
    case PrecipitationKind::kDust:
      return {0.58, 0.52, 0.42};
    default:
      return {0.0, 0.0, 0.0};
  }
}

PrecipitationMedia precipitationMedia(const Scene& scene, const HeapDrawing& heaps) {
  PrecipitationMedia out;
  for (const auto& [key, w] : scene.weather) {
    const double visibility = precipitationVisibility(w.precipitation);
    // Heaps rain in shafts (their fields'), a region's slab is not drawn.
    if (key.region || !std::isfinite(visibility) || genus(w.type).heaps) continue;
    Fog f;
    const bool clouds = w.type != CloudType::kNone;
    f.bottom_m = clouds ? 0.0 : w.base_m;
    f.top_m = clouds ? w.base_m : w.base_m + w.thickness_m;
    f.visibility_m = visibility;
    f.colour = precipitationColour(w.precipitation.kind);
    out.slabs.push_back(f);
  }
  out.shafts = scene.rain_shafts;
  if (!scene.fields.empty()) {
    std::vector<RainShaft> more = rainShaftsInView(scene, heaps);
    out.shafts.insert(out.shafts.end(), more.begin(), more.end());
  }
  return out;
}

PrecipitationMedia precipitationMedia(const Scene& scene) {
  return precipitationMedia(scene, HeapDrawing{});
}

std::vector<RainShaft> rainShaftsInView(const Scene& scene, const HeapDrawing& heaps) {
  std::vector<RainShaft> out;
  for (const CloudField& field : scene.fields) {
    std::vector<RainShaft> shafts = fieldRainShafts(field, scene.camera, heaps);
    out.insert(out.end(), shafts.begin(), shafts.end());
  }
  const glm::dvec2 eye(scene.camera.position);
  auto distance = [&](const RainShaft& s) { return glm::length(s.centre - eye) - s.radius_m; };
  if (out.size() > std::size_t(kMaxRainShafts)) {
    std::nth_element(
        out.begin(), out.begin() + kMaxRainShafts, out.end(),
        [&](const RainShaft& a, const RainShaft& b) { return distance(a) < distance(b); });
    out.resize(std::size_t(kMaxRainShafts));
  }
  return out;
}

bool hasPrecipitation(const Scene& scene) {
  return hasPrecipitationSlabs(scene) || hasPrecipitationShafts(scene);
}

bool hasPrecipitationSlabs(const Scene& scene) {
  for (const auto& [key, w] : scene.weather)  // precipitationMedia's slabs
    if (precipitationExtinction(w.precipitation) > 0.0 && !key.region && !genus(w.type).heaps)
      return true;
  return false;
}

bool hasPrecipitationShafts(const Scene& scene) {
  if (!scene.rain_shafts.empty()) return true;
  for (const auto& [key, w] : scene.weather)
    if (precipitationExtinction(w.precipitation) > 0.0 && genus(w.type).heaps) return true;
  return false;
}

}  // namespace nephele
