#include "protocol/messages.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <set>

#include "protocol/cloud_codes.h"
#include "world/limits.h"
#include "world/sea.h"

namespace nephele {
namespace {

using nlohmann::json;

struct FieldError {
  ErrorCode code;
  std::string message;
};

// Reads one JSON object; every key must be read, and finish() names what is left over.
class FieldReader {
 public:
  FieldReader(const json& object, std::string path) : object_(object), path_(std::move(path)) {}

  bool has(const char* key) const { return object_.contains(key); }

  std::optional<double> number(const char* key, Range range) {
    return number(key, range.lo, range.hi);
  }
  std::optional<double> number(const char* key, double lo, double hi) {
    const json* v = take(key);
    if (!v) return std::nullopt;
    if (!v->is_number()) fail(key, "must be a number (allowed: " + range(lo, hi) + ")");
    if (!heldExactly(*v))
      fail(key, v->dump() + " cannot be held exactly (allowed: " + range(lo, hi) + ")");
    const double x = v->get<double>();
    if (!std::isfinite(x) || x < lo || x > hi)
      fail(key, formatNumber(x) + " is out of range (allowed: " + range(lo, hi) + ")");
    return x;
  }

  double requiredNumber(const char* key, double lo, double hi) {
    if (!has(key)) fail(key, "is missing (allowed: " + range(lo, hi) + ")");
    return *number(key, lo, hi);
  }

  std::optional<std::int64_t> integer(const char* key, std::int64_t lo, std::int64_t hi) {
    const json* v = take(key);
    if (!v) return std::nullopt;
    if (!v->is_number_integer())
      fail(key, "must be an integer (allowed: " + std::to_string(lo) + " to " + std::to_string(hi) +
                    ")");
    const bool negative = v->is_number_integer() && !v->is_number_unsigned();
    const std::int64_t x = negative ? v->get<std::int64_t>()
                                    : std::int64_t(std::min<std::uint64_t>(
                                          v->get<std::uint64_t>(), std::uint64_t(INT64_MAX)));
    if (x < lo || x > hi)
      fail(key, v->dump() + " is out of range (allowed: " + std::to_string(lo) + " to " +
                    std::to_string(hi) + ")");
    return x;
  }

  std::optional<bool> boolean(const char* key) {
    const json* v = take(key);
    if (!v) return std::nullopt;
    if (!v->is_boolean()) fail(key, "must be true or false");
    return v->get<bool>();
  }

  // A name, by the one name rule (world/limits.h).
  std::optional<std::string> name(const char* key) {
    const json* v = take(key);
    if (!v) return std::nullopt;
    if (!v->is_string()) fail(key, "must be a string of " + std::string(kNameRule));
    const std::string s = v->get<std::string>();
    if (std::string e = nameError(s); !e.empty()) fail(key, e);
    return s;
  }

  std::string requiredName(const char* key) {
    if (!has(key)) fail(key, "is missing");
    return *name(key);
  }

  std::optional<std::string> string(const char* key, std::size_t max_length) {
    const json* v = take(key);
    if (!v) return std::nullopt;
    if (!v->is_string() || v->get_ref<const std::string&>().size() > max_length)
      fail(key, "must be a string of at most " + std::to_string(max_length) + " characters");
    return v->get<std::string>();
  }

  template <int N>
  std::optional<glm::vec<N, double>> vector(const char* key, double lo, double hi) {
    const json* v = take(key);
    if (!v) return std::nullopt;
    if (!v->is_array() || v->size() != std::size_t(N))
      fail(key, "must be an array of " + std::to_string(N) + " numbers (allowed: each " +
                    range(lo, hi) + ")");
    glm::vec<N, double> out;
    for (int i = 0; i < N; ++i) {
      const json& e = (*v)[std::size_t(i)];
      if (!e.is_number() || !heldExactly(e) || !std::isfinite(e.get<double>()) ||
          e.get<double>() < lo || e.get<double>() > hi)
        fail(key, "element " + std::to_string(i) + " is not a number in " + range(lo, hi));
      out[i] = e.get<double>();
    }
    return out;
  }

  // The value of `key` as it is (null when absent), for arrays the reader has no getter for.
  const json* raw(const char* key) { return take(key); }

  const json* object(const char* key) {
    const json* v = take(key);
    if (v && !v->is_object()) fail(key, "must be an object");
    return v;
  }

  void finish(const char* allowed) const {
    for (auto it = object_.begin(); it != object_.end(); ++it)
      if (!taken_.count(it.key()))
        throw FieldError{ErrorCode::kBadField,
                         qualified(it.key()) + ": unknown field (allowed: " + allowed + ")"};
  }

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    throw FieldError{ErrorCode::kBadField, qualified(key) + ": " + what};
  }

 private:
  const json* take(const char* key) {
    taken_.insert(key);
    auto it = object_.find(key);
    return it == object_.end() ? nullptr : &*it;
  }
  std::string qualified(const std::string& key) const {
    return path_.empty() ? key : path_ + "." + key;
  }
  // An integer read as a number must lie within +-2^53 (world/limits.h, heldExactly).
  static bool heldExactly(const json& v) {
    if (v.is_number_unsigned()) return v.get<std::uint64_t>() <= std::uint64_t(kMaxExactInteger);
    if (v.is_number_integer()) return nephele::heldExactly(v.get<std::int64_t>());
    return true;
  }
  static std::string range(double lo, double hi) {
    return formatNumber(lo) + " to " + formatNumber(hi);
  }

  const json& object_;
  std::string path_;
  std::set<std::string> taken_;
};

ImageFormat readFormat(FieldReader& r, ImageFormat current) {
  const auto f = r.string("format", 16);
  if (!f) return current;
  if (*f == "raw") return ImageFormat::kRaw;
  if (*f == "png") return ImageFormat::kPng;
  if (*f == "jpeg") return ImageFormat::kJpeg;
  if (*f == "exr") return ImageFormat::kExr;
  r.fail("format",
         "\"" + *f + "\" is not allowed (allowed: " + std::string(kImageFormatNames) + ")");
}

// "format" and "channels", if either is given.
std::optional<ImageRequest> readImage(FieldReader& r) {
  if (!r.has("format") && !r.has("channels")) return std::nullopt;
  ImageRequest image;
  image.format = readFormat(r, image.format);
  image.coverage = defaultCoverage(image.format);
  if (const json* channels = r.raw("channels")) {
    const std::string allowed = " (allowed: a non-empty array of " + channelNames() + "; " +
                                channelNames(true) + " with raw or exr)";
    if (!channels->is_array() || channels->empty() || channels->size() > kChannels.size())
      r.fail("channels", "must be an array of channel names" + allowed);
    image.colour = image.coverage = false;
    ChannelSet seen;
    for (const json& c : *channels) {
      const std::string name = c.is_string() ? c.get<std::string>() : c.dump();
      const std::optional<Channel> channel = channelFromName(name);
      if (!channel || seen.has(*channel))
        r.fail("channels", name + " is not allowed or repeated" + allowed);
      seen.add(*channel);
      image.order.push_back(*channel);
      if (*channel == Channel::kColour)
        image.colour = true;
      else if (*channel == Channel::kCoverage)
        image.coverage = true;
      else
        image.planes.add(*channel);
    }
    if (image.floatPlanes() && image.format != ImageFormat::kRaw &&
        image.format != ImageFormat::kExr)
      r.fail("channels", channelNames(true) +
                             " are float planes: format raw or exr only (allowed with " +
                             std::string(imageFormatName(image.format)) + ": colour, coverage)");
  }
  if (image.format == ImageFormat::kJpeg && image.coverage)
    r.fail("channels", "jpeg holds colour only (allowed with jpeg: [\"colour\"])");
  return image;
}

ViewPatch readViewPatch(FieldReader& r, bool image = true) {
  ViewPatch p;
  p.position = r.vector<3>("position", -Limits::kMaxCoordinate, Limits::kMaxCoordinate);
  if (p.position && p.position->z < 0.0)
    r.fail("position", "z is below the ground (allowed: z >= 0)");
  p.heading = r.number("heading", -Limits::kMaxHeading, Limits::kMaxHeading);
  p.pitch = r.number("pitch", -Limits::kMaxPitch, Limits::kMaxPitch);
  p.roll = r.number("roll", -Limits::kMaxRoll, Limits::kMaxRoll);
  p.vfov = r.number("vfov", Limits::kMinVfov, Limits::kMaxVfov);
  if (auto w = r.integer("width", 1, Limits::kMaxImageSide)) p.width = int(*w);
  if (auto h = r.integer("height", 1, Limits::kMaxImageSide)) p.height = int(*h);
  if (const json* f = r.object("frustum")) {
    FieldReader fr(*f, "frustum");
    const Range a = Limits::kFrustumAngle;
    Frustum frustum{fr.requiredNumber("left", a.lo, a.hi), fr.requiredNumber("right", a.lo, a.hi),
                    fr.requiredNumber("bottom", a.lo, a.hi), fr.requiredNumber("top", a.lo, a.hi)};
    fr.finish("left, right, bottom, top");
    if (std::string e = frustumError(frustum); !e.empty()) r.fail("frustum", e.substr(9));
    if (p.vfov) r.fail("frustum", "give vfov (a centred view) or frustum, not both");
    p.frustum = frustum;
  }
  if (image) p.image = readImage(r);
  return p;
}

constexpr const char* kCameraKeys = "position, heading, pitch, roll, vfov, width, height, frustum";

// The views of a render: "view" (one name) or "views" (an array of names).
std::vector<std::string> readViews(FieldReader& r) {
  const std::string allowed = "\"view\": a name, or \"views\": an array of 1 to " +
                              std::to_string(ProtocolLimits::kMaxViewsPerRender) +
                              " distinct view names";
  if (r.has("view") == r.has("views"))
    r.fail("view", "give one of view and views (" + allowed + ")");
  if (r.has("view")) return {r.requiredName("view")};
  const json* views = r.raw("views");
  if (!views->is_array() || views->empty() ||
      views->size() > std::size_t(ProtocolLimits::kMaxViewsPerRender))
    r.fail("views", "must be " + allowed);
  std::vector<std::string> names;
  for (const json& v : *views) {
    const std::string name = v.is_string() ? v.get<std::string>() : v.dump();
    if (std::string e = nameError(name); !e.empty()) r.fail("views", e);
    if (std::find(names.begin(), names.end(), name) != names.end())
      r.fail("views", "\"" + name + "\" is repeated (" + allowed + ")");
    names.push_back(name);
  }
  return names;
}

WeatherLayer readWeather(FieldReader& r) {
  WeatherLayer w;
  if (auto t = r.integer("type", 0, kCloudTypeCodes - 1)) w.type = *cloudTypeFromCode(int(*t));
  w.base_m = r.number("base", 0.0, Limits::kMaxBase).value_or(w.base_m);
  w.thickness_m = r.number("thickness", Limits::kThickness).value_or(w.thickness_m);
  w.coverage = r.number("coverage", Limits::kCoveragePercent).value_or(w.coverage * 100.0) / 100.0;
  w.wind = r.vector<2>("wind", -Limits::kMaxWind, Limits::kMaxWind);
  if (w.wind && glm::length(*w.wind) > Limits::kMaxWind)
    r.fail("wind", "speed is above " + formatNumber(Limits::kMaxWind) + " m/s");
  // A macrocluster or one side of a front (MODEL.md section 11): the keys of a scene file's
  // [[macrocluster]]; without `size` the layer is unbounded.
  Region& region = w.region;
  const double c = Limits::kMaxCoordinate;
  region.centre = r.vector<2>("centre", -c, c).value_or(region.centre);
  if (auto size = r.vector<2>("size", Limits::kRegionSize.lo, Limits::kRegionSize.hi))
    region.half_size = 0.5 * *size;
  region.heading_deg = r.number("heading", -Limits::kMaxHeading, Limits::kMaxHeading).value_or(0.0);
  region.edge_m = r.number("edge", Limits::kRegionBand).value_or(0.0);
  if (auto front = r.string("front", 8)) {
    if (*front != "none" && *front != "left" && *front != "right")
      r.fail("front", "\"" + *front + "\" is not allowed (allowed: none, left, right)");
    region.side = *front == "left" ? -1 : *front == "right" ? 1 : 0;
  }
  region.transition_m = r.number("transition", Limits::kRegionBand).value_or(0.0);
  w.clusters.spacing_m = r.number("spacing", Limits::kClusterSpacing).value_or(0.0);
  if (auto v = r.number("visibility", 0.0, Limits::kLayerVisibility.hi)) w.visibility_m = *v;
  w.transition_band_m = r.number("transition_band", Limits::kTransitionBand).value_or(0.0);
  w.scud = r.number("scud", Limits::kCoveragePercent).value_or(0.0) / 100.0;
  if (auto kind = r.string("precipitation", 8)) {
    const auto found = std::find(kPrecipitationNames.begin(), kPrecipitationNames.end(), *kind);
    if (found == kPrecipitationNames.end())
      r.fail("precipitation", "\"" + *kind +
                                  "\" is not allowed (allowed: none, rain, snow, sleet, hail, "
                                  "sand, dust)");
    w.precipitation.kind = PrecipitationKind(found - kPrecipitationNames.begin());
  }
  w.precipitation.rate_mm_h =
      r.number("precipitation_rate", Limits::kPrecipitationRate).value_or(0.0);
  if (auto v = r.number("precipitation_visibility", 0.0, Limits::kPrecipitationVisibility.hi))
    w.precipitation.visibility_m = *v;
  w.clusters.amount = r.number("variation", Limits::kClusterVariation).value_or(0.0);
  // The rules between keys are the world's, shared with scene files.
  if (std::string e = weatherLayerError(w); !e.empty()) throw FieldError{ErrorCode::kBadField, e};
  return w;
}

using namespace command;

Hello readHello(FieldReader& r) {
  Hello c{r.string("token", 256)};
  r.finish("cmd, id, token");
  return c;
}

GetView readGetView(FieldReader& r) {
  GetView c{r.name("view").value_or("")};
  r.finish("cmd, id, view");
  return c;
}

SetView readSetView(FieldReader& r) {
  SetView c{r.requiredName("view"), readViewPatch(r)};
  r.finish(
      "cmd, id, view, position, heading, pitch, roll, vfov, width, height, frustum, format, "
      "channels");
  return c;
}

SetWeather readSetWeather(FieldReader& r) {
  SetWeather c;
  if (!r.has("layer"))
    r.fail("layer",
           "is missing (allowed: 1 to 3, the CIGI cloud layers, and 4 to 9, its precipitation "
           "layers)");
  c.layer = int(*r.integer("layer", 1, ProtocolLimits::kWeatherKeys));
  if (!r.has("type"))
    r.fail("type", "is missing (allowed: " + cloudTypeCodesAllowed() +
                       ", CIGI cloud types: " + cloudTypeCodesListed() + ")");
  const bool named = r.has("precipitation");
  c.weather = readWeather(r);
  if (c.layer > ProtocolLimits::kWeatherLayers) {
    // CIGI's precipitation layers: no clouds, and the kind is the layer's ("none" removes it).
    const auto kind = PrecipitationKind(c.layer - ProtocolLimits::kWeatherLayers);
    if (c.weather.type != CloudType::kNone)
      r.fail("type", "layers 4 to 9 hold precipitation only (allowed: 0 none)");
    if (!named) c.weather.precipitation.kind = kind;
    if (c.weather.precipitation.kind != kind &&
        c.weather.precipitation.kind != PrecipitationKind::kNone)
      r.fail("precipitation", "layer " + std::to_string(c.layer) + " holds " +
                                  std::string(kPrecipitationNames[int(kind)]) +
                                  " (allowed: that or none)");
  }
  r.finish(
      "cmd, id, layer, type, base, thickness, coverage, wind, centre, size, heading, edge, "
      "front, transition, spacing, variation, visibility, transition_band, scud, precipitation, "
      "precipitation_rate, precipitation_visibility");
  return c;
}

SetWind readSetWind(FieldReader& r) {
  if (!r.has("velocity")) r.fail("velocity", "is missing ([east, north] m/s)");
  SetWind c{*r.vector<2>("velocity", -Limits::kMaxWind, Limits::kMaxWind)};
  if (glm::length(c.velocity) > Limits::kMaxWind)
    r.fail("velocity", "speed is above " + formatNumber(Limits::kMaxWind) + " m/s");
  r.finish("cmd, id, velocity");
  return c;
}

SetSun readSetSun(FieldReader& r) {
  SetSun c{r.number("azimuth", -Limits::kMaxHeading, Limits::kMaxHeading),
           r.number("elevation", -Limits::kMaxPitch, Limits::kMaxPitch), std::nullopt,
           std::nullopt};
  if (auto utc = r.string("utc", 64)) {
    if (c.azimuth || c.elevation)
      r.fail("utc", "give the sun by azimuth and elevation, or by utc, not both");
    CivilTime t;
    if (std::string e = parseUtc(*utc, t); !e.empty()) r.fail("utc", e);
    c.utc = t;
  }
  r.finish("cmd, id, azimuth, elevation, utc");
  return c;
}

SetFog readSetFog(FieldReader& r) {
  SetFog c{r.boolean("enabled"), r.number("top", 0.0, Limits::kMaxAltitude),
           r.number("visibility", Limits::kFogVisibility),
           r.vector<3>("colour", Limits::kColour.lo, Limits::kColour.hi)};
  if (c.enabled == false && (c.top || c.visibility || c.colour))
    r.fail("enabled", "false removes the fog; give no top, visibility or colour with it");
  r.finish("cmd, id, enabled, top, visibility, colour");
  return c;
}

SetHaze readSetHaze(FieldReader& r) {
  SetHaze c{r.boolean("enabled"), r.number("visibility", Limits::kHazeVisibility),
            r.number("scale_height", Limits::kHazeScaleHeight)};
  if (c.enabled == false && (c.visibility || c.scale_height))
    r.fail("enabled", "false removes the haze; give no visibility or scale_height with it");
  r.finish("cmd, id, enabled, visibility, scale_height");
  return c;
}

// One object of set_sea's `waves`.
WavePatch readWavePatch(FieldReader& r) {
  if (!r.has("id"))
    r.fail("id", "is missing (allowed: 0 to " + std::to_string(Limits::kMaxWaveId) + ")");
  WavePatch w;
  w.id = int(*r.integer("id", 0, Limits::kMaxWaveId));
  w.enabled = r.boolean("enabled");
  w.height = r.number("height", Limits::kWaveHeight);
  w.wavelength = r.number("wavelength", Limits::kWavelength);
  w.period = r.number("period", Limits::kWavePeriod);
  w.direction = r.number("direction", Limits::kWaveDirection);
  w.phase = r.number("phase", Limits::kWavePhase);
  if (w.enabled == false && (w.height || w.wavelength || w.period || w.direction || w.phase))
    r.fail("enabled",
           "false removes the wave train; give no height, wavelength, period, direction or "
           "phase with it");
  r.finish("id, enabled, height, wavelength, period, direction, phase");
  return w;
}

SetSea readSetSea(FieldReader& r) {
  SetSea c;
  c.enabled = r.boolean("enabled");
  c.fetch = r.number("fetch", Limits::kSeaFetch);
  c.temperature = r.number("temperature", Limits::kSeaTemperature);
  c.clarity = r.number("clarity", Limits::kSeaClarity);
  c.whitecaps = r.boolean("whitecaps");
  if (auto seed = r.integer("seed", 0, INT64_MAX)) c.seed = std::uint64_t(*seed);
  if (const json* waves = r.raw("waves")) {
    const std::string allowed = "an array of 1 to " + std::to_string(kMaxWaveTrains) +
                                " objects {id, enabled, height, wavelength, period, direction, "
                                "phase} of distinct ids";
    if (!waves->is_array() || waves->empty() || waves->size() > std::size_t(kMaxWaveTrains))
      r.fail("waves", "must be " + allowed);
    for (std::size_t i = 0; i < waves->size(); ++i) {
      const json& w = (*waves)[i];
      const std::string path = "waves[" + std::to_string(i) + "]";
      if (!w.is_object()) r.fail(path, "must be an object (" + allowed + ")");
      FieldReader wr(w, path);
      const WavePatch patch = readWavePatch(wr);
      for (const WavePatch& other : c.waves)
        if (other.id == patch.id)
          r.fail(path, "id " + std::to_string(patch.id) + " is repeated (" + allowed + ")");
      c.waves.push_back(patch);
    }
  }
  if (c.enabled == false &&
      (c.fetch || c.temperature || c.clarity || c.whitecaps || c.seed || !c.waves.empty()))
    r.fail("enabled",
           "false removes the sea; give no fetch, temperature, clarity, whitecaps, seed or waves "
           "with it");
  r.finish("cmd, id, enabled, fetch, temperature, clarity, whitecaps, seed, waves");
  return c;
}

SetSite readSetSite(FieldReader& r) {
  SetSite c{r.number("latitude", Limits::kLatitude), r.number("longitude", Limits::kLongitude),
            r.number("grid", -Limits::kMaxHeading, Limits::kMaxHeading)};
  if (c.latitude.has_value() != c.longitude.has_value())
    r.fail(c.latitude ? "longitude" : "latitude",
           "is missing (give latitude and longitude together)");
  if (c.grid && !c.latitude) r.fail("grid", "needs latitude and longitude with it");
  r.finish("cmd, id, latitude, longitude, grid");
  return c;
}

SetTime readSetTime(FieldReader& r) {
  SetTime c{r.number("time_scale", 0.0, ProtocolLimits::kMaxTimeScale), r.boolean("paused"),
            r.number("advance", 0.0, Limits::kMaxAdvance), std::nullopt};
  if (auto mode = r.string("mode", 16)) {
    if (*mode != "realtime" && *mode != "lockstep")
      r.fail("mode", "\"" + *mode + "\" is not allowed (allowed: realtime, lockstep)");
    c.mode = *mode == "realtime" ? TickMode::kRealtime : TickMode::kLockstep;
  }
  r.finish("cmd, id, time_scale, paused, advance, mode");
  return c;
}

AddCloud readAddCloud(FieldReader& r) {
  const json* cloud = r.object("cloud");
  if (!cloud) r.fail("cloud", "is missing (an object with the keys of a scene file's [[cloud]])");
  AddCloud c{*cloud};
  r.finish("cmd, id, cloud");
  return c;
}

ChangeCloud readChangeCloud(FieldReader& r) {
  ChangeCloud c;
  c.name = r.requiredName("name");
  c.move = r.vector<3>("move", -Limits::kMaxCoordinate, Limits::kMaxCoordinate);
  c.threshold = r.number("threshold", Limits::kCloudThreshold);
  c.limb_threshold = r.number("limb_threshold", Limits::kCloudThreshold);
  c.transition = r.number("transition", Limits::kTransition);
  c.colour = r.vector<3>("colour", Limits::kColour.lo, Limits::kColour.hi);
  r.finish("cmd, id, name, move, threshold, limb_threshold, transition, colour");
  return c;
}

AddTarget readAddTarget(FieldReader& r) {
  const json* target = r.object("target");
  if (!target)
    r.fail("target",
           "is missing (an object with the keys of a scene file's [[target]], or a type "
           "named in the daemon config's [[entity_type]])");
  AddTarget c{*target, false, std::nullopt};
  r.finish("cmd, id, target");
  return c;
}

MoveTarget readMoveTarget(FieldReader& r) {
  MoveTarget c;
  c.name = r.requiredName("name");
  c.centre = r.vector<3>("centre", -Limits::kMaxCoordinate, Limits::kMaxCoordinate);
  c.heading = r.number("heading", -Limits::kMaxHeading, Limits::kMaxHeading);
  c.pitch = r.number("pitch", -Limits::kMaxPitch, Limits::kMaxPitch);
  c.roll = r.number("roll", -Limits::kMaxRoll, Limits::kMaxRoll);
  r.finish("cmd, id, name, centre, heading, pitch, roll");
  return c;
}

Tick readTick(FieldReader& r) {
  Tick c{r.requiredNumber("dt", 0.0, Limits::kMaxTick)};
  r.finish("cmd, id, dt");
  return c;
}

Render readRender(FieldReader& r) {
  Render c{readViews(r), std::nullopt, readImage(r)};
  if (const json* camera = r.object("camera")) {
    if (c.views.size() != 1) r.fail("camera", "applies to a render of one view");
    FieldReader cr(*camera, "camera");
    c.camera = readViewPatch(cr, false);
    cr.finish(kCameraKeys);
  }
  r.finish("cmd, id, view, views, camera, format, channels");
  return c;
}

Subscribe readSubscribe(FieldReader& r) {
  Subscribe c;
  c.view = r.requiredName("view");
  c.rate_hz = r.number("rate", 0.01, ProtocolLimits::kMaxSubscriptionHz).value_or(c.rate_hz);
  c.image = readImage(r);
  r.finish("cmd, id, view, rate, format, channels");
  return c;
}

Unsubscribe readUnsubscribe(FieldReader& r) {
  if (!r.has("subscription")) r.fail("subscription", "is missing");
  Unsubscribe c{*r.integer("subscription", 1, INT64_MAX)};
  r.finish("cmd, id, subscription");
  return c;
}

Stream readStream(FieldReader& r) {
  Stream c;
  c.view = r.requiredName("view");
  using L = VideoStreamLimits;
  VideoStreamSettings& v = c.settings;
  if (!r.has("address"))
    r.fail("address", "is missing (udp://host:port, srt://host:port or rtp://host:port)");
  v.address = *r.string("address", 256);
  v.bitrate_kbps = int(r.integer("bitrate", L::kMinKbps, L::kMaxKbps).value_or(v.bitrate_kbps));
  v.rate_hz = r.number("rate", L::kMinRate, L::kMaxRate).value_or(v.rate_hz);
  v.keyframe_interval =
      int(r.integer("keyframe_interval", 1, L::kMaxKeyframeInterval).value_or(v.keyframe_interval));
  v.encoder = r.string("encoder", 32).value_or(v.encoder);
  v.stamp = r.boolean("stamp").value_or(false);
  if (std::string e = videoStreamSettingsError(v); !e.empty())
    r.fail(e.substr(0, e.find(':')), e.substr(e.find(':') + 2));
  r.finish("cmd, id, view, address, bitrate, rate, keyframe_interval, encoder, stamp");
  return c;
}

Unstream readUnstream(FieldReader& r) {
  if (!r.has("stream")) r.fail("stream", "is missing");
  Unstream c{*r.integer("stream", 1, INT64_MAX)};
  r.finish("cmd, id, stream");
  return c;
}

// Commands of a name alone, and of nothing.
template <class T>
T readNamed(FieldReader& r) {
  T c{r.requiredName("name")};
  r.finish("cmd, id, name");
  return c;
}
template <class T>
T readBare(FieldReader& r) {
  r.finish("cmd, id");
  return {};
}
RemoveCloud readRemoveCloud(FieldReader& r) {
  return readNamed<RemoveCloud>(r);
}
RemoveTarget readRemoveTarget(FieldReader& r) {
  return readNamed<RemoveTarget>(r);
}
Snapshot readSnapshot(FieldReader& r) {
  return readNamed<Snapshot>(r);
}
Restore readRestore(FieldReader& r) {
  return readNamed<Restore>(r);
}
ListTargets readListTargets(FieldReader& r) {
  return readBare<ListTargets>(r);
}
Stats readStats(FieldReader& r) {
  return readBare<Stats>(r);
}
Hash readHash(FieldReader& r) {
  return readBare<Hash>(r);
}

// The readers by name, from the one list (protocol/commands.inc).
Command readCommand(const std::string& cmd, FieldReader& r) {
  using Reader = Command (*)(FieldReader&);
  static const std::pair<std::string_view, Reader> kReaders[] = {
#define NEPHELE_COMMAND(name, Type) \
  {#name, [](FieldReader& r) -> Command { return read##Type(r); }},
#include "protocol/commands.inc"
#undef NEPHELE_COMMAND
  };
  for (const auto& [name, read] : kReaders)
    if (name == cmd) return read(r);
  throw FieldError{ErrorCode::kUnknownCommand, "cmd: \"" + cmd + "\" is not a command (allowed: " +
                                                   std::string(kCommandNames) + ")"};
}

// Nesting depth of JSON text, counted before parsing so that deep input cannot exhaust
// the stack of a recursive parser or destructor.
int nestingDepth(std::string_view text) {
  int depth = 0, deepest = 0;
  bool in_string = false, escaped = false;
  for (char c : text) {
    if (in_string) {
      if (escaped)
        escaped = false;
      else if (c == '\\')
        escaped = true;
      else if (c == '"')
        in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      deepest = std::max(deepest, ++depth);
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return deepest;
}

}  // namespace

std::string_view errorCodeName(ErrorCode code) {
  switch (code) {
    case ErrorCode::kBadJson:
      return "bad_json";
    case ErrorCode::kBadField:
      return "bad_field";
    case ErrorCode::kUnknownCommand:
      return "unknown_command";
    case ErrorCode::kTooLarge:
      return "too_large";
    case ErrorCode::kUnauthorized:
      return "unauthorized";
    case ErrorCode::kBusy:
      return "busy";
    case ErrorCode::kNotFound:
      return "not_found";
    case ErrorCode::kLimit:
      return "limit";
    case ErrorCode::kFailed:
      return "failed";
  }
  return "failed";
}

std::string_view imageFormatName(ImageFormat format) {
  switch (format) {
    case ImageFormat::kRaw:
      return "raw";
    case ImageFormat::kPng:
      return "png";
    case ImageFormat::kJpeg:
      return "jpeg";
    case ImageFormat::kExr:
      return "exr";
  }
  return "raw";
}

std::string_view commandName(const Command& command) {
  static constexpr std::string_view kNames[] = {
#define NEPHELE_COMMAND(name, Type) #name,
#include "protocol/commands.inc"
#undef NEPHELE_COMMAND
  };
  return kNames[command.index()];
}

std::variant<Request, BadRequest> parseRequest(std::string_view line) {
  if (line.size() >= ProtocolLimits::kMaxRequestBytes)
    return BadRequest{nullptr,
                      {ErrorCode::kTooLarge,
                       "request is " + std::to_string(line.size()) + " bytes (allowed: less than " +
                           std::to_string(ProtocolLimits::kMaxRequestBytes) + ")"}};
  if (nestingDepth(line) > ProtocolLimits::kMaxJsonDepth)
    return BadRequest{
        nullptr,
        {ErrorCode::kBadJson,
         "request nests deeper than " + std::to_string(ProtocolLimits::kMaxJsonDepth) + " levels"}};
  // Strict JSON (RFC 8259): no byte-order mark in a protocol line (section 8.1), no NUL, and
  // object names unique (section 4) so that no command means two things.
  if (line.starts_with("\xEF\xBB\xBF"))
    return BadRequest{nullptr, {ErrorCode::kBadJson, "request starts with a byte-order mark"}};
  if (line.find('\0') != std::string_view::npos)
    return BadRequest{nullptr, {ErrorCode::kBadJson, "request is not valid JSON (a NUL byte)"}};
  std::vector<std::vector<std::string>> keys;  // the names seen in each open object
  std::string duplicate;
  const json::parser_callback_t check_keys = [&](int, json::parse_event_t event, json& parsed) {
    if (event == json::parse_event_t::object_start) keys.emplace_back();
    if (event == json::parse_event_t::object_end && !keys.empty()) keys.pop_back();
    if (event == json::parse_event_t::key && !keys.empty()) {
      const std::string& name = parsed.get_ref<const std::string&>();
      std::vector<std::string>& seen = keys.back();
      if (duplicate.empty() && std::find(seen.begin(), seen.end(), name) != seen.end())
        duplicate = name;
      seen.push_back(name);
    }
    return true;
  };
  json root = json::parse(line, check_keys, /*allow_exceptions=*/false);
  if (root.is_discarded())
    return BadRequest{nullptr, {ErrorCode::kBadJson, "request is not valid JSON"}};
  if (!duplicate.empty())
    return BadRequest{nullptr,
                      {ErrorCode::kBadJson, "request has a duplicate key \"" + duplicate + "\""}};
  if (!root.is_object())
    return BadRequest{nullptr, {ErrorCode::kBadJson, "request must be a JSON object"}};
  json id = nullptr;
  if (auto it = root.find("id"); it != root.end()) {
    if (!it->is_number() && !(it->is_string() && it->get_ref<const std::string&>().size() <= 64) &&
        !it->is_null())
      return BadRequest{nullptr,
                        {ErrorCode::kBadField,
                         "id: must be a number, a string of at most 64 characters, or null"}};
    id = *it;
  }
  auto cmd = root.find("cmd");
  if (cmd == root.end() || !cmd->is_string())
    return BadRequest{id,
                      {ErrorCode::kBadField, "cmd: is missing or not a string (allowed: " +
                                                 std::string(kCommandNames) + ")"}};
  try {
    FieldReader reader(root, "");
    reader.raw("cmd");
    reader.raw("id");
    return Request{id, readCommand(cmd->get<std::string>(), reader)};
  } catch (const FieldError& e) {
    return BadRequest{id, {e.code, e.message}};
  } catch (const std::exception& e) {  // nlohmann type errors: a backstop
    return BadRequest{id, {ErrorCode::kBadField, std::string("request: ") + e.what()}};
  }
}

std::string okReply(const json& id, const json& result) {
  return json{{"id", id}, {"ok", true}, {"result", result}}.dump(-1, ' ', false,
                                                                 json::error_handler_t::replace) +
         "\n";
}

std::string errorReply(const json& id, const ProtocolError& error) {
  return json{{"id", id},
              {"ok", false},
              {"error", {{"code", errorCodeName(error.code)}, {"message", error.message}}}}
             .dump(-1, ' ', false, json::error_handler_t::replace) +
         "\n";
}

std::string imageReplyHeader(const json& id, json image, std::size_t byte_count) {
  image["bytes"] = byte_count;
  return okReply(id, json{{"image", std::move(image)}});
}

std::string frameEventHeader(std::int64_t subscription, json image, std::size_t byte_count) {
  image["bytes"] = byte_count;
  return json{{"event", "frame"}, {"subscription", subscription}, {"image", std::move(image)}}.dump(
             -1, ' ', false, json::error_handler_t::replace) +
         "\n";
}

json channelNames(const ImageRequest& image) {
  json out = json::array();
  if (!image.order.empty()) {
    for (Channel c : image.order) out.push_back(nephele::channelName(c));
    return out;
  }
  if (image.colour) out.push_back("colour");
  if (image.coverage) out.push_back("coverage");
  return out;
}

json frustumJson(const Frustum& f) {
  return {{"left", f.left}, {"right", f.right}, {"bottom", f.bottom}, {"top", f.top}};
}

json cameraJson(const FrameInfo& info) {
  return {{"position", {info.position.x, info.position.y, info.position.z}},
          {"heading_deg", info.orientation.heading_deg},
          {"pitch_deg", info.orientation.pitch_deg},
          {"roll_deg", info.orientation.roll_deg},
          {"vfov_deg", info.vfov_deg},
          {"focal_px", info.focal_px},
          {"principal_point", {info.cx, info.cy}}};
}

}  // namespace nephele
