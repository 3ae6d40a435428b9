#include "world/precipitation.h"

#include <algorithm>
#include <cmath>

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

std::vector<Fog> precipitationMedia(const Scene& scene) {
  std::vector<Fog> out;
  for (const auto& [key, w] : scene.weather) {
    const double visibility = precipitationVisibility(w.precipitation);
    if (key.region || !std::isfinite(visibility)) continue;
    Fog f;
    const bool clouds = w.type != CloudType::kNone;
    f.bottom_m = clouds ? 0.0 : w.base_m;
    f.top_m = clouds ? w.base_m : w.base_m + w.thickness_m;
    f.visibility_m = visibility;
    f.colour = precipitationColour(w.precipitation.kind);
    out.push_back(f);
  }
  return out;
}

}  // namespace nephele
