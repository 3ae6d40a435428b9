#include "world/formations/weather.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "world/counter_random.h"
#include "world/textures/layer_texture.h"

namespace nephele {
namespace {

// How a stratiform type looks as a Gardner sky plane: base frequencies (radians per metre),
// term count, contrast offset T0, transition D, colour and shading.
struct PlaneLook {
  double fx1, fy1;
  int terms;
  double t0, transition, grey, ambient, texture_fraction;
};

// Indexed by CloudType; the convective types (cumulus, cumulonimbus) are drawn as heaps.
constexpr std::array<PlaneLook, kCloudTypeCount> kPlaneLooks{{
    {0, 0, 0, 0, 0, 0, 0, 0},                            // none
    {3.0e-3, 3.0e-3, 6, 0.5, 0.20, 0.92, 0.60, 0.50},    // altocumulus: mid-level cells
    {1.0e-3, 0.8e-3, 5, 2.0, 0.30, 0.75, 0.65, 0.35},    // altostratus: grey sheet
    {8.0e-3, 8.0e-3, 6, 0.5, 0.30, 1.00, 0.70, 0.50},    // cirrocumulus: small ripples
    {0.3e-3, 0.3e-3, 4, 1.0, 0.80, 1.00, 0.75, 0.30},    // cirrostratus: thin veil
    {0.5e-3, 0.25e-3, 7, 0.25, 0.50, 1.00, 0.70, 0.60},  // cirrus: streaks
    {0, 0, 0, 0, 0, 0, 0, 0},                            // cumulonimbus (heaps)
    {0, 0, 0, 0, 0, 0, 0, 0},                            // cumulus (heaps)
    {3.0e-3, 2.5e-3, 5, 3.0, 0.05, 0.45, 0.70, 0.40},    // nimbostratus: dark, uniform
    {2.0e-3, 1.6e-3, 6, 0.8, 0.15, 0.80, 0.60, 0.55},    // stratocumulus: large lumps
    {4.0e-3, 3.0e-3, 5, 2.0, 0.22, 0.78, 0.65, 0.45},    // stratus: low grey deck
}};

constexpr std::array<std::string_view, kCloudTypeCount> kNames{
    "none",         "altocumulus", "altostratus",  "cirrocumulus",  "cirrostratus", "cirrus",
    "cumulonimbus", "cumulus",     "nimbostratus", "stratocumulus", "stratus"};

// Texture values on a grid over one period, sorted.
std::vector<double> sortedSamples(const LayerTextureSpec& spec) {
  constexpr int kGrid = 96;  // samples per period axis
  const LayerTexture texture(spec);
  const glm::dvec2 period = texture.period();
  std::vector<double> values;
  values.reserve(kGrid * kGrid);
  for (int j = 0; j < kGrid; ++j)
    for (int i = 0; i < kGrid; ++i)
      values.push_back(
          texture.value({(i + 0.5) / kGrid * period.x, (j + 0.5) / kGrid * period.y}, 0.0));
  std::sort(values.begin(), values.end());
  return values;
}

double positiveFraction(const LayerTextureSpec& spec) {
  const std::vector<double> values = sortedSamples(spec);
  const auto zeros = std::upper_bound(values.begin(), values.end(), 0.0) - values.begin();
  return 1.0 - double(zeros) / double(values.size());
}

bool isConvective(CloudType type) {
  return type == CloudType::kCumulus || type == CloudType::kCumulonimbus;
}

CloudLayer planeLayer(const WeatherLayer& w, const std::string& name, std::uint64_t seed) {
  const PlaneLook& look = kPlaneLooks[std::size_t(w.type)];
  CloudLayer layer;
  layer.name = name;
  layer.altitude_m = w.base_m;  // the plane is the cloud base, which is what is seen from below
  layer.colour = glm::dvec3(look.grey);
  layer.transition = look.transition;
  layer.shading.ambient = look.ambient;
  layer.shading.texture_fraction = look.texture_fraction;
  layer.texture.source = TextureSource::kGardner;
  layer.texture.gardner.fx1 = look.fx1;
  layer.texture.gardner.fy1 = look.fy1;
  layer.texture.gardner.terms = look.terms;
  layer.texture.gardner.t0 = look.t0;
  layer.texture.seed = seed;
  // Gardner's T is zero wherever a sum of sines is negative, which caps the coverage any T1
  // can give; raise T0 (fewer zeros, less contrast) until the asked coverage is within reach.
  constexpr double kMaxT0 = 8.0;
  while (w.coverage < 1.0 && layer.texture.gardner.t0 < kMaxT0 &&
         positiveFraction(layer.texture) < w.coverage + 0.02)
    layer.texture.gardner.t0 += 0.25;
  layer.threshold = thresholdForCoverage(layer.texture, w.coverage);
  return layer;
}

// Heaps over a disc around `centre`, as many as cover `coverage` of it (at most kMaxHeaps),
// each as wide as about 1.2 times the layer's thickness.
std::vector<EllipsoidCloud> heapField(const WeatherLayer& w, const std::string& prefix,
                                      glm::dvec2 centre, std::uint64_t seed) {
  const bool cb = w.type == CloudType::kCumulonimbus;
  const double width = std::clamp(1.2 * w.thickness_m, 200.0, 8000.0);
  const double radius = WeatherLimits::kFieldRadius;
  const double footprint = 0.25 * width * width;  // (w/2)^2; the disc areas' pi cancels
  const int count = w.coverage <= 0.0
                        ? 0
                        : std::clamp(int(std::lround(w.coverage * radius * radius / footprint)), 1,
                                     WeatherLimits::kMaxHeaps);
  std::vector<EllipsoidCloud> out;
  for (int i = 0; i < count; ++i) {
    // Uniform over the disc: radius from the square root of a uniform draw.
    const double r = radius * std::sqrt(unitFromBits(hashCounters(seed, 1, std::uint64_t(i))));
    const double a = 2.0 * std::numbers::pi * unitFromBits(hashCounters(seed, 2, std::uint64_t(i)));
    const glm::dvec3 base(centre + r * glm::dvec2(std::cos(a), std::sin(a)), w.base_m);
    EllipsoidCloud cloud;
    cloud.name = prefix + "/heap" + std::to_string(i);
    cloud.colour = glm::dvec3(cb ? 0.7 : 1.0);
    cloud.texture.seed = hashCounters(seed, 3, std::uint64_t(i));
    cloud.ellipsoids = cumulusEllipsoids(cb ? 48 : 27, base, width, cloud.texture.seed);
    out.push_back(std::move(cloud));
  }
  return out;
}

}  // namespace

std::string_view cloudTypeName(CloudType type) {
  const int i = int(type);
  return i >= 0 && i < kCloudTypeCount ? kNames[std::size_t(i)] : "unknown";
}

WeatherClouds weatherClouds(const WeatherLayer& weather, const std::string& prefix,
                            glm::dvec2 field_centre, std::uint64_t seed) {
  WeatherClouds out;
  if (weather.type == CloudType::kNone || weather.coverage <= 0.0) return out;
  if (isConvective(weather.type))
    out.clouds = heapField(weather, prefix, field_centre, seed);
  else
    out.layers.push_back(planeLayer(weather, prefix, seed));
  return out;
}

double thresholdForCoverage(const LayerTextureSpec& spec, double coverage) {
  const std::vector<double> values = sortedSamples(spec);
  const double c = std::clamp(coverage, 0.0, 1.0);
  if (c >= 1.0) return values.front() - 1e-3;
  if (c <= 0.0) return values.back() + 1e-3;
  return values[std::size_t(std::floor((1.0 - c) * double(values.size())))];
}

}  // namespace nephele
