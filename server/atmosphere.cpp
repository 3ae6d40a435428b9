#include <spdlog/spdlog.h>

#include "server/engine_detail.h"
#include "world/formations/weather.h"

// Weather and atmosphere at run time: weather layers onto formations (MODEL.md section 10),
// wind, ground fog, haze, the sea, the sun by direction or by date and time (world/solar.h),
// and the clock's mode. The same for every transport: the socket, Modbus and CIGI all arrive as
// commands.
namespace nephele {

using namespace engine_detail;

std::optional<ProtocolError> Engine::setWeather(int layer, const WeatherLayer& weather,
                                                std::optional<int> region) {
  const WeatherKey key{
      layer, region ? std::optional<std::uint16_t>(std::uint16_t(*region)) : std::nullopt};
  bool changed = false;
  if (std::string error = world_->setWeather(key, weather, &changed); !error.empty())
    return ProtocolError{ErrorCode::kFailed, error};
  if (changed)
    spdlog::info("event=weather layer={} region={} type={} base={} thickness={} coverage={:.2f}",
                 layer, region ? std::to_string(*region) : "global", cloudTypeName(weather.type),
                 weather.base_m, weather.thickness_m, weather.coverage);
  return std::nullopt;
}

Outcome Engine::setSun(const command::SetSun& c) {
  Sun sun = world_->base().sun;
  if (c.utc) {
    // At the place given, else at the database's origin; the azimuth from true north there
    // turned to the database's north (MODEL.md section 13).
    const std::optional<Site>& site = world_->base().site;
    const glm::dvec2 place = c.place.value_or(
        site ? glm::dvec2(site->latitude_deg, site->longitude_deg) : glm::dvec2(0.0));
    const SolarPosition p = solarPosition(*c.utc, place.x, place.y);
    sun.azimuth_deg = p.azimuth_deg;
    if (site) sun.azimuth_deg += LocalFrame(*site).northBearing({place.x, place.y, 0.0});
    sun.elevation_deg = p.elevation_deg;
    sun_utc_ = c.utc;
  }
  if (c.azimuth || c.elevation) sun_utc_.reset();
  if (c.azimuth) sun.azimuth_deg = *c.azimuth;
  if (c.elevation) sun.elevation_deg = *c.elevation;
  world_->setSun(sun);
  json out{{"azimuth", sun.azimuth_deg}, {"elevation", sun.elevation_deg}};
  if (sun_utc_) out["utc"] = formatUtc(*sun_utc_);
  return out;
}

Outcome Engine::setFog(const command::SetFog& c) {
  std::optional<Fog> fog = world_->base().fog;
  const bool read_back = !c.enabled && !c.top && !c.visibility && !c.colour;
  if (read_back) {
    // no field: the fog as it is
  } else if (c.enabled == false) {
    fog.reset();
  } else {
    if (!fog) fog.emplace();
    if (c.top) fog->top_m = *c.top;
    if (c.visibility) fog->visibility_m = *c.visibility;
    if (c.colour) fog->colour = *c.colour;
  }
  if (std::string error = world_->setFog(fog); !error.empty())
    return ProtocolError{ErrorCode::kFailed, error};
  if (!fog) return json{{"enabled", false}};
  return json{{"enabled", true},
              {"top", fog->top_m},
              {"visibility", fog->visibility_m},
              {"colour", {fog->colour.x, fog->colour.y, fog->colour.z}}};
}

Outcome Engine::setHaze(const command::SetHaze& c) {
  std::optional<Haze> haze = world_->base().haze;
  const bool read_back = !c.enabled && !c.visibility && !c.scale_height;
  if (read_back) {
    // no field: the haze as it is
  } else if (c.enabled == false) {
    haze.reset();
  } else {
    if (!haze) haze.emplace();
    if (c.visibility) haze->visibility_m = *c.visibility;
    if (c.scale_height) haze->scale_height_m = *c.scale_height;
  }
  if (std::string error = world_->setHaze(haze); !error.empty())
    return ProtocolError{ErrorCode::kFailed, error};
  if (!haze) return json{{"enabled", false}};
  return json{{"enabled", true},
              {"visibility", haze->visibility_m},
              {"scale_height", haze->scale_height_m}};
}

glm::dvec2 engine_detail::surfaceWind(const World& world) {
  const WindProfile& wind = world.dynamics().wind;
  return wind.empty() ? Sea{}.wind : wind.at(0.0);
}

std::variant<std::optional<Sea>, ProtocolError> engine_detail::seaAfter(
    const std::optional<Sea>& before, const command::SetSea& c, glm::dvec2 surface_wind) {
  if (c.enabled == false) return std::optional<Sea>();
  const bool adds_train =
      std::any_of(c.waves.begin(), c.waves.end(),
                  [](const command::WavePatch& w) { return w.enabled != false; });
  const bool enables =
      c.enabled || c.fetch || c.temperature || c.clarity || c.whitecaps || c.seed || adds_train;
  if (!before && !enables) return before;  // read back, or trains removed from no sea
  Sea sea;
  if (before)
    sea = *before;
  else
    sea.wind = surface_wind;
  if (c.fetch) sea.fetch_m = *c.fetch;
  if (c.temperature) sea.temperature_c = *c.temperature;
  if (c.clarity) sea.clarity = *c.clarity;
  if (c.whitecaps) sea.whitecaps = *c.whitecaps;
  if (c.seed) sea.seed = *c.seed;
  std::vector<WaveTrain>& trains = sea.trains;
  for (const command::WavePatch& w : c.waves) {
    auto train = std::find_if(trains.begin(), trains.end(),
                              [&](const WaveTrain& t) { return t.id == w.id; });
    if (w.enabled == false) {
      if (train != trains.end()) trains.erase(train);
      continue;
    }
    if (train == trains.end()) {  // kept in order of id
      train = std::find_if(trains.begin(), trains.end(),
                           [&](const WaveTrain& t) { return t.id > w.id; });
      train = trains.insert(train, WaveTrain{});
      train->id = w.id;
    }
    if (w.height) train->height_m = *w.height;
    if (w.wavelength) train->wavelength_m = *w.wavelength;
    if (w.period) train->period_s = *w.period;
    if (w.direction) train->direction_deg = *w.direction;
    if (w.phase) train->phase_deg = *w.phase;
  }
  if (trains.size() > std::size_t(kMaxWaveTrains))
    return badField("waves: the sea would hold " + std::to_string(trains.size()) +
                    " wave trains (allowed: at most " + std::to_string(kMaxWaveTrains) +
                    "; remove one with {\"id\": ID, \"enabled\": false})");
  return std::optional<Sea>(std::move(sea));
}

json engine_detail::seaJson(const std::optional<Sea>& sea) {
  if (!sea) return json{{"enabled", false}};
  json waves = json::array();
  for (const WaveTrain& t : sea->trains)
    waves.push_back({{"id", t.id},
                     {"height", t.height_m},
                     {"wavelength", t.wavelength_m},
                     {"period", t.period_s},
                     {"direction", t.direction_deg},
                     {"phase", t.phase_deg}});
  return json{{"enabled", true},         {"wind", {sea->wind.x, sea->wind.y}},
              {"fetch", sea->fetch_m},   {"temperature", sea->temperature_c},
              {"clarity", sea->clarity}, {"whitecaps", sea->whitecaps},
              {"seed", sea->seed},       {"waves", waves}};
}

Outcome Engine::setSea(const command::SetSea& c) {
  auto sea = seaAfter(world_->base().sea, c, surfaceWind(*world_));
  if (const auto* error = std::get_if<ProtocolError>(&sea)) return *error;
  const std::optional<Sea>& after = std::get<std::optional<Sea>>(sea);
  bool changed = false;
  if (std::string error = world_->setSea(after, &changed); !error.empty()) return badField(error);
  if (changed)
    spdlog::info("event=sea enabled={} trains={}", after.has_value(),
                 after ? after->trains.size() : 0);
  return seaJson(after);
}

nlohmann::json engine_detail::siteJson(const World& world) {
  const std::optional<Site>& site = world.base().site;
  if (!site) return json{{"placed", false}};
  const glm::dvec2 o = world.base().content_origin;
  return json{{"placed", true},
              {"latitude", site->latitude_deg},
              {"longitude", site->longitude_deg},
              {"grid", site->grid_deg},
              {"content_origin", {o.x, o.y}}};
}

Site engine_detail::siteAfter(const World& world, const command::SetSite& c) {
  Site site{*c.latitude, *c.longitude, 0.0};
  if (const std::optional<Site>& before = world.base().site)
    site = recentred(*before, site.latitude_deg, site.longitude_deg).to;
  if (c.grid) site.grid_deg = *c.grid;
  return site;
}

std::optional<ProtocolError> Engine::siteError(const command::SetSite& c) const {
  if (!c.latitude) return std::nullopt;
  const Site site = siteAfter(*world_, c);
  if (std::string error = world_->setSiteError(site); !error.empty()) return badField(error);
  // The views move with the world: none may be carried beyond where set_view places one.
  const glm::dvec2 shift = world_->recentreShift(site);
  for (const ViewConfig& v : views_.all()) {
    const glm::dvec3 to = v.camera.position - glm::dvec3(shift, 0.0);
    if (std::string e = placementError("view " + v.name, to.x, to.y, to.z); !e.empty())
      return badField(recentringRefusal(shift, e));
  }
  return std::nullopt;
}

Outcome Engine::setSite(const command::SetSite& c) {
  World& world = *world_;
  if (c.latitude) {
    if (auto error = siteError(c)) return *error;
    const Site site = siteAfter(world, c);
    const glm::dvec2 origin = world.base().content_origin;
    bool changed = false;
    if (std::string error = world.setSite(site, &changed); !error.empty()) return badField(error);
    // The views move with the world, so that each sees what it saw (a host places its own).
    const glm::dvec3 shift(world.base().content_origin - origin, 0.0);
    views_.shiftAll(shift);
    if (changed)
      spdlog::info("event=site latitude={:.6f} longitude={:.6f} grid={:.4f} moved={:.1f}",
                   site.latitude_deg, site.longitude_deg, site.grid_deg, glm::length(shift));
  }
  return siteJson(world);
}

}  // namespace nephele
