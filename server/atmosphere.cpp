#include <spdlog/spdlog.h>

#include "server/engine_state.h"
#include "world/counter_random.h"
#include "world/formations/weather.h"

// Weather and atmosphere at run time: weather layers onto formations (MODEL.md section 10),
// wind, ground fog, the sun by direction or by date and time (world/solar.h), and the clock's
// mode. The same for every transport: the socket, Modbus and CIGI all arrive as commands.
namespace nephele {

using namespace engine_detail;

namespace {

void setWindSample(WindProfile& profile, double altitude, glm::dvec2 velocity) {
  auto& samples = profile.samples;
  std::erase_if(samples,
                [&](const WindSample& w) { return std::abs(w.altitude_m - altitude) < 1.0; });
  samples.push_back({altitude, velocity});
  std::sort(samples.begin(), samples.end(),
            [](const WindSample& a, const WindSample& b) { return a.altitude_m < b.altitude_m; });
}

}  // namespace

std::optional<ProtocolError> Engine::setWeather(int layer, const WeatherLayer& weather,
                                                std::optional<int> region) {
  State& s = *state_;
  // The daemon's own names hold a '/', which no user name may (world/limits.h): set_weather
  // replaces exactly what it made before. A region's layers are its own, and seeded apart.
  const std::string prefix =
      (region ? "weather/region" + std::to_string(*region) + "/" : std::string("weather/")) +
      std::to_string(layer);
  std::uint64_t seed = weatherSeed(config_.scene.scene.seed, layer);
  if (region) seed = hashCounters(seed, 0x526567696f6eull, std::uint64_t(*region));
  const WeatherClouds add = weatherClouds(weather, prefix, seed);
  std::string error = s.world->edit([&](Scene& now, WorldDynamics& d) -> std::string {
    auto made = [&](const std::string& name) {
      return name == prefix || name.rfind(prefix + "/", 0) == 0;
    };
    eraseWithDevelopment(now.layers, d.layers, [&](const CloudLayer& l) { return made(l.name); });
    std::erase_if(now.fields, [&](const CloudField& f) { return made(f.name); });
    now.fields.insert(now.fields.end(), add.fields.begin(), add.fields.end());
    for (const CloudLayer& l : add.layers) {
      now.layers.push_back(l);
      if (!d.layers.empty()) d.layers.emplace_back();
    }
    if (weather.wind)
      setWindSample(d.wind, weather.base_m + 0.5 * weather.thickness_m, *weather.wind);
    return "";
  });
  if (!error.empty()) return ProtocolError{ErrorCode::kFailed, error};
  if (!region) s.weather[std::size_t(layer - 1)] = weather;  // what a host reads back
  spdlog::info(
      "event=weather layer={} region={} type={} base={} thickness={} coverage={:.2f} planes={} "
      "fields={}",
      layer, region ? std::to_string(*region) : "global", cloudTypeName(weather.type),
      weather.base_m, weather.thickness_m, weather.coverage, add.layers.size(), add.fields.size());
  return std::nullopt;
}

Outcome Engine::setSun(const command::SetSun& c) {
  State& s = *state_;
  Sun sun = s.world->base().sun;
  if (c.utc) {
    const glm::dvec2 place =
        c.place.value_or(glm::dvec2(config_.site.latitude_deg, config_.site.longitude_deg));
    const SolarPosition p = solarPosition(*c.utc, place.x, place.y);
    sun.azimuth_deg = p.azimuth_deg;
    sun.elevation_deg = p.elevation_deg;
    s.sun_utc = c.utc;
  }
  if (c.azimuth || c.elevation) s.sun_utc.reset();
  if (c.azimuth) sun.azimuth_deg = *c.azimuth;
  if (c.elevation) sun.elevation_deg = *c.elevation;
  s.world->setSun(sun);
  json out{{"azimuth", sun.azimuth_deg}, {"elevation", sun.elevation_deg}};
  if (s.sun_utc) out["utc"] = formatUtc(*s.sun_utc);
  return out;
}

Outcome Engine::setFog(const command::SetFog& c) {
  State& s = *state_;
  std::optional<Fog> fog = s.world->base().fog;
  if (c.enabled == false) {
    fog.reset();
  } else {
    if (!fog) fog.emplace();
    if (c.top) fog->top_m = *c.top;
    if (c.visibility) fog->visibility_m = *c.visibility;
    if (c.colour) fog->colour = *c.colour;
  }
  std::string error = s.world->edit([&](Scene& now, WorldDynamics&) {
    now.fog = fog;
    return std::string();
  });
  if (!error.empty()) return ProtocolError{ErrorCode::kFailed, error};
  if (!fog) return json{{"enabled", false}};
  return json{{"enabled", true},
              {"top", fog->top_m},
              {"visibility", fog->visibility_m},
              {"colour", {fog->colour.x, fog->colour.y, fog->colour.z}}};
}

Outcome Engine::setHaze(const command::SetHaze& c) {
  State& s = *state_;
  std::optional<Haze> haze = s.world->base().haze;
  if (c.enabled == false) {
    haze.reset();
  } else {
    if (!haze) haze.emplace();
    if (c.visibility) haze->visibility_m = *c.visibility;
    if (c.scale_height) haze->scale_height_m = *c.scale_height;
  }
  std::string error = s.world->edit([&](Scene& now, WorldDynamics&) {
    now.haze = haze;
    return std::string();
  });
  if (!error.empty()) return ProtocolError{ErrorCode::kFailed, error};
  if (!haze) return json{{"enabled", false}};
  return json{{"enabled", true},
              {"visibility", haze->visibility_m},
              {"scale_height", haze->scale_height_m}};
}

void Engine::setMode(TickMode mode) {
  State& s = *state_;
  if (mode == s.mode) return;
  s.mode = mode;
  lockstep_ = mode == TickMode::kLockstep;
  // Realtime ticks and subscription periods start from now, not from when they last ran.
  s.next_tick = Clock::now();
  for (Subscription& sub : s.subscriptions) sub.next_due = Clock::now();
  spdlog::info("event=mode mode={}", modeName(mode));
}

}  // namespace nephele
