#include "world/world.h"

#include "world/limits.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "world/check.h"
#include "world/counter_random.h"
#include "world/formations/weather.h"

namespace nephele {
namespace {

bool sameWind(const WindProfile& a, const WindProfile& b) {
  return std::equal(a.samples.begin(), a.samples.end(), b.samples.begin(), b.samples.end(),
                    [](const WindSample& x, const WindSample& y) {
                      return x.altitude_m == y.altitude_m && x.velocity == y.velocity;
                    });
}

// Development changes T0 in steps of 1/256 so that a developing layer rebakes its texture
// a bounded number of times rather than every frame.
double quantisedT0(double t0) {
  return std::round(t0 * 256.0) / 256.0;
}

// What is wrong with a wind profile (a sample's altitude or speed, altitudes out of order), or
// empty.
std::string windProfileError(const WindProfile& wind) {
  std::ostringstream out;
  for (std::size_t i = 0; i < wind.samples.size() && out.tellp() == 0; ++i) {
    const WindSample& w = wind.samples[i];
    if (!std::isfinite(w.altitude_m) || !(glm::length(w.velocity) <= 200.0))
      out << "wind: sample " << i << " needs a finite altitude and a speed of at most 200 m/s";
    else if (i > 0 && !(w.altitude_m > wind.samples[i - 1].altitude_m))
      out << "wind: altitudes must increase strictly";
  }
  return out.str();
}

}  // namespace

std::string worldDynamicsError(const Scene& scene, const WorldDynamics& d) {
  std::ostringstream out;
  if (!d.layers.empty() && d.layers.size() != scene.layers.size())
    out << "development: " << d.layers.size() << " layer schedules for " << scene.layers.size()
        << " layers";
  if (!d.clouds.empty() && d.clouds.size() != scene.clouds.size())
    out << "development: " << d.clouds.size() << " cloud schedules for " << scene.clouds.size()
        << " clouds";
  if (out.tellp() == 0) out << windProfileError(d.wind);
  auto check = [&](const char* what, const Schedule& s, double lo, double hi) {
    if (out.tellp() != 0) return;
    if (std::string e = scheduleError(s, lo, hi); !e.empty()) out << what << ": " << e;
  };
  for (const LayerDevelopment& l : d.layers) {
    check("threshold", l.threshold, -10.0, 10.0);
    check("transition", l.transition, 0.0, 10.0);
    check("t0", l.t0, 0.0, 100.0);
  }
  for (const CloudDevelopment& c : d.clouds) {
    check("threshold_centre", c.threshold_centre, -10.0, 10.0);
    check("threshold_limb", c.threshold_limb, -10.0, 10.0);
    check("transition", c.transition, 0.0, 10.0);
  }
  for (const AutomatonCloudSpec& a : d.automata)
    if (out.tellp() == 0)
      if (std::string e = automatonCloudError(a); !e.empty())
        out << "automaton " << a.name << ": " << e;
  return out.str();
}

World::World(const Scene& scene, const WorldDynamics& dynamics, int threads)
    : World(scene, dynamics, threads, true) {}

World::World(const Scene& scene, const WorldDynamics& dynamics, int threads, bool warm_up)
    : base_(scene), dynamics_(dynamics), threads_(std::max(1, threads)) {
  NEPHELE_CHECK(worldDynamicsError(scene, dynamics).empty(), worldDynamicsError(scene, dynamics));
  base_.time_s = 0.0;
  base_.automata.clear();
  // With a wind profile, layers drift with the wind at their altitude.
  if (!dynamics_.wind.empty())
    for (CloudLayer& layer : base_.layers)
      layer.texture.drift_velocity = dynamics_.wind.at(layer.altitude_m);
  const glm::dvec3 to_sun = sunDirection(base_.sun);
  for (const AutomatonCloudSpec& spec : dynamics_.automata)
    automata_.emplace_back(spec, dynamics_.wind, to_sun, warm_up);
  rebuildNow();
}

World::~World() = default;
World::World(World&&) noexcept = default;
World& World::operator=(World&&) noexcept = default;

std::string World::advanceError(double dt_s) const {
  if (!std::isfinite(dt_s) || dt_s < 0.0 || dt_s > Limits::kMaxAdvance) {
    std::ostringstream out;
    out << "dt: " << dt_s << " (allowed: 0 to " << Limits::kMaxAdvance << " seconds)";
    return out.str();
  }
  if (time_ns_ > std::numeric_limits<std::int64_t>::max() - std::llround(dt_s / kTimeResolutionS))
    return "dt: the world's clock would pass its limit of about 292 years";
  return {};
}

std::string World::advanceInPieces(double dt_s, int pieces,
                                   const std::function<void(int, int)>& after_piece) {
  if (!std::isfinite(dt_s) || dt_s < 0.0 || dt_s > Limits::kMaxTime) {
    std::ostringstream out;
    out << "dt: " << dt_s << " (allowed: 0 to " << Limits::kMaxTime << " seconds)";
    return out.str();
  }
  const std::int64_t total_ns = std::llround(dt_s / kTimeResolutionS);
  if (time_ns_ > std::numeric_limits<std::int64_t>::max() - total_ns)
    return "dt: the world's clock would pass its limit of about 292 years";
  const int n = std::max(pieces, int(std::ceil(dt_s / Limits::kMaxAdvance)));
  // Whole nanoseconds per piece, so the pieces add up to exactly one advance of dt_s.
  std::int64_t done = 0;
  for (int i = 1; i <= n; ++i) {
    const std::int64_t next = total_ns / n * i + (i == n ? total_ns % n : 0);
    advanceNs(next - done);
    done = next;
    if (after_piece) after_piece(i, n);
  }
  return {};
}

std::string World::advance(double dt_s) {
  if (std::string e = advanceError(dt_s); !e.empty()) return e;
  advanceNs(std::llround(dt_s / kTimeResolutionS));
  return {};
}

void World::advanceNs(std::int64_t dt_ns) {
  if (dt_ns == 0) return;
  time_ns_ += dt_ns;
  refreshAutomata();
  now_stale_ = true;
}

void World::refreshAutomata() {
  for (AutomatonCloud& cloud : automata_) steps_run_ += cloud.advanceTo(time_ns_, threads_);
}

void World::setSun(const Sun& sun) {
  base_.sun = now_.sun = sun;
  const glm::dvec3 to_sun = sunDirection(sun);
  for (AutomatonCloud& cloud : automata_) relights_run_ += cloud.setSun(to_sun);
  now_stale_ = true;  // the automata's views
}

void World::foldDrift(double sign) {
  const double t = timeSeconds();
  for (CloudLayer& layer : base_.layers)
    layer.texture.drift_offset_m += sign * layer.texture.drift_velocity * t;
  if (dynamics_.wind.empty()) return;
  for (CloudField& field : base_.fields)
    field.drift_m += sign * dynamics_.wind.at(fieldAltitude(field)) * t;
  for (EllipsoidCloud& cloud : base_.clouds) {
    const glm::dvec3 drift(sign * dynamics_.wind.at(cloudAltitude(cloud)) * t, 0.0);
    for (Ellipsoid& e : cloud.ellipsoids) e.centre += drift;
    cloud.drift_m += drift;
  }
}

std::string weatherPrefix(const WeatherKey& key) {
  return (key.region ? "weather/region" + std::to_string(*key.region) + "/"
                     : std::string("weather/")) +
         std::to_string(key.layer);
}

namespace {

// One wind sample per altitude (within a metre), kept in increasing altitude.
void setWindSample(WindProfile& profile, double altitude, glm::dvec2 velocity) {
  auto& samples = profile.samples;
  std::erase_if(samples,
                [&](const WindSample& w) { return std::abs(w.altitude_m - altitude) < 1.0; });
  samples.push_back({altitude, velocity});
  std::sort(samples.begin(), samples.end(),
            [](const WindSample& a, const WindSample& b) { return a.altitude_m < b.altitude_m; });
}

}  // namespace

void appendWeatherClouds(Scene& scene, WorldDynamics& dynamics, const WeatherClouds& clouds) {
  scene.fields.insert(scene.fields.end(), clouds.fields.begin(), clouds.fields.end());
  for (const CloudLayer& l : clouds.layers) {
    scene.layers.push_back(l);
    if (!dynamics.layers.empty()) dynamics.layers.emplace_back();  // none, or one per layer
  }
}

namespace {

// Whether a layer holds anything: clouds, or precipitation of its own (CIGI's layers 4 to 9).
bool weatherHeld(const WeatherLayer& w) {
  return w.type != CloudType::kNone || w.precipitation.kind != PrecipitationKind::kNone;
}

}  // namespace

std::string placeWeather(Scene& scene, WorldDynamics& dynamics, const WeatherKey& key,
                         const WeatherLayer& weather) {
  if (weatherHeld(weather))
    if (std::string e = weatherLayerError(weather); !e.empty()) return e;
  const std::string prefix = weatherPrefix(key);
  // A region's layers are its own, and seeded apart from the global layer of that number.
  std::uint64_t seed = weatherSeed(scene.seed, key.layer);
  if (key.region) seed = hashCounters(seed, 0x526567696f6eull, std::uint64_t(*key.region));
  // Laid out from where the world's content was (a re-centred world's), its region where the
  // database has it.
  WeatherLayer laid_out = weather;
  if (!laid_out.region.everywhere()) laid_out.region.centre += scene.content_origin;
  WeatherClouds add = weatherClouds(laid_out, prefix, seed);
  auto made = [&](const std::string& name) {
    return name == prefix || name.rfind(prefix + "/", 0) == 0;
  };
  // A layer or field the layer made before keeps where it has drifted to, so that a layer set
  // again (its cover, its wind turned by a re-centring) grows and thins in place.
  for (CloudLayer& layer : add.layers) {
    layer.texture.drift_offset_m -= scene.content_origin;
    for (const CloudLayer& old : scene.layers)
      if (old.name == layer.name) {
        layer.region.centre += layer.texture.drift_offset_m - old.texture.drift_offset_m;
        layer.texture.drift_offset_m = old.texture.drift_offset_m;
      }
  }
  for (CloudField& field : add.fields) {
    field.drift_m -= scene.content_origin;
    for (const CloudField& old : scene.fields)
      if (old.name == field.name) {
        field.region.centre += field.drift_m - old.drift_m;
        field.drift_m = old.drift_m;
      }
  }
  eraseWithDevelopment(scene.layers, dynamics.layers,
                       [&](const CloudLayer& l) { return made(l.name); });
  std::erase_if(scene.fields, [&](const CloudField& f) { return made(f.name); });
  appendWeatherClouds(scene, dynamics, add);
  if (!weatherHeld(weather)) {
    scene.weather.erase(key);
    return "";
  }
  if (weather.wind)
    setWindSample(dynamics.wind, weather.base_m + 0.5 * weather.thickness_m, *weather.wind);
  scene.weather[key] = weather;
  return "";
}

std::string World::setWeather(const WeatherKey& key, const WeatherLayer& weather, bool* changed) {
  if (changed) *changed = false;
  const auto held = base_.weather.find(key);
  const bool same = !weatherHeld(weather) ? held == base_.weather.end()
                                          : held != base_.weather.end() && held->second == weather;
  if (same) return "";
  // Checked first, so that placeWeather cannot fail: the layer, then the wind it sets.
  bool wind_changes = false;
  if (weatherHeld(weather)) {
    if (std::string e = weatherLayerError(weather); !e.empty()) return e;
    if (weather.wind) {
      WindProfile wind = dynamics_.wind;
      setWindSample(wind, weather.base_m + 0.5 * weather.thickness_m, *weather.wind);
      if (std::string e = windProfileError(wind); !e.empty()) return e;
      wind_changes = !sameWind(wind, dynamics_.wind);
    }
  }
  editBase(
      [&](Scene& base, WorldDynamics& dynamics) { placeWeather(base, dynamics, key, weather); },
      wind_changes);
  // The layers and fields are a few plain values each; the clouds are untouched.
  now_.layers = base_.layers;
  now_.fields = base_.fields;
  now_.weather = base_.weather;
  now_.sea = base_.sea;
  finishEdit();
  if (changed) *changed = true;
  return "";
}

// Sets one optional part of the scene (fog, haze, the sea): nothing when it is already so.
template <class T>
std::string World::setPart(std::optional<T> Scene::*part, const std::optional<T>& value,
                           bool* changed) {
  if (changed) *changed = false;
  if (base_.*part == value) return "";
  editBase([&](Scene& base, WorldDynamics&) { base.*part = value; });
  now_.*part = value;
  finishEdit();
  if (changed) *changed = true;
  return "";
}

std::string World::setFog(const std::optional<Fog>& fog, bool* changed) {
  return setPart(&Scene::fog, fog, changed);
}

std::string World::setHaze(const std::optional<Haze>& haze, bool* changed) {
  return setPart(&Scene::haze, haze, changed);
}

std::string seaError(const Sea& sea) {
  std::ostringstream out;
  if (!(glm::length(sea.wind) <= Limits::kMaxWind)) {
    out << "wind: " << glm::length(sea.wind) << " m/s is out of range (allowed: 0 to "
        << Limits::kMaxWind << " m/s)";
    return out.str();
  }
  if (outOfRange(out, "fetch", sea.fetch_m, Limits::kSeaFetch) ||
      outOfRange(out, "temperature", sea.temperature_c, Limits::kSeaTemperature) ||
      outOfRange(out, "clarity", sea.clarity, Limits::kSeaClarity))
    return out.str();
  if (sea.trains.size() > std::size_t(kMaxWaveTrains))
    return "waves: " + std::to_string(sea.trains.size()) + " wave trains (allowed: at most " +
           std::to_string(kMaxWaveTrains) + ")";
  for (auto t = sea.trains.begin(); t != sea.trains.end(); ++t) {
    const std::string id = std::to_string(t->id);
    if (t->id < 0 || t->id > Limits::kMaxWaveId)
      return "wave: id " + id + " is out of range (allowed: 0 to " +
             std::to_string(Limits::kMaxWaveId) + ")";
    if (std::any_of(sea.trains.begin(), t, [&](const WaveTrain& o) { return o.id == t->id; }))
      return "wave: id " + id + " is given twice (allowed: one train per id)";
    const std::string at = "wave " + id + " ";
    if (outOfRange(out, (at + "height").c_str(), t->height_m, Limits::kWaveHeight) ||
        outOfRange(out, (at + "wavelength").c_str(), t->wavelength_m, Limits::kWavelength) ||
        outOfRange(out, (at + "period").c_str(), t->period_s, Limits::kWavePeriod) ||
        outOfRange(out, (at + "direction").c_str(), t->direction_deg, Limits::kWaveDirection) ||
        outOfRange(out, (at + "phase").c_str(), t->phase_deg, Limits::kWavePhase))
      return out.str();
  }
  return "";
}

std::string World::setSea(const std::optional<Sea>& sea, bool* changed) {
  if (changed) *changed = false;
  if (sea)
    if (std::string e = seaError(*sea); !e.empty()) return e;
  if (sea && !base_.sea) {  // a new sea's waves are laid out from where the content was
    std::optional<Sea> laid_out = sea;
    laid_out->origin_m = -base_.content_origin;
    return setPart(&Scene::sea, laid_out, changed);
  }
  return setPart(&Scene::sea, sea, changed);
}

namespace {

// Moves everything `scene` holds by -shift: the database's origin to `shift` (setSite).
// The automata move apart (World::setSite).
void moveContent(Scene& scene, glm::dvec2 shift) {
  const glm::dvec3 by(shift, 0.0);
  scene.camera.position -= by;
  // A layer's texture and region, and a field's heaps and region, lie in frames that drift.
  for (CloudLayer& layer : scene.layers) layer.texture.drift_offset_m -= shift;
  for (CloudField& field : scene.fields) field.drift_m -= shift;
  for (EllipsoidCloud& cloud : scene.clouds) {
    for (Ellipsoid& e : cloud.ellipsoids) e.centre -= by;
    cloud.drift_m -= by;  // the texture moves with the cloud
  }
  for (Target& target : scene.targets) target.centre -= by;
  for (RainShaft& shaft : scene.rain_shafts) shaft.centre -= shift;
  for (auto& [key, weather] : scene.weather)
    if (!weather.region.everywhere()) weather.region.centre -= shift;
  if (scene.sea) scene.sea->origin_m -= shift;
  scene.content_origin += shift;
}

}  // namespace

std::string siteError(const Site& site) {
  if (Limits::kLatitude.contains(site.latitude_deg) &&
      Limits::kLongitude.contains(site.longitude_deg) && std::isfinite(site.grid_deg))
    return "";
  return "site: latitude " + std::to_string(site.latitude_deg) + ", longitude " +
         std::to_string(site.longitude_deg) +
         " (allowed: latitude -90 to 90, longitude -180 to 180, a finite grid north)";
}

std::string recentringRefusal(glm::dvec2 shift, const std::string& error) {
  return "site: the re-centring moves the world by " + formatNumber(glm::length(shift)) +
         " m, which would carry " + error + "; nothing changed";
}

glm::dvec2 World::recentreShift(const Site& site) const {
  if (!base_.site || *base_.site == site) return glm::dvec2(0.0);
  return recentred(*base_.site, site.latitude_deg, site.longitude_deg).shift;
}

std::string World::setSiteError(const Site& site) const {
  if (std::string e = siteError(site); !e.empty()) return e;
  const glm::dvec2 shift = recentreShift(site);
  const glm::dvec3 by(shift, 0.0);
  const auto refused = [&](const std::string& e) { return recentringRefusal(shift, e); };
  for (const Target& t : base_.targets) {  // targets do not drift: base_ holds where they stand
    const glm::dvec3 to = t.centre - by;
    if (std::string e = placementError("target " + t.name, to.x, to.y, to.z); !e.empty())
      return refused(e);
  }
  // A weather layer's macrocluster moves with the content (moveContent), within the range
  // set_weather and the snapshot reader accept.
  for (const auto& [key, weather] : base_.weather) {
    if (weather.region.everywhere()) continue;
    WeatherLayer moved = weather;
    moved.region.centre -= shift;
    if (std::string e = weatherLayerError(moved); !e.empty())
      return refused("weather layer " + std::to_string(key.layer) + "'s " + e);
  }
  return "";
}

std::string World::setSite(const Site& site, bool* changed) {
  if (changed) *changed = false;
  if (std::string e = setSiteError(site); !e.empty()) return e;
  if (base_.site == site) return "";
  const glm::dvec2 shift = recentreShift(site);
  editBase([&](Scene& base, WorldDynamics&) {
    base.site = site;
    moveContent(base, shift);
  });
  now_.site = site;
  moveContent(now_, shift);
  for (AutomatonCloudSpec& spec : dynamics_.automata) spec.position -= glm::dvec3(shift, 0.0);
  for (AutomatonCloud& cloud : automata_) cloud.moveBy(-shift);
  finishEdit();
  if (changed) *changed = true;
  return "";
}

std::string World::setWind(const WindProfile& wind) {
  if (std::string e = windProfileError(wind); !e.empty()) return e;
  editBase([&](Scene&, WorldDynamics& dynamics) { dynamics.wind = wind; },
           !sameWind(wind, dynamics_.wind));
  now_.sea = base_.sea;
  // Without a wind time moves no field or cloud and shears no field: now_ holds base_'s, into
  // which the drift so far was folded.
  if (dynamics_.wind.empty()) {
    for (std::size_t i = 0; i < base_.fields.size(); ++i) {
      now_.fields[i].drift_m = base_.fields[i].drift_m;
      now_.fields[i].shear = base_.fields[i].shear;
    }
    for (std::size_t i = 0; i < base_.clouds.size(); ++i) {
      const EllipsoidCloud& from = base_.clouds[i];
      EllipsoidCloud& cloud = now_.clouds[i];
      for (std::size_t k = 0; k < from.ellipsoids.size(); ++k)
        cloud.ellipsoids[k].centre = from.ellipsoids[k].centre;
      cloud.drift_m = from.drift_m;
    }
  }
  finishEdit();
  return "";
}

namespace {

void applyCloudChange(EllipsoidCloud& cloud, const CloudChange& c) {
  if (c.move) {
    for (Ellipsoid& e : cloud.ellipsoids) e.centre += *c.move;
    cloud.drift_m += *c.move;  // the texture moves with the cloud
  }
  if (c.threshold) cloud.threshold_centre = *c.threshold;
  if (c.limb_threshold) cloud.threshold_limb = *c.limb_threshold;
  if (c.transition) cloud.transition = *c.transition;
  if (c.colour) cloud.colour = *c.colour;
}

void applyPose(Target& t, const TargetPose& pose) {
  if (pose.centre) t.centre = *pose.centre;
  if (pose.heading) t.orientation.heading_deg = *pose.heading;
  if (pose.pitch) t.orientation.pitch_deg = *pose.pitch;
  if (pose.roll) t.orientation.roll_deg = *pose.roll;
}

// The index of the item called `name` in `items`, or none.
template <class T>
std::optional<std::size_t> indexOf(const std::vector<T>& items, const std::string& name) {
  const auto at =
      std::find_if(items.begin(), items.end(), [&](const T& x) { return x.name == name; });
  if (at == items.end()) return std::nullopt;
  return std::size_t(at - items.begin());
}

}  // namespace

std::string World::addCloud(const EllipsoidCloud& cloud) {
  if (indexOf(base_.clouds, cloud.name)) return "cloud.name: \"" + cloud.name + "\" is taken";
  editBase([&](Scene& base, WorldDynamics& dynamics) {
    base.clouds.push_back(cloud);
    if (!dynamics.clouds.empty()) dynamics.clouds.emplace_back();  // none, or one per cloud
  });
  now_.clouds.push_back(cloud);
  finishEdit();
  return "";
}

std::string World::changeCloud(const std::string& name, const CloudChange& c) {
  const std::optional<std::size_t> i = indexOf(base_.clouds, name);
  if (!i) return "name: no cloud is called \"" + name + "\"";
  editBase([&](Scene& base, WorldDynamics&) { applyCloudChange(base.clouds[*i], c); });
  applyCloudChange(now_.clouds[*i], c);
  finishEdit();
  return "";
}

std::string World::removeCloud(const std::string& name) {
  if (!indexOf(base_.clouds, name)) return "name: no cloud is called \"" + name + "\"";
  const auto called = [&](const EllipsoidCloud& cloud) { return cloud.name == name; };
  editBase([&](Scene& base, WorldDynamics& dynamics) {
    eraseWithDevelopment(base.clouds, dynamics.clouds, called);
  });
  std::erase_if(now_.clouds, called);
  finishEdit();
  return "";
}

std::string World::addTarget(const Target& target, bool replace, std::size_t max_targets) {
  const std::optional<std::size_t> i = indexOf(base_.targets, target.name);
  if (i && !replace) return "target.name: \"" + target.name + "\" is taken";
  if (!i && base_.targets.size() >= max_targets)
    return "target: the world holds " + std::to_string(max_targets) + " targets already";
  const auto place = [&](std::vector<Target>& targets) {
    if (i)
      targets[*i] = target;
    else
      targets.push_back(target);
  };
  editBase([&](Scene& base, WorldDynamics&) { place(base.targets); });
  place(now_.targets);
  finishEdit();
  return "";
}

std::string World::moveTarget(const std::string& name, const TargetPose& pose) {
  const std::optional<std::size_t> i = indexOf(base_.targets, name);
  if (!i) return "name: no target is called \"" + name + "\"";
  editBase([&](Scene& base, WorldDynamics&) { applyPose(base.targets[*i], pose); });
  applyPose(now_.targets[*i], pose);
  finishEdit();
  return "";
}

std::string World::removeTarget(const std::string& name) {
  if (!indexOf(base_.targets, name)) return "name: no target is called \"" + name + "\"";
  const auto called = [&](const Target& t) { return t.name == name; };
  editBase([&](Scene& base, WorldDynamics&) { std::erase_if(base.targets, called); });
  std::erase_if(now_.targets, called);
  finishEdit();
  return "";
}

void World::editBase(const std::function<void(Scene& base, WorldDynamics& dynamics)>& change,
                     bool wind_changes) {
  // The arithmetic of every edit since the world began (base_ and the drift are bit-exact
  // parts of its hash): the change sees positions as they are now.
  foldDrift(+1.0);
  change(base_, dynamics_);
  if (!dynamics_.wind.empty())
    for (CloudLayer& layer : base_.layers)
      layer.texture.drift_velocity = dynamics_.wind.at(layer.altitude_m);
  // The sea's wind is the surface wind (its waves are the wind's): it follows the wind's changes.
  if (base_.sea && !dynamics_.wind.empty() && wind_changes)
    base_.sea->wind = dynamics_.wind.at(0.0);
  foldDrift(-1.0);
  // The automata ride the new wind from where they are; the specs a restore builds them from
  // move with them.
  if (wind_changes)
    for (std::size_t i = 0; i < automata_.size(); ++i)
      dynamics_.automata[i].position +=
          glm::dvec3(automata_[i].setWind(dynamics_.wind, time_ns_), 0.0);
}

void World::finishEdit() {
  for (std::size_t i = 0; i < base_.layers.size(); ++i) {
    now_.layers[i].texture.drift_offset_m = base_.layers[i].texture.drift_offset_m;
    now_.layers[i].texture.drift_velocity = base_.layers[i].texture.drift_velocity;
  }
  now_stale_ = true;
  ++edits_;
}

const Scene& World::scene() const {
  if (now_stale_) applyTime();
  return now_;
}

const Scene& World::seenFrom(const Camera& camera) const {
  scene();
  now_.camera = camera;
  return now_;
}

void World::rebuildNow() {
  now_ = base_;
  now_stale_ = true;
}

void World::applyTime() const {
  // Every member time changes is set from base_'s, as base + v t: the same arithmetic whenever it
  // is applied, so that equal worlds hand out equal scenes.
  const double t = timeSeconds();
  now_.time_s = t;
  for (std::size_t i = 0; i < dynamics_.layers.size(); ++i) {
    const LayerDevelopment& d = dynamics_.layers[i];
    const CloudLayer& from = base_.layers[i];
    CloudLayer& layer = now_.layers[i];
    layer.threshold = d.threshold.at(t, from.threshold);
    layer.transition = d.transition.at(t, from.transition);
    if (!d.t0.empty()) layer.texture.gardner.t0 = quantisedT0(d.t0.at(t, 0.0));
  }
  for (std::size_t i = 0; i < dynamics_.clouds.size(); ++i) {
    const CloudDevelopment& d = dynamics_.clouds[i];
    const EllipsoidCloud& from = base_.clouds[i];
    EllipsoidCloud& cloud = now_.clouds[i];
    cloud.threshold_centre = d.threshold_centre.at(t, from.threshold_centre);
    cloud.threshold_limb = d.threshold_limb.at(t, from.threshold_limb);
    cloud.transition = d.transition.at(t, from.transition);
  }
  if (!dynamics_.wind.empty()) applyDrift(t);
  refreshAutomatonViews();
  now_stale_ = false;
}

void World::applyDrift(double t) const {
  for (std::size_t i = 0; i < base_.fields.size(); ++i) {
    const CloudField& from = base_.fields[i];
    CloudField& field = now_.fields[i];
    const glm::dvec2 carried = dynamics_.wind.at(fieldAltitude(from));
    field.drift_m = from.drift_m + carried * t;
    field.shear = dynamics_.wind.at(from.base_m + from.thickness_m) - carried;
  }
  for (std::size_t i = 0; i < base_.clouds.size(); ++i) {
    const EllipsoidCloud& from = base_.clouds[i];
    EllipsoidCloud& cloud = now_.clouds[i];
    const glm::dvec3 drift(dynamics_.wind.at(cloudAltitude(from)) * t, 0.0);
    for (std::size_t k = 0; k < from.ellipsoids.size(); ++k)
      cloud.ellipsoids[k].centre = from.ellipsoids[k].centre + drift;
    cloud.drift_m = from.drift_m + drift;
  }
}

void World::refreshAutomatonViews() const {
  now_.automata.clear();
  for (const AutomatonCloud& cloud : automata_) now_.automata.push_back(cloud.view(time_ns_));
}

}  // namespace nephele
