#include "dataset/dataset.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "protocol/messages.h"
#include "renderer/reference/reference_renderer.h"
#include "world/counter_random.h"
#include "world/formations/weather.h"
#include "world/limits.h"

namespace nephele {
namespace {

using nlohmann::json;

// Independent streams of one sample's draws: changing how many targets a sample has never
// moves its sky, and the reverse.
// Each draw its own stream, so that a new kind of draw leaves every existing one as it was.
enum Stream : std::uint64_t { kSky = 1, kSun, kFog, kCamera, kTargets, kInfrared, kSea, kRain };

// Draws from (key, counter): the n-th number of a stream is a pure function of both.
class Draws {
 public:
  explicit Draws(std::uint64_t key) : key_(key) {}
  double unit() { return unitFromBits(hashCounters(key_, n_++)); }
  double in(Span s) { return s.lo + (s.hi - s.lo) * unit(); }
  int integer(Span s) {  // uniform over the integers lo..hi
    const int lo = int(std::lround(s.lo)), hi = int(std::lround(s.hi));
    return std::min(hi, lo + int(std::floor(unit() * (hi - lo + 1))));
  }

 private:
  std::uint64_t key_;
  std::uint64_t n_ = 0;
};

const char* shapeName(TargetShape shape) {
  return shape == TargetShape::kBox         ? "box"
         : shape == TargetShape::kEllipsoid ? "ellipsoid"
                                            : "mesh";
}

json vec3(glm::dvec3 v) {
  return json::array({v.x, v.y, v.z});
}

std::string spanError(const char* name, Span s) {
  if (!(s.lo <= s.hi)) return std::string(name) + ": the range's low end is above its high end";
  return "";
}

// One sample's draws of a stream.
Draws streamOf(std::uint64_t seed, Stream s) {
  return Draws(hashCounters(seed, s));
}

// The sample's weather layers, genus by genus, and rain from the lowest of them: in shafts
// under heaps, else from its base down (MODEL.md section 17), which the scene's weather holds.
void drawSky(const DatasetSpec& spec, std::uint64_t seed, SampleScene& out) {
  Draws sky = streamOf(seed, kSky);
  const int layers = spec.genera.empty() ? 0 : sky.integer(spec.layers);
  std::vector<WeatherLayer> weather(std::size_t(std::max(layers, 0)));
  for (WeatherLayer& w : weather) {
    w.type = spec.genera[std::min(spec.genera.size() - 1,
                                  std::size_t(sky.unit() * double(spec.genera.size())))];
    w.coverage = sky.in(spec.coverage);
    w.base_m = sky.in(spec.base);
    w.thickness_m = sky.in(spec.thickness);
  }
  Draws rain = streamOf(seed, kRain);
  std::optional<std::size_t> raining;
  if (rain.unit() < spec.rain_probability && layers > 0) {
    raining = 0;
    for (std::size_t k = 1; k < weather.size(); ++k)
      if (weather[k].base_m < weather[*raining].base_m) raining = k;
    weather[*raining].precipitation = {PrecipitationKind::kRain, rain.in(spec.rain_rate), 0.0};
  }
  Scene& scene = out.scene;
  json& record = out.record;
  record["layers"] = json::array();
  for (int k = 0; k < layers; ++k) {
    const WeatherLayer& w = weather[std::size_t(k)];
    const std::uint64_t layer_seed = weatherSeed(seed, k + 1);
    const WeatherClouds add = weatherClouds(w, "layer" + std::to_string(k + 1), layer_seed);
    scene.layers.insert(scene.layers.end(), add.layers.begin(), add.layers.end());
    scene.fields.insert(scene.fields.end(), add.fields.begin(), add.fields.end());
    if (raining == std::size_t(k)) scene.weather[{k + 1, std::nullopt}] = w;
    record["layers"].push_back({{"genus", std::string(cloudTypeName(w.type))},
                                {"coverage", w.coverage},
                                {"base_m", w.base_m},
                                {"thickness_m", w.thickness_m},
                                {"seed", std::to_string(layer_seed)}});
  }
  record["rain_mm_h"] = raining ? json(weather[*raining].precipitation.rate_mm_h) : json(nullptr);
}

void drawSea(const DatasetSpec& spec, std::uint64_t seed, SampleScene& out) {
  Draws water = streamOf(seed, kSea);
  if (!(water.unit() < spec.sea_probability)) {
    out.record["sea"] = nullptr;
    return;
  }
  Sea& sea = out.scene.sea.emplace();
  const double speed = water.in(spec.sea_wind);
  const double towards = glm::radians(water.in(spec.sea_wind_direction));
  sea.wind = speed * glm::dvec2(std::sin(towards), std::cos(towards));
  sea.clarity = water.in(spec.sea_clarity);
  sea.whitecaps = spec.sea_whitecaps;
  sea.seed = hashCounters(seed, kSea);
  out.record["sea"] = {{"wind", json::array({sea.wind.x, sea.wind.y})},
                       {"clarity", sea.clarity},
                       {"whitecaps", sea.whitecaps},
                       {"significant_height_m", SeaSurface(sea).significantHeight()}};
}

void drawSun(const DatasetSpec& spec, std::uint64_t seed, SampleScene& out) {
  Draws sun = streamOf(seed, kSun);
  Scene& scene = out.scene;
  scene.sun.azimuth_deg = sun.in(spec.sun_azimuth);
  scene.sun.elevation_deg = sun.in(spec.sun_elevation);
  out.record["sun"] = {{"azimuth_deg", scene.sun.azimuth_deg},
                       {"elevation_deg", scene.sun.elevation_deg}};
}

void drawFog(const DatasetSpec& spec, std::uint64_t seed, SampleScene& out) {
  Draws fog = streamOf(seed, kFog);
  if (!(fog.unit() < spec.fog_probability)) {
    out.record["fog"] = nullptr;
    return;
  }
  Fog& f = out.scene.fog.emplace();
  f.top_m = fog.in(spec.fog_top);
  f.visibility_m = fog.in(spec.fog_visibility);
  out.record["fog"] = {{"top_m", f.top_m}, {"visibility_m", f.visibility_m}};
}

void drawCamera(const DatasetSpec& spec, std::uint64_t seed, SampleScene& out) {
  Draws cam = streamOf(seed, kCamera);
  Camera& camera = out.scene.camera;
  camera.width = spec.width;
  camera.height = spec.height;
  camera.position = {0.0, 0.0, cam.in(spec.altitude)};
  camera.orientation = {cam.in(spec.heading), cam.in(spec.pitch), cam.in(spec.roll)};
  camera.vfov_deg = cam.in(spec.vfov);
  out.record["camera"] = cameraJson(frameInfo(camera, 0.0));
}

// Places targets along rays of the sample's camera: a pixel and a distance per instance;
// those meant to be behind cloud (or in the clear) try up to kPlacementAttempts placements
// for one whose centre ray says so.
class TargetPlacer {
 public:
  static constexpr int kPlacementAttempts = 64;
  TargetPlacer(const DatasetSpec& spec, const Scene& scene, Draws& draw)
      : spec_(spec),
        scene_(scene),
        camera_(scene.camera),
        basis_(viewBasis(scene.camera)),
        cloudy_(!scene.layers.empty() || !scene.fields.empty()),
        draw_(draw) {}

  struct Placement {
    double transmittance = 1.0;  // along the ray to the target's centre
    bool met = false;            // behind cloud or in the clear, as asked
  };
  Placement place(const TargetClass& cls, bool behind, Target& target) {
    Placement placed;
    for (int attempt = 0; attempt < kPlacementAttempts && !placed.met; ++attempt) {
      const bool last = attempt + 1 == kPlacementAttempts;
      const double px = draw_.in({0.1 * spec_.width, 0.9 * spec_.width});
      const double py = draw_.in({0.1 * spec_.height, 0.9 * spec_.height});
      const glm::dvec3 d = glm::normalize(rayDirection(basis_, camera_, px, py));
      Span range = cls.distance;
      if (cls.afloat) {
        // Where the ray meets the plane of its centre, if that lies within its range.
        const double at = (0.3 * cls.size.z - camera_.position.z) / d.z;
        if (!(d.z < 0.0 && at >= range.lo && at <= range.hi) && !last) continue;
        range = {at, at};
      }
      if (behind && cloudy_) {
        if (transmittanceTo(d, range.hi) >= 0.9 && !last) continue;
        range.lo = nearestBehindCloud(d, range);
      }
      const double distance = draw_.in(range);
      const glm::dvec3 centre = camera_.position + distance * d;
      if (centre.z < 0.0 && !last) continue;  // below the ground
      target.centre = centre;
      placed.transmittance = transmittanceTo(d, distance);
      placed.met = behind ? placed.transmittance < 0.9 : placed.transmittance > 0.99;
    }
    return placed;
  }

 private:
  double transmittanceTo(glm::dvec3 d, double distance) {
    if (!cloudy_) return 1.0;
    if (!probe_) probe_.emplace(scene_, spec_.heaps);
    return probe_->transmittance(d, distance);
  }
  // Behind cloud: only as far as the cloud along this ray allows. Transmittance falls with
  // distance; the nearest distance where it is below 0.9 is found by bisection, and the
  // target drawn between it and the far end.
  double nearestBehindCloud(glm::dvec3 d, Span range) {
    if (transmittanceTo(d, range.lo) < 0.9) return range.lo;
    double lo = range.lo, hi = range.hi;
    for (int k = 0; k < 12; ++k) {
      const double mid = 0.5 * (lo + hi);
      (transmittanceTo(d, mid) < 0.9 ? hi : lo) = mid;
    }
    return hi;
  }

  const DatasetSpec& spec_;
  const Scene& scene_;
  const Camera& camera_;
  const ViewBasis basis_;
  const bool cloudy_;
  Draws& draw_;
  std::optional<CloudProbe> probe_;
};

// Every class's targets, with their temperatures from their own stream, so that both bands
// place the same targets.
void drawTargets(const DatasetSpec& spec, std::uint64_t seed, SampleScene& out) {
  Draws draw = streamOf(seed, kTargets);
  Draws heat = streamOf(seed, kInfrared);
  out.infrared = spec.infrared;
  TargetPlacer placer(spec, out.scene, draw);
  json& record = out.record;
  record["targets"] = json::array();
  for (std::size_t c = 0; c < spec.targets.size(); ++c) {
    const TargetClass& cls = spec.targets[c];
    const int count = draw.integer(cls.count);
    for (int i = 0; i < count; ++i) {
      const bool behind = draw.unit() < spec.occluded_fraction;
      Target target;
      target.name = cls.name + std::to_string(i + 1);
      target.shape = cls.shape;
      target.mesh = cls.mesh;
      target.size = cls.size;
      target.colour = cls.colour;
      target.orientation = {draw.in(cls.heading), draw.in(cls.pitch), draw.in(cls.roll)};
      const TargetPlacer::Placement placed = placer.place(cls, behind, target);
      const double temperature = heat.in(cls.temperature);
      out.infrared.target_temperatures.push_back(temperature);
      out.scene.targets.push_back(target);
      out.target_class.push_back(int(c));
      record["targets"].push_back({{"category", cls.name},
                                   {"shape", shapeName(cls.shape)},
                                   {"mesh", cls.mesh_path},
                                   {"centre", vec3(target.centre)},
                                   {"heading_deg", target.orientation.heading_deg},
                                   {"pitch_deg", target.orientation.pitch_deg},
                                   {"roll_deg", target.orientation.roll_deg},
                                   {"size", vec3(target.size)},
                                   {"placed", behind ? "behind cloud" : "clear"},
                                   {"placement_met", placed.met},
                                   {"centre_transmittance", placed.transmittance},
                                   {"temperature_k", temperature}});
    }
  }
}

}  // namespace

std::string datasetSpecError(const DatasetSpec& spec) {
  if (spec.genera.empty() && spec.layers.hi > 0.0)
    return "sky.genera: empty, yet sky.layers asks for layers";
  using Named = std::pair<const char*, Span>;
  const Named spans[] = {{"sky.layers", spec.layers},
                         {"sky.coverage", spec.coverage},
                         {"sky.base", spec.base},
                         {"sky.thickness", spec.thickness},
                         {"sun.azimuth", spec.sun_azimuth},
                         {"sun.elevation", spec.sun_elevation},
                         {"fog.top", spec.fog_top},
                         {"fog.visibility", spec.fog_visibility},
                         {"sky.rain_rate", spec.rain_rate},
                         {"sea.wind", spec.sea_wind},
                         {"sea.direction", spec.sea_wind_direction},
                         {"sea.clarity", spec.sea_clarity},
                         {"camera.altitude", spec.altitude},
                         {"camera.heading", spec.heading},
                         {"camera.pitch", spec.pitch},
                         {"camera.roll", spec.roll},
                         {"camera.vfov", spec.vfov}};
  for (const auto& [name, s] : spans)
    if (std::string e = spanError(name, s); !e.empty()) return e;
  for (const TargetClass& c : spec.targets) {
    const Named target_spans[] = {{"count", c.count},
                                  {"distance", c.distance},
                                  {"heading", c.heading},
                                  {"pitch", c.pitch},
                                  {"roll", c.roll}};
    for (const auto& [name, s] : target_spans)
      if (std::string e = spanError(name, s); !e.empty()) return "target " + c.name + "." + e;
  }
  return "";
}

SampleScene drawSample(const DatasetSpec& spec, int index) {
  const std::uint64_t seed = hashCounters(spec.seed, 0x53616d706c65ull, std::uint64_t(index));
  SampleScene out;
  out.scene.seed = seed;
  json& record = out.record;
  record["index"] = index;
  record["seed"] = std::to_string(seed);
  record["band"] = spec.band == Band::kLwir ? "lwir" : "visible";
  drawSky(spec, seed, out);
  drawSea(spec, seed, out);
  drawSun(spec, seed, out);
  drawFog(spec, seed, out);
  drawCamera(spec, seed, out);
  drawTargets(spec, seed, out);
  return out;
}

std::vector<float> glintMask(const Frame& frame, double threshold) {
  std::vector<float> mask(frame.glint.size(), 0.0f);
  for (std::size_t i = 0; i < mask.size(); ++i)
    if (frame.glint[i] >= threshold) mask[i] = 65535.0f;
  return mask;
}

std::vector<TargetLabel> labelTargets(const Frame& frame, const std::vector<int>& target_class,
                                      double glint_threshold) {
  const int w = frame.width(), h = frame.height();
  std::vector<TargetLabel> labels(target_class.size());
  std::vector<double> transmittance(labels.size(), 0.0);
  struct Extent {
    int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
    void add(int x, int y) {
      x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
    }
    void to(double (&box)[4]) const {
      if (x1 < 0) return;
      box[0] = x0, box[1] = y0, box[2] = x1 - x0 + 1, box[3] = y1 - y0 + 1;
    }
  };
  std::vector<Extent> full(labels.size()), visible(labels.size());
  for (std::size_t k = 0; k < labels.size(); ++k) {
    labels[k].target = int(k);
    labels[k].category = target_class[k];
  }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      const int id = int(frame.object_id[i]);
      if (id <= 0 || id > int(labels.size())) continue;
      TargetLabel& l = labels[id - 1];
      const double t = frame.visibility[i];
      ++l.silhouette_px;
      transmittance[id - 1] += t;
      full[id - 1].add(x, y);
      if (t >= 0.5) {
        ++l.visible_px;
        visible[id - 1].add(x, y);
      }
    }
  for (std::size_t k = 0; k < labels.size(); ++k) {
    TargetLabel& l = labels[k];
    if (l.silhouette_px > 0) l.visibility = transmittance[k] / l.silhouette_px;
    full[k].to(l.box_full);
    visible[k].to(l.box);
    if (!frame.glint.empty()) {
      l.glint_px = 0;
      for (int y = int(l.box[1]); y < int(l.box[1] + l.box[3]); ++y)
        for (int x = int(l.box[0]); x < int(l.box[0] + l.box[2]); ++x)
          l.glint_px += frame.glint[std::size_t(y) * w + x] >= glint_threshold;
    }
    if (l.visible_px == 0) continue;
    // COCO's uncompressed RLE runs down the columns, starting with a run of zeros.
    bool inside = false;
    std::uint32_t run = 0;
    for (int x = 0; x < w; ++x)
      for (int y = 0; y < h; ++y) {
        const std::size_t i = std::size_t(y) * w + x;
        const bool on = int(frame.object_id[i]) == int(k) + 1 && frame.visibility[i] >= 0.5f;
        if (on != inside) {
          l.rle.push_back(run);
          run = 0;
          inside = on;
        }
        ++run;
      }
    l.rle.push_back(run);
  }
  return labels;
}

std::vector<float> instanceMask(const Frame& frame) {
  std::vector<float> mask(frame.object_id.size(), 0.0f);
  for (std::size_t i = 0; i < mask.size(); ++i)
    if (frame.object_id[i] > 0.0f && frame.visibility[i] >= 0.5f)
      mask[i] = float(std::uint16_t(frame.object_id[i]));
  return mask;
}

json sampleLabelsJson(const std::vector<TargetLabel>& labels, int width, int height) {
  json out = json::array();
  for (const TargetLabel& l : labels) {
    json a = {
        {"target", l.target},
        {"category", l.category},
        {"bbox", json::array({l.box[0], l.box[1], l.box[2], l.box[3]})},
        {"bbox_full", json::array({l.box_full[0], l.box_full[1], l.box_full[2], l.box_full[3]})},
        {"area", l.visible_px},
        {"area_full", l.silhouette_px},
        {"visibility", l.visibility},
        {"occluded_fraction",
         l.silhouette_px ? 1.0 - double(l.visible_px) / l.silhouette_px : 1.0}};
    if (l.glint_px >= 0) a["glint_px"] = l.glint_px;
    if (l.visible_px > 0) a["segmentation"] = {{"size", {height, width}}, {"counts", l.rle}};
    out.push_back(std::move(a));
  }
  return out;
}

std::string yoloText(const std::vector<TargetLabel>& labels, int width, int height) {
  std::string out;
  char line[128];
  for (const TargetLabel& l : labels) {
    if (l.visible_px == 0) continue;
    std::snprintf(line, sizeof line, "%d %.6f %.6f %.6f %.6f\n", l.category,
                  (l.box[0] + 0.5 * l.box[2]) / width, (l.box[1] + 0.5 * l.box[3]) / height,
                  l.box[2] / width, l.box[3] / height);
    out += line;
  }
  return out;
}

json cocoInfo(const DatasetSpec& spec) {
  return {{"description", "Nephele cloud-clutter dataset"},
          {"version", "1"},
          {"seed", std::to_string(spec.seed)}};
}

json cocoCategories(const DatasetSpec& spec) {
  json categories = json::array();
  for (std::size_t c = 0; c < spec.targets.size(); ++c)
    categories.push_back(
        {{"id", c + 1}, {"name", spec.targets[c].name}, {"supercategory", "target"}});
  return categories;
}

json cocoImage(const DatasetSpec& spec, const json& record) {
  return {{"id", record["index"].get<int>() + 1},
          {"file_name", record["file_name"]},
          {"width", spec.width},
          {"height", spec.height},
          {"camera", record["camera"]}};
}

std::vector<json> cocoAnnotations(const json& record, int& next_id) {
  std::vector<json> out;
  for (const json& l : record["labels"]) {
    if (l["area"].get<int>() == 0) continue;  // hidden: in the manifest, not in COCO
    json a = l;
    a.erase("target");
    a.erase("category");
    a["id"] = ++next_id;
    a["image_id"] = record["index"].get<int>() + 1;
    a["category_id"] = l["category"].get<int>() + 1;
    a["iscrowd"] = 0;
    out.push_back(std::move(a));
  }
  return out;
}

}  // namespace nephele
