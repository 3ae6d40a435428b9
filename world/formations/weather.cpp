#include "world/formations/weather.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>

#include "world/counter_random.h"
#include "world/formations/genus.h"
#include "world/scene.h"
#include "world/shading.h"
#include "world/textures/layer_texture.h"

namespace nephele {
namespace {

// Every genus's texture breaks Gardner's lattice by rotation (PlaneLook) and by scale, each
// component spread over half an octave either side of its term's frequency: the highest
// secondary autocorrelation peak of the drawn coverage stays near 0.2 (cirrus 0.25) for any
// seed, against 0.44 to 0.85 on Gardner's lattice (docs/ACCURACY.md, "Knobs of the model").
constexpr double kJitterOctaves = 0.5;

// Seeded points spread over 24 x 24 texture periods (the texture has no period once rotated).
constexpr int kSamples = 16384;
glm::dvec2 samplePoint(int k, glm::dvec2 period) {
  constexpr double kSpan = 24.0;  // periods
  return kSpan * period *
         glm::dvec2(unitFromBits(hashCounters(0x436f76ull, std::uint64_t(k), 0)),
                    unitFromBits(hashCounters(0x436f76ull, std::uint64_t(k), 1)));
}

// Texture values at the sample points, sorted.
std::vector<double> sortedSamples(const LayerTextureSpec& spec) {
  LayerTextureSpec still = spec;
  still.drift_velocity = still.drift_offset_m = glm::dvec2(0.0);
  const LayerTexture texture(still);
  std::vector<double> values;
  values.reserve(kSamples);
  for (int k = 0; k < kSamples; ++k)
    values.push_back(texture.value(samplePoint(k, texture.period()), 0.0));
  std::sort(values.begin(), values.end());
  return values;
}

// Gardner's two sums at the sample points, without T0. T0 only offsets both sums and sets k
// (MODEL.md section 2), so the sorted values for any T0 follow from one evaluation of the
// sines: planes() raises T0 step by step.
class GardnerSamples {
 public:
  explicit GardnerSamples(const GardnerTextureParams& params) : params_(params) {
    params_.t0 = 0.0;
    const GardnerTexture texture(params_);
    sums_.reserve(kSamples);
    for (int k = 0; k < kSamples; ++k)
      sums_.push_back(texture.planarSums(samplePoint(k, texture.period())));
  }
  std::vector<double> sorted(double t0) const {
    GardnerTextureParams p = params_;
    p.t0 = t0;
    const double k = GardnerTexture(p).normalisation();
    std::vector<double> values;
    values.reserve(sums_.size());
    for (const glm::dvec2& s : sums_) values.push_back(textureFromSums(s.x + t0, s.y + t0, k));
    std::sort(values.begin(), values.end());
    return values;
  }
  // The fraction of the samples where T > 0 for this T0: where both sums are positive.
  double positiveFraction(double t0) const {
    const auto positive = std::count_if(sums_.begin(), sums_.end(), [t0](const glm::dvec2& s) {
      return s.x + t0 > 0.0 && s.y + t0 > 0.0;
    });
    return double(positive) / double(sums_.size());
  }

 private:
  GardnerTextureParams params_;  // with T0 = 0
  std::vector<glm::dvec2> sums_;
};

// Every parameter of a Gardner texture, in full precision: the key of the caches below.
std::string gardnerKey(const GardnerTextureParams& p) {
  std::ostringstream key;
  key.precision(17);
  key << p.terms << '/' << p.fx1 << '/' << p.fy1 << '/' << p.t0 << '/' << p.seeded_phases << '/'
      << p.seed << '/' << p.rotation_deg << '/' << p.jitter_octaves << '/' << p.amplitude_ratio;
  return key.str();
}

// GardnerSamples of a look, computed once per process and shared by every layer of it (a
// dataset draws new skies for every sample, a daemon on every set_weather). The calibration
// does not depend on the layer's seed: it reads the look's texture with seed 0 (the layer's
// seed enters in LayerTexture), since over 24 x 24 periods a seed's phases, turns and scales
// within each octave leave the distribution of values as it is; realism_bench's drawn
// coverage is within 0.03 of the asked for every stratiform genus. Any thread.
std::shared_ptr<const GardnerSamples> lookSamples(const GardnerTextureParams& params) {
  GardnerTextureParams p = params;
  p.seed = 0;
  p.t0 = 0.0;
  const std::string key = gardnerKey(p);
  static std::mutex mutex;
  static std::map<std::string, std::shared_ptr<const GardnerSamples>> cache;
  std::lock_guard lock(mutex);
  if (cache.size() >= 256) cache.clear();  // a bound, should a caller vary a look continuously
  std::shared_ptr<const GardnerSamples>& entry = cache[key];
  if (!entry) entry = std::make_shared<const GardnerSamples>(p);
  return entry;
}

// thresholdForCoverage on the texture's sorted samples.
double thresholdFromSamples(const std::vector<double>& values, double transition, int planes,
                            double coverage, bool veil = false) {
  // Through k identical planes of opacity a each, 1 - (1 - a)^k >= 1/2 where
  // a >= 1 - 2^(-1/k); eq. 9 gives a = (T - T1) / D, so T >= T1 + a D.
  const double level = 1.0 - std::pow(0.5, 1.0 / std::max(planes, 1));
  const double shift = level * transition;
  const double c = std::clamp(coverage, 0.0, 1.0);
  // D = 0 is a hard threshold: opaque where T > T1.
  const double margin = 1e-6 + 1e-3 * transition;
  // A full cover is drawn opaque (a = 1 on every plane), not merely at opacity 1/2; a veil
  // just above opacity 1/2 where it is thinnest.
  if (c >= 1.0) return values.front() - (veil ? level + 0.05 : 1.0) * transition - margin;
  if (c <= 0.0) return values.back() - shift + margin;
  // A coverage within rounding of 0 (1 - c == 1) takes the last sample, not one past it.
  const auto index = std::size_t(std::floor((1.0 - c) * double(values.size())));
  return values[std::min(index, values.size() - 1)] - shift;
}

// The planes of a stratiform layer, or the deck under heaps, covering `coverage`.
std::vector<CloudLayer> planes(const WeatherLayer& w, const PlaneLook& look, double coverage,
                               const std::string& prefix, std::uint64_t seed) {
  CloudLayer layer;
  layer.colour = glm::dvec3(look.grey);
  layer.transition = look.transition;
  layer.shading.ambient = look.ambient;
  layer.shading.texture_fraction = look.texture_fraction;
  LayerTextureSpec& t = layer.texture;
  t.source = TextureSource::kGardner;
  t.gardner.fx1 = look.fx1;
  t.gardner.fy1 = look.fy1;
  t.gardner.terms = look.terms;
  t.gardner.amplitude_ratio = look.amplitude_ratio;
  t.gardner.t0 = look.t0;
  t.gardner.rotation_deg = look.rotation_deg;
  t.gardner.jitter_octaves = kJitterOctaves;
  t.seed = seed;
  // Gardner's T is zero wherever a sum of sines is negative, so no threshold separates
  // coverages between the positive fraction and 1; raise T0 (less contrast) until the asked
  // coverage is below the positive fraction.
  constexpr double kMaxT0 = 8.0;
  const std::shared_ptr<const GardnerSamples> sums = lookSamples(t.gardner);
  while (coverage < 1.0 && t.gardner.t0 < kMaxT0 &&
         sums->positiveFraction(t.gardner.t0) < coverage + 0.02)
    t.gardner.t0 += 0.25;
  const std::vector<double> samples = sums->sorted(t.gardner.t0);
  const int count = look.planes;
  layer.threshold = thresholdFromSamples(samples, layer.transition, count, coverage, look.veil);
  layer.region = w.region;
  std::vector<CloudLayer> out;
  for (int k = 0; k < count; ++k) {
    CloudLayer plane = layer;
    plane.name = k == 0 ? prefix : prefix + "/" + std::to_string(k);
    // A stack brightens upwards: the genus's grey at the base, white at the sunlit top.
    if (count > 1) plane.colour = glm::dvec3(look.grey + (1.0 - look.grey) * k / (count - 1));
    plane.altitude_m = w.base_m + (count == 1 ? 0.0 : w.thickness_m * k / (count - 1));
    out.push_back(plane);
  }
  return out;
}

}  // namespace

// Scud (MODEL.md section 10): one plane of ragged fragments under the base, covering
// `w.scud`: stratus fractus, the stratus look with features a third the size, a darker grey
// and edges twice as sharp, half way through the transition band below the base, or a sixth
// of the thickness (50 to 300 m) without one.
std::vector<CloudLayer> scudPlane(const WeatherLayer& w, const std::string& prefix,
                                  std::uint64_t seed) {
  if (!(w.scud > 0.0)) return {};
  PlaneLook look = genus(CloudType::kStratus).planes;
  look.planes = 1;
  look.fx1 *= 3.0, look.fy1 *= 3.0;
  look.grey *= 0.65;
  look.transition *= 0.5;
  WeatherLayer under = w;
  const double below = w.transition_band_m > 0.0 ? 0.5 * w.transition_band_m
                                                 : std::clamp(w.thickness_m / 6.0, 50.0, 300.0);
  under.base_m = std::max(w.base_m - below, 0.5 * w.base_m);
  under.thickness_m = 0.0;
  return planes(under, look, std::min(w.scud, 1.0), prefix + "/scud",
                hashCounters(seed, 0x53637564ull));
}

WeatherClouds weatherClouds(const WeatherLayer& w, const std::string& prefix, std::uint64_t seed) {
  WeatherClouds out;
  if (w.type == CloudType::kNone || !(w.coverage > 0.0) || !weatherLayerError(w).empty())
    return out;
  const Genus& g = genus(w.type);
  const PlaneLook& look = g.planes;
  const double coverage = std::min(w.coverage, 1.0);
  const std::vector<CloudLayer> scud = scudPlane(w, prefix, seed);
  if (!g.heaps) {
    out.layers = planes(w, look, coverage, prefix, seed);
    // The layer's slab rides on its base plane (MODEL.md section 5, the in-layer veil).
    out.layers.front().in_layer = {
        w.base_m + w.thickness_m, w.transition_band_m,
        w.visibility_m > 0.0 ? w.visibility_m : look.in_layer_visibility_m};
    out.layers.insert(out.layers.end(), scud.begin(), scud.end());
    return out;
  }
  // Heaps cover up to CloudField::kMaxFieldCoverage; a deck independent of them covers the
  // rest, so that together 1 - (1 - heaps) (1 - deck) is the coverage asked.
  CloudField field;
  field.name = prefix + "/heaps";
  field.type = w.type;
  field.base_m = w.base_m;
  field.thickness_m = w.thickness_m;
  field.coverage = std::min(coverage, CloudField::kMaxFieldCoverage);
  field.seed = hashCounters(seed, 0x48656170ull);
  field.region = w.region;
  field.clusters = w.clusters;
  field.precipitation = w.precipitation;
  out.fields.push_back(field);
  if (coverage > field.coverage) {
    const double deck = coverage >= 1.0 ? 1.0 : 1.0 - (1.0 - coverage) / (1.0 - field.coverage);
    out.layers = planes(w, look, deck, prefix + "/deck", seed);
  }
  out.layers.insert(out.layers.end(), scud.begin(), scud.end());
  return out;
}

namespace {
// Whether height z lies in the slab of layer `l` (a stratiform layer's base plane) or its bands.
bool inSlab(const CloudLayer& l, double z) {
  const CloudLayer::InLayer& in = l.in_layer;
  return in.visibility_m > 0.0 && z >= l.altitude_m - in.band_m && z <= in.top_m + in.band_m;
}
}  // namespace

bool eyeInLayer(const Scene& scene) {
  return std::any_of(scene.layers.begin(), scene.layers.end(),
                     [&](const CloudLayer& l) { return inSlab(l, scene.camera.position.z); });
}

std::optional<Fog> inLayerVeil(const Scene& scene) {
  if (!eyeInLayer(scene)) return std::nullopt;
  const glm::dvec3 eye = scene.camera.position;
  const glm::dvec2 xy(eye);
  const double lit_from_above = std::max(0.0, sunDirection(scene.sun).z);
  std::optional<Fog> veil;
  double densest = 0.0;
  for (const CloudLayer& l : scene.layers) {
    if (!inSlab(l, eye.z)) continue;
    const CloudLayer::InLayer& in = l.in_layer;
    // The layer's slab is as dense as the cloud its base plane draws over the eye (eq. 9, its
    // region's threshold)...
    Fog f;
    f.bottom_m = l.altitude_m;
    f.top_m = in.top_m;
    f.band_m = in.band_m;
    // ... and as the band thins it at the eye's height, so that it fades out as the eye
    // climbs out of the band (a layer without one has a sharp base and top).
    const LayerTexture texture(l.texture);
    const double t = texture.value(xy, scene.time_s);
    const double t1 = regionThreshold(l.threshold, layerRegionWeight(l, xy, scene.time_s, xy));
    const double cover = (1.0 - skyPlaneTranslucence(t, t1, l.transition)) * fogDensity(f, eye.z);
    if (!(cover > densest)) continue;  // where layers overlap, the densest
    densest = cover;
    f.visibility_m = in.visibility_m / cover;
    f.colour = gardnerIntensity(l.shading, lit_from_above, 0.0, t) * l.colour * scene.sun.colour;
    veil = f;
  }
  return veil;
}

std::uint64_t weatherSeed(std::uint64_t scene_seed, int layer) {
  return hashCounters(scene_seed, 0x57656174686572ull, std::uint64_t(layer));
}

WeatherLayer typicalWeatherLayer(CloudType type, double coverage) {
  const Genus& g = genus(type);
  return {type, g.typical_base_m, g.typical_thickness_m, coverage, {}, {}, {}};
}

double thresholdForCoverage(const LayerTextureSpec& spec, double transition, int planes,
                            double coverage) {
  return thresholdFromSamples(sortedSamples(spec), transition, planes, coverage);
}

void calibrateFarCover(const LayerTextureSpec& spec, double transition, FarCover& far) {
  // The thresholds depend on the texture and the transition alone, and far decks take one of a
  // few textures (farDeck): computed once per process for each, not sorting 16,384 texture
  // values again for each dataset sample's new field (its own cover and seed). Any thread.
  std::ostringstream key_text;
  key_text.precision(17);
  key_text << spec.seed << '/' << transition << '/' << gardnerKey(spec.gardner);
  const std::string key = key_text.str();
  using Thresholds = std::array<double, FarCover::kSteps + 1>;
  static std::mutex mutex;
  static std::map<std::string, Thresholds> cache;
  const bool keyed = spec.source == TextureSource::kGardner;  // the key names Gardner's only
  if (keyed) {
    std::lock_guard lock(mutex);
    if (auto it = cache.find(key); it != cache.end()) {
      std::copy(it->second.begin(), it->second.end(), far.threshold);
      return;
    }
  }
  const std::vector<double> samples = sortedSamples(spec);
  Thresholds thresholds;
  for (int k = 0; k <= FarCover::kSteps; ++k)
    thresholds[k] = thresholdFromSamples(samples, transition, 1, double(k) / FarCover::kSteps);
  std::copy(thresholds.begin(), thresholds.end(), far.threshold);
  if (!keyed) return;
  std::lock_guard lock(mutex);
  if (cache.size() >= 256) cache.clear();  // a bound, should a caller vary a texture continuously
  cache[key] = thresholds;
}

}  // namespace nephele
