#include "protocol/cigi_session.h"

#include <cmath>
#include <numbers>
#include <set>
#include <sstream>

#include "protocol/cloud_codes.h"
#include "world/camera.h"
#include "world/formations/cloud_field.h"
#include "world/limits.h"
#include "world/sea.h"
#include "world/solar.h"

namespace nephele::cigi {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

std::string text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

bool finite(std::initializer_list<double> values) {
  for (double v : values)
    if (!std::isfinite(v)) return false;
  return true;
}

// CIGI body axes (x forward, y right, z down) to Nephele's (x right, y forward, z up).
glm::dvec3 fromCigiBody(double x, double y, double z) {
  return {y, x, -z};
}

// Wind blowing from `from_deg` (clockwise from north, as CIGI gives it) at `speed`, in the
// database's X, Y: `north` is the database bearing of true north (LocalFrame::northBearing).
glm::dvec2 windVelocity(double speed, double from_deg, double north) {
  from_deg += north;
  return -speed * glm::dvec2(std::sin(from_deg * kDeg), std::cos(from_deg * kDeg));
}

// The weather fields Nephele draws; a packet differing only elsewhere changes nothing.
bool sameCloudLayer(const WeatherControl& a, const WeatherControl& b) {
  return a.enabled == b.enabled && a.cloud_type == b.cloud_type && a.base == b.base &&
         a.thickness == b.thickness && a.coverage == b.coverage && a.wind_speed == b.wind_speed &&
         a.wind_direction == b.wind_direction && a.visibility == b.visibility &&
         a.transition_band == b.transition_band && a.scud == b.scud &&
         (!a.scud || a.scud_frequency == b.scud_frequency);
}

// A Weather Control cloud layer (1 to 3) as the layer it draws, or what is wrong with it
// (everywhere: the caller sets a regional layer's region).
std::variant<WeatherLayer, std::string> cloudLayerOf(const WeatherControl& w, double north) {
  WeatherLayer layer;
  const std::optional<CloudType> type = cloudTypeFromCode(w.cloud_type);
  if (w.enabled && !type)
    return "cloud type " + std::to_string(w.cloud_type) + " (allowed: " + cloudTypeCodesAllowed() +
           ")";
  layer.type = w.enabled ? *type : CloudType::kNone;
  layer.base_m = w.base;
  layer.thickness_m = w.thickness;
  layer.coverage = w.coverage / 100.0;
  if (!w.enabled) {  // removes the layer: its other fields need not be in range
    layer.base_m = std::clamp(layer.base_m, 0.0, Limits::kMaxBase);
    layer.thickness_m = std::clamp(layer.thickness_m, Limits::kThickness.lo, Limits::kThickness.hi);
    layer.coverage = std::clamp(layer.coverage, 0.0, 1.0);
    return layer;
  }
  if (!(layer.base_m >= 0.0 && layer.base_m <= Limits::kMaxBase) ||
      !Limits::kThickness.contains(layer.thickness_m) ||
      !Limits::kCoveragePercent.contains(w.coverage) ||
      !(w.wind_speed >= 0.0 && w.wind_speed <= Limits::kMaxWind))
    return "base " + text(w.base) + ", thickness " + text(w.thickness) + ", coverage " +
           text(w.coverage) + ", wind " + text(w.wind_speed) + " (allowed: base 0 to " +
           text(Limits::kMaxBase) + " m, thickness " + text(Limits::kThickness.lo) + " to " +
           text(Limits::kThickness.hi) + " m, coverage 0 to 100 %, wind 0 to " +
           text(Limits::kMaxWind) + " m/s)";
  layer.wind = windVelocity(w.wind_speed, w.wind_direction, north);
  // Inside the layer (MODEL.md section 5): its visibility (0, the genus's) and transition band.
  layer.visibility_m = w.visibility;
  layer.transition_band_m = w.transition_band;
  // Scud: fragments under the base covering the scud frequency (MODEL.md section 10), its
  // range checked with the rest of the layer's below.
  if (w.scud) layer.scud = w.scud_frequency / 100.0;
  if (std::string e = weatherLayerError(layer); !e.empty()) return e;
  return layer;
}

// A Weather Control precipitation layer (4 to 9: rain, snow, sleet, hail, sand, dust) as the
// layer it draws (MODEL.md section 17): no clouds, the precipitation from base to base +
// thickness, its visibility the packet's, else from its severity (a rate for rain, snow, sleet
// and hail; a visibility for sand and dust); or what is wrong with it. Disabled removes it.
std::variant<WeatherLayer, std::string> precipitationLayerOf(const WeatherControl& w) {
  WeatherLayer layer;
  if (!w.enabled) return layer;
  if (!finite({w.base, w.thickness, w.visibility}) ||
      !(w.base >= 0.0 && w.base <= Limits::kMaxBase) || !Limits::kThickness.contains(w.thickness))
    return "base " + text(w.base) + ", thickness " + text(w.thickness) + " (allowed: base 0 to " +
           text(Limits::kMaxBase) + " m, thickness " + text(Limits::kThickness.lo) + " to " +
           text(Limits::kThickness.hi) + " m)";
  layer.base_m = w.base;
  layer.thickness_m = w.thickness;
  Precipitation& p = layer.precipitation;
  p.kind = PrecipitationKind(w.layer - Layer::kCloud3);
  const bool obscurant = w.layer >= Layer::kSand;
  p.rate_mm_h = obscurant ? 0.0 : rateForSeverity(w.severity);
  p.visibility_m = w.visibility > 0.0 ? w.visibility
                   : obscurant        ? obscurantVisibilityForSeverity(w.severity)
                                      : 0.0;
  if (std::string e = weatherLayerError(layer); !e.empty()) return e;
  return layer;
}

// An active Environmental Region as the region of a weather layer (world/formations/region.h):
// its X axis (along `rotation`, clockwise from north) is the region's y axis, and CIGI's
// transition perimeter, outside the rectangle, becomes the band the cover fades over, so the
// rectangle grows by it on every side and the region's weather is whole inside it.
Region regionOf(const EnvironmentalRegionControl& e, const LocalFrame& database) {
  Region r;
  const glm::dvec3 centre = database.toLocal({e.latitude, e.longitude, 0.0});
  r.centre = {centre.x, centre.y};
  const double band = e.transition_perimeter;
  r.half_size = 0.5 * glm::dvec2(e.size_y, e.size_x) + band;
  r.heading_deg = e.rotation + database.northBearing({e.latitude, e.longitude, 0.0});
  r.edge_m = band;
  return r;
}

// What is wrong with an Environmental Region Control making its region active, or empty.
std::string regionControlError(const EnvironmentalRegionControl& e) {
  if (!finite({e.latitude, e.longitude, e.size_x, e.size_y, e.rotation, e.transition_perimeter,
               e.corner_radius}))
    return "a field is not a finite number";
  const Range size = Limits::kRegionSize, band = Limits::kRegionBand;
  if (std::abs(e.latitude) > 90.0 || std::abs(e.longitude) > 180.0 || !size.contains(e.size_x) ||
      !size.contains(e.size_y) || !band.contains(e.transition_perimeter) ||
      std::abs(e.rotation) > Limits::kMaxHeading)
    return "latitude " + text(e.latitude) + ", longitude " + text(e.longitude) + ", size " +
           text(e.size_x) + " x " + text(e.size_y) + ", rotation " + text(e.rotation) +
           ", transition perimeter " + text(e.transition_perimeter) +
           " (allowed: latitude -90 to 90, longitude -180 to 180, sizes " + text(size.lo) + " to " +
           text(size.hi) + " m, rotation -" + text(Limits::kMaxHeading) + " to " +
           text(Limits::kMaxHeading) + " degrees, transition perimeter " + text(band.lo) + " to " +
           text(band.hi) + " m)";
  return "";
}

// Equal, or both NaN: a field a host repeats with a NaN is not a change.
bool same(float a, float b) {
  return a == b || (std::isnan(a) && std::isnan(b));
}

constexpr const char* kSeaIsGlobal = "regional sea state is not modelled: the sea is global";

// "of region 7" or "of entity 7": where a packet of regional or entity scope applies.
std::string scopeOf(WeatherScope scope, std::uint16_t id) {
  const char* kind = scope == WeatherScope::kRegional ? "region"
                     : scope == WeatherScope::kEntity ? "entity"
                                                      : "scope 3 id";
  return std::string(" of ") + kind + " " + std::to_string(id);
}

// The Maritime Surface Conditions fields Nephele reads (docs/CIGI.md); a packet differing only
// elsewhere changes nothing, and a disabled one only in being disabled.
bool sameMaritime(const MaritimeSurfaceConditionsControl& a,
                  const MaritimeSurfaceConditionsControl& b) {
  if (!a.surface_conditions_enabled || !b.surface_conditions_enabled)
    return a.surface_conditions_enabled == b.surface_conditions_enabled;
  return a.whitecaps == b.whitecaps && same(a.water_temperature, b.water_temperature) &&
         same(a.clarity, b.clarity) && same(a.sea_surface_height, b.sea_surface_height);
}

// The same for Wave Control: its train's fields, and those it ignores but reports.
bool sameWave(const WaveControl& a, const WaveControl& b) {
  if (!a.enabled || !b.enabled) return a.enabled == b.enabled;
  return same(a.height, b.height) && same(a.wavelength, b.wavelength) && same(a.period, b.period) &&
         same(a.direction, b.direction) && same(a.phase_offset, b.phase_offset) &&
         a.breaker == b.breaker && same(a.leading, b.leading);
}

// What is wrong with an enabled Wave Control's train, or empty.
std::string waveError(const WaveControl& w) {
  if (!finite({w.height, w.wavelength, w.period, w.direction, w.phase_offset}) ||
      !Limits::kWaveHeight.contains(w.height) || !Limits::kWavelength.contains(w.wavelength) ||
      !Limits::kWavePeriod.contains(w.period) || !Limits::kWaveDirection.contains(w.direction) ||
      !Limits::kWavePhase.contains(w.phase_offset))
    return "height " + text(w.height) + ", wavelength " + text(w.wavelength) + ", period " +
           text(w.period) + ", direction " + text(w.direction) + ", phase offset " +
           text(w.phase_offset) + " (allowed: height " + text(Limits::kWaveHeight.lo) + " to " +
           text(Limits::kWaveHeight.hi) + " m, wavelength " + text(Limits::kWavelength.lo) +
           " to " + text(Limits::kWavelength.hi) + " m, period " + text(Limits::kWavePeriod.lo) +
           " to " + text(Limits::kWavePeriod.hi) + " s, direction and phase offset " +
           text(Limits::kWaveDirection.lo) + " to " + text(Limits::kWaveDirection.hi) + " degrees)";
  return "";
}

// A Wave Control as set_sea's train: CIGI's direction is where the wave propagates, clockwise
// from true north, the sea's from the database's north, whose bearing is `north`; disabled
// removes the train.
command::WavePatch wavePatchOf(const WaveControl& w, double north) {
  command::WavePatch p;
  p.id = w.wave_id;
  p.enabled = w.enabled;
  if (!w.enabled) return p;
  p.height = w.height;
  p.wavelength = w.wavelength;
  p.period = w.period;
  double direction = w.direction + north;  // kept in [0, 360)
  if (direction < 0.0) direction += 360.0;
  if (direction >= 360.0) direction -= 360.0;
  p.direction = direction;
  p.phase = w.phase_offset;
  return p;
}

// The UTC moment of a Celestial Sphere Control (date MMDDYYYY, hour, minute).
CivilTime civilTimeOf(const CelestialSphereControl& c) {
  CivilTime t;
  t.month = int(c.date / 1000000);
  t.day = int(c.date / 10000 % 100);
  t.year = int(c.date % 10000);
  t.hour = c.hour;
  t.minute = c.minute;
  t.second = 0.0;
  return t;
}

// The sun is placed again for the ownship once it has moved this far in latitude or
// longitude: the sun's direction then moves by about as much, 0.05 degree (5 km).
constexpr double kSunPlaceStepDeg = 0.05;

std::string entityName(std::uint16_t id) {
  return "cigi-" + std::to_string(id);
}

// A latitude and longitude on the Earth, as an entity may be placed at.
bool onEarth(double latitude, double longitude) {
  return std::isfinite(latitude) && std::isfinite(longitude) && std::abs(latitude) <= 90.0 &&
         std::abs(longitude) <= 360.0;
}

// The message's ownship (Entity Control 0, not attached) placed on the Earth: the last one.
const EntityControl* lastOwnship(const Message& message) {
  const EntityControl* ownship = nullptr;
  for (std::size_t i = 1; i < message.packets.size(); ++i)
    if (const auto* e = std::get_if<EntityControl>(&message.packets[i]);
        e && e->entity_id == 0 && !e->attached && onEarth(e->latitude, e->longitude))
      ownship = e;
  return ownship;
}

// With no [site] the host's first position on the Earth sets the database origin (docs/CIGI.md,
// "Where the database lies"): the ownship's, else the message's first active entity or region
// placed by latitude and longitude, whatever the packets' order.
std::optional<glm::dvec2> firstPlace(const Message& message, const EntityControl* ownship) {
  if (ownship) return glm::dvec2(ownship->latitude, std::remainder(ownship->longitude, 360.0));
  for (std::size_t i = 1; i < message.packets.size(); ++i) {
    const Packet& packet = message.packets[i];
    if (const auto* e = std::get_if<EntityControl>(&packet)) {
      if (e->entity_id != 0 && !e->attached && e->state == EntityState::kActive &&
          onEarth(e->latitude, e->longitude))
        return glm::dvec2(e->latitude, std::remainder(e->longitude, 360.0));
    } else if (const auto* r = std::get_if<EnvironmentalRegionControl>(&packet)) {
      if (r->state == RegionState::kActive && regionControlError(*r).empty())
        return glm::dvec2(r->latitude, std::remainder(r->longitude, 360.0));
    }
  }
  return std::nullopt;
}

}  // namespace

LocalFrame Session::databaseOf(const State& state) {
  return LocalFrame(state.site.value_or(Site{}));
}

std::optional<Session::Pose> Session::poseOf(const State& state, std::uint16_t id,
                                             int depth) const {
  const auto it = state.entities.find(id);
  if (it == state.entities.end()) {
    if (id == 0) return Pose{};  // the ownship before the host has placed it: the origin
    return std::nullopt;
  }
  const EntityControl& e = it->second.packet;
  if (e.attached && e.parent_id != id && depth < 16) {
    const glm::dmat3 own = bodyToWorld({e.yaw, e.pitch, e.roll});
    const std::optional<Pose> parent = poseOf(state, e.parent_id, depth + 1);
    if (!parent) return std::nullopt;
    return Pose{
        parent->position + parent->attitude * fromCigiBody(e.latitude, e.longitude, e.altitude),
        parent->attitude * own};
  }
  if (e.attached) return std::nullopt;  // attached to itself, or a chain deeper than 16
  // Its heading from true north there, turned to the database's north (MODEL.md section 13).
  const LocalFrame database = databaseOf(state);
  const Geodetic place{e.latitude, e.longitude, e.altitude};
  return Pose{database.toLocal(place),
              bodyToWorld({e.yaw + database.northBearing(place), e.pitch, e.roll})};
}

// One message's packets, in order, mapped onto the state they lead to and the commands they
// send. What the packets have changed is gathered here and placed once all are read: the sun
// (placeSun), the targets (placeTargets) and the views (placeViews).
class Session::Mapping {
 public:
  Mapping(const Session& session, State& s, MappedMessage& mapped)
      : session_(session),
        settings_(session.settings_),
        s_(s),
        mapped_(mapped),
        database_(databaseOf(s)),
        north_(-s.site.value_or(Site{}).grid_deg) {}

  void placeSite();
  void apply(const Packet& packet);
  void placeSun();
  void placeTargets();
  void placeViews();

 private:
  void entityControl(const EntityControl& e);
  void viewControl(const ViewControl& v);
  void viewDefinition(const ViewDefinition& d);
  void weatherControl(const WeatherControl& w);
  void precipitation(const WeatherControl& w, const std::string& where);
  void groundFog(const WeatherControl& w, const std::string& where);
  void cloudLayer(const WeatherControl& w, const std::string& where);
  void regionControl(const EnvironmentalRegionControl& e);
  void moveRegionalWeather(const EnvironmentalRegionControl& e);
  void atmosphereControl(const AtmosphereControl& a);
  void celestialControl(const CelestialSphereControl& c);
  void maritimeControl(const MaritimeSurfaceConditionsControl& m);
  void waveControl(const WaveControl& w);
  std::optional<command::SetView> viewCommand(std::uint16_t id);

  // A packet with a value out of range is refused alone; the message's other packets apply.
  void refuse(std::string what) { mapped_.refused.push_back(std::move(what)); }
  void ignore(std::string what) { mapped_.ignored.push_back(std::move(what)); }
  template <class C>
  void send(C command) {
    mapped_.commands.emplace_back(std::move(command));
  }
  // The [[entity_type]] a CIGI entity type is drawn as, or null.
  const std::string* typeName(std::uint16_t type) const {
    for (const auto& [id, name] : settings_.entity_types)
      if (id == type) return &name;
    return nullptr;
  }

  const Session& session_;
  const SessionSettings& settings_;
  State& s_;
  MappedMessage& mapped_;
  const LocalFrame database_;
  // The database bearing of true north at the origin, for what the host gives for the whole
  // world (its wind, its wave trains).
  const double north_;
  bool views_moved_ = false;
  std::set<std::uint16_t> changed_entities_;
};

// Every message says where its positions lie: the world adopts it, re-centres on it, or (a
// snapshot restored from elsewhere) moves its content there. The host's wind turns with the
// meridians at a re-centring, so that it stays true.
void Session::Mapping::placeSite() {
  if (s_.site)
    send(command::SetSite{s_.site->latitude_deg, s_.site->longitude_deg, s_.site->grid_deg});
  if (mapped_.recentred && s_.atmosphere)
    send(command::SetWind{
        windVelocity(s_.atmosphere->wind_speed, s_.atmosphere->wind_direction, north_)});
}

void Session::Mapping::apply(const Packet& packet) {
  if (const auto* e = std::get_if<EntityControl>(&packet))
    entityControl(*e);
  else if (const auto* v = std::get_if<ViewControl>(&packet))
    viewControl(*v);
  else if (const auto* d = std::get_if<ViewDefinition>(&packet))
    viewDefinition(*d);
  else if (const auto* w = std::get_if<WeatherControl>(&packet))
    weatherControl(*w);
  else if (const auto* r = std::get_if<EnvironmentalRegionControl>(&packet))
    regionControl(*r);
  else if (const auto* a = std::get_if<AtmosphereControl>(&packet))
    atmosphereControl(*a);
  else if (const auto* c = std::get_if<CelestialSphereControl>(&packet))
    celestialControl(*c);
  else if (const auto* m = std::get_if<MaritimeSurfaceConditionsControl>(&packet))
    maritimeControl(*m);
  else if (const auto* wave = std::get_if<WaveControl>(&packet))
    waveControl(*wave);
  else if (const auto* o = std::get_if<OtherPacket>(&packet))
    ignore("packet " + std::to_string(o->id) + " (not used by Nephele)");
}

// The ownship carries the views; another entity is a target of an [[entity_type]], placed
// once all packets are read (placeTargets), or removed when it is no longer active.
void Session::Mapping::entityControl(const EntityControl& e) {
  const std::string where = "Entity Control " + std::to_string(e.entity_id);
  if (!finite({e.roll, e.pitch, e.yaw, e.latitude, e.longitude, e.altitude}))
    return refuse(where + ": a position or angle is not a finite number");
  if (!e.attached && (std::abs(e.latitude) > 90.0 || std::abs(e.longitude) > 360.0))
    return refuse(where + ": latitude " + text(e.latitude) + ", longitude " + text(e.longitude) +
                  " (allowed: -90 to 90, -360 to 360 degrees)");
  if (e.entity_id == 0) {
    s_.entities[0] = {e, false};
    views_moved_ = true;
    return;
  }
  const auto known = s_.entities.find(e.entity_id);
  if (e.state != EntityState::kActive) {
    if (known != s_.entities.end()) {
      if (known->second.target) send(command::RemoveTarget{entityName(e.entity_id)});
      s_.entities.erase(known);
    }
    return;
  }
  if (!typeName(e.type))
    return ignore(where + ": entity type " + std::to_string(e.type) +
                  " is not in the daemon config's [[entity_type]]");
  if (known == s_.entities.end() || !(known->second.packet == e))
    changed_entities_.insert(e.entity_id);
  s_.entities[e.entity_id] = {e, true};
}

// A view's offset from the entity carrying it: the enabled fields change, the others stay.
void Session::Mapping::viewControl(const ViewControl& v) {
  if (v.view_id >= settings_.views.size())
    return ignore("View Control: view " + std::to_string(v.view_id) + " is not one of the " +
                  std::to_string(settings_.views.size()) + " views of [cigi] views");
  if (!finite({v.x, v.y, v.z, v.roll, v.pitch, v.yaw}))
    return refuse("View Control " + std::to_string(v.view_id) + ": an offset is not finite");
  ViewState& view = s_.views[v.view_id];
  ViewControl merged = view.control.value_or(ViewControl{});
  float* fields[] = {&merged.x, &merged.y, &merged.z, &merged.roll, &merged.pitch, &merged.yaw};
  const float values[] = {v.x, v.y, v.z, v.roll, v.pitch, v.yaw};
  for (int k = 0; k < 6; ++k)
    if (v.enables & (1 << k)) *fields[k] = values[k];
  merged.view_id = v.view_id;
  merged.entity_id = v.entity_id;
  merged.enables = 0x3f;
  view.control = merged;
  views_moved_ = true;
}

// A view's frustum.
void Session::Mapping::viewDefinition(const ViewDefinition& d) {
  if (d.view_id >= settings_.views.size())
    return ignore("View Definition: view " + std::to_string(d.view_id) +
                  " is not one of [cigi] views");
  if (std::string e = frustumError({d.left, d.right, d.bottom, d.top}); !e.empty())
    return refuse("View Definition " + std::to_string(d.view_id) + ": left " + text(d.left) +
                  ", right " + text(d.right) + ", bottom " + text(d.bottom) + ", top " +
                  text(d.top) + ": " + e.substr(9));
  if (d.orthographic) ignore("View Definition: orthographic projection");
  s_.views[d.view_id].definition = d;
  views_moved_ = true;
}

// Weather Control, by layer (docs/CIGI.md): precipitation (4 to 9) and ground fog (0) are
// global only; a cloud layer (1 to 3) is global, or drawn in a region.
void Session::Mapping::weatherControl(const WeatherControl& w) {
  const bool regional = w.scope == WeatherScope::kRegional;
  const std::string where =
      "Weather Control layer " + std::to_string(w.layer) +
      (regional ? " of region " + std::to_string(w.entity_region_id) : std::string());
  if (w.scope == WeatherScope::kEntity)
    return ignore(where + ": entity scope (global and regional weather are drawn)");
  if (w.layer > Layer::kDust) return ignore(where + ": not one of CIGI's defined layers (0 to 9)");
  if (w.layer > Layer::kCloud3) {
    if (regional) return ignore(where + ": a region's precipitation is not drawn (global only)");
    return precipitation(w, where);
  }
  const bool fog = w.layer == Layer::kGroundFog;
  if (fog && regional) return ignore(where + ": ground fog is global only");
  // The world holds the weather as set and ignores a layer set again as it is (a host
  // repeats its packets every frame); a region's packets are also kept here, since they
  // may come before the region is active and follow it when it moves.
  if (regional)
    if (auto last = s_.regional_weather.find({w.entity_region_id, w.layer});
        last != s_.regional_weather.end() && sameCloudLayer(last->second, w))
      return;
  if (!finite({w.base, w.thickness, w.coverage, w.visibility, w.wind_speed, w.wind_direction}))
    return refuse(where + ": a field is not a finite number");
  if (fog) return groundFog(w, where);
  cloudLayer(w, where);
}

void Session::Mapping::precipitation(const WeatherControl& w, const std::string& where) {
  auto layer = precipitationLayerOf(w);
  if (const auto* e = std::get_if<std::string>(&layer)) return refuse(where + ": " + *e);
  send(command::SetWeather{w.layer, std::get<WeatherLayer>(layer), std::nullopt});
}

// Ground fog from the ground to the layer's top (base + thickness).
void Session::Mapping::groundFog(const WeatherControl& w, const std::string& where) {
  command::SetFog c;
  c.enabled = w.enabled;
  if (w.enabled) {
    const double top = double(w.base) + double(w.thickness);
    if (!(top >= 0.0 && top <= Limits::kMaxAltitude) ||
        !Limits::kFogVisibility.contains(w.visibility))
      return refuse(where + ": fog top (base + thickness) " + text(top) + " and visibility " +
                    text(w.visibility) + " (allowed: top 0 to " + text(Limits::kMaxAltitude) +
                    " m, visibility " + text(Limits::kFogVisibility.lo) + " to " +
                    text(Limits::kFogVisibility.hi) + " m)");
    c.top = top;
    c.visibility = w.visibility;
  }
  send(c);
}

// A cloud layer, global or of a region: a region's layer is drawn while its region is active
// (Environmental Region Control), and kept until then.
void Session::Mapping::cloudLayer(const WeatherControl& w, const std::string& where) {
  auto layer = cloudLayerOf(w, north_);
  if (const auto* e = std::get_if<std::string>(&layer)) return refuse(where + ": " + *e);
  if (w.scope != WeatherScope::kRegional)
    return send(command::SetWeather{w.layer, std::get<WeatherLayer>(layer), std::nullopt});
  s_.regional_weather[{w.entity_region_id, w.layer}] = w;
  const auto region = s_.regions.find(w.entity_region_id);
  if (region == s_.regions.end())
    return ignore(where + ": no Environmental Region Control has made region " +
                  std::to_string(w.entity_region_id) + " active yet (drawn once one does)");
  WeatherLayer& drawn = std::get<WeatherLayer>(layer);
  drawn.region = regionOf(region->second, database_);
  send(command::SetWeather{w.layer, drawn, w.entity_region_id});
}

// A region made active, moved, made inactive or destroyed; its layers follow it.
void Session::Mapping::regionControl(const EnvironmentalRegionControl& e) {
  const std::uint16_t id = e.region_id;
  const std::string where = "Environmental Region Control " + std::to_string(id);
  const auto last = s_.regions.find(id);
  const bool active = e.state == RegionState::kActive;
  if (active && last != s_.regions.end() && last->second == e) return;
  if (!active && last == s_.regions.end() && e.state != RegionState::kDestroyed) return;
  if (active) {
    std::string error = regionControlError(e);
    if (error.empty()) error = regionError(regionOf(e, database_));
    if (!error.empty()) return refuse(where + ": " + error);
    if (e.corner_radius != 0.0f) ignore(where + ": corner radius (the corners are drawn square)");
    if (e.merge_weather)
      ignore(where +
             ": merging (the region's layers are drawn over the global ones, not blended with "
             "them)");
    s_.regions[id] = e;
  } else {
    s_.regions.erase(id);
  }
  moveRegionalWeather(e);
}

// A region's layers drawn in its new place, or removed (inactive, destroyed); a destroyed
// region's layers are forgotten.
void Session::Mapping::moveRegionalWeather(const EnvironmentalRegionControl& e) {
  const std::uint16_t id = e.region_id;
  const bool active = e.state == RegionState::kActive;
  for (auto it = s_.regional_weather.begin(); it != s_.regional_weather.end();) {
    if (it->first.region != id) {
      ++it;
      continue;
    }
    command::SetWeather c{it->first.layer, {}, id};
    if (active) {
      c.weather = std::get<WeatherLayer>(cloudLayerOf(it->second, north_));  // checked when stored
      c.weather.region = regionOf(e, database_);
    }
    send(c);
    it = e.state == RegionState::kDestroyed ? s_.regional_weather.erase(it) : std::next(it);
  }
}

// The wind and the global visibility apply on their own: a bad one is refused alone, and what
// was applied is what the next packet is compared with.
void Session::Mapping::atmosphereControl(const AtmosphereControl& a) {
  AtmosphereControl applied = s_.atmosphere.value_or(AtmosphereControl{});
  if (!s_.atmosphere || applied.wind_speed != a.wind_speed ||
      applied.wind_direction != a.wind_direction) {
    if (!finite({a.wind_speed, a.wind_direction}) ||
        !(a.wind_speed >= 0.0 && a.wind_speed <= Limits::kMaxWind)) {
      refuse("Atmosphere Control: wind speed " + text(a.wind_speed) + " (allowed: 0 to " +
             text(Limits::kMaxWind) + " m/s)");
    } else {
      send(command::SetWind{windVelocity(a.wind_speed, a.wind_direction, north_)});
      applied.wind_speed = a.wind_speed;
      applied.wind_direction = a.wind_direction;
    }
  }
  // Global visibility is the distance haze over everything (MODEL.md section 5), with the
  // haze's default scale height; 0 is no haze.
  if (!s_.atmosphere || applied.visibility != a.visibility) {
    const double v = a.visibility;
    if (!finite({v}) || (v != 0.0 && !Limits::kHazeVisibility.contains(v))) {
      refuse("Atmosphere Control: visibility " + text(v) + " (allowed: 0 for none, or " +
             text(Limits::kHazeVisibility.lo) + " to " + text(Limits::kHazeVisibility.hi) + " m)");
    } else {
      send(v == 0.0 ? command::SetHaze{false, {}, {}} : command::SetHaze{true, v, {}});
      applied.visibility = a.visibility;
    }
  }
  s_.atmosphere = applied;
}

// The host's date and time, for the sun placed once all packets are read (placeSun).
void Session::Mapping::celestialControl(const CelestialSphereControl& c) {
  if (!c.date_valid) return;  // the ICD: date and time not to be applied
  if (s_.celestial && s_.celestial->date == c.date && s_.celestial->hour == c.hour &&
      s_.celestial->minute == c.minute)
    return;
  if (std::string e = civilTimeError(civilTimeOf(c)); !e.empty())
    return refuse("Celestial Sphere Control: date " + std::to_string(c.date) + " (MMDDYYYY) " +
                  std::to_string(c.hour) + ":" + std::to_string(c.minute) + ": " + e);
  s_.celestial = c;
  s_.sun_place.reset();
}

// The sea's surface conditions: enabled, it takes the host's enabled wave trains with it.
void Session::Mapping::maritimeControl(const MaritimeSurfaceConditionsControl& m) {
  const std::string where = "Maritime Surface Conditions Control";
  if (m.scope != WeatherScope::kGlobal)
    return ignore(where + scopeOf(m.scope, m.entity_region_id) + ": " + kSeaIsGlobal);
  if (s_.maritime && sameMaritime(*s_.maritime, m)) return;
  command::SetSea c;
  c.enabled = m.surface_conditions_enabled;
  if (m.surface_conditions_enabled) {
    const Range clarity{0.0, 100.0};
    if (!finite({m.water_temperature, m.clarity}) ||
        !Limits::kSeaTemperature.contains(m.water_temperature) || !clarity.contains(m.clarity))
      return refuse(where + ": surface water temperature " + text(m.water_temperature) +
                    ", surface clarity " + text(m.clarity) + " (allowed: temperature " +
                    text(Limits::kSeaTemperature.lo) + " to " + text(Limits::kSeaTemperature.hi) +
                    " degrees C, clarity 0 to 100 %)");
    c.temperature = m.water_temperature;
    c.clarity = m.clarity / 100.0;
    c.whitecaps = m.whitecaps;
    // The host's wave trains, which a sea it disabled lost with it.
    for (const auto& [id, wave] : s_.waves)
      if (wave.enabled) c.waves.push_back(wavePatchOf(wave, north_));
    if (m.sea_surface_height != 0.0f &&
        !(s_.maritime && s_.maritime->surface_conditions_enabled &&
          same(s_.maritime->sea_surface_height, m.sea_surface_height)))
      ignore(where + ": sea surface height " + text(m.sea_surface_height) +
             " m (the sea lies at the database's Z = 0)");
  }
  send(std::move(c));
  s_.maritime = m;
}

// One wave train, at most kMaxWaveTrains enabled at once. A sea the host disabled takes its
// trains when it enables it again (maritimeControl).
void Session::Mapping::waveControl(const WaveControl& w) {
  const std::string where = "Wave Control " + std::to_string(w.wave_id);
  if (w.scope != WeatherScope::kGlobal)
    return ignore(where + scopeOf(w.scope, w.entity_region_id) + ": " + kSeaIsGlobal);
  const auto last = s_.waves.find(w.wave_id);
  if (last != s_.waves.end() && sameWave(last->second, w)) return;
  if (w.enabled) {
    if (std::string e = waveError(w); !e.empty()) return refuse(where + ": " + e);
    const auto held = std::count_if(s_.waves.begin(), s_.waves.end(), [&](const auto& entry) {
      return entry.second.enabled && entry.first != w.wave_id;
    });
    if (held >= kMaxWaveTrains)
      return refuse(where + ": the host's " + std::to_string(held) +
                    " other wave trains are enabled (allowed: at most " +
                    std::to_string(kMaxWaveTrains) + " at once; disable one first)");
    const bool was = last != s_.waves.end() && last->second.enabled;
    if (w.breaker != BreakerType::kPlunging && !(was && last->second.breaker == w.breaker))
      ignore(where + ": breaker type " + std::to_string(int(w.breaker)) +
             " (not modelled: the trains are sines)");
    if (w.leading != 0.0f && !(was && same(last->second.leading, w.leading)))
      ignore(where + ": leading " + text(w.leading) +
             " degrees (not modelled: the trains are sines)");
  }
  s_.waves[w.wave_id] = w;
  if (s_.maritime && !s_.maritime->surface_conditions_enabled) return;
  command::SetSea c;
  c.waves.push_back(wavePatchOf(w, north_));
  send(std::move(c));
}

// The sun of the host's date where the ownship is (MODEL.md section 13), not at the site: a
// long flight sees it move.
void Session::Mapping::placeSun() {
  if (!s_.celestial) return;
  glm::dvec2 place =
      s_.site ? glm::dvec2(s_.site->latitude_deg, s_.site->longitude_deg) : glm::dvec2(0.0);
  if (const auto own = s_.entities.find(0);
      own != s_.entities.end() && !own->second.packet.attached)
    place = {own->second.packet.latitude, std::remainder(own->second.packet.longitude, 360.0)};
  const bool moved = !s_.sun_place || std::abs(place.x - s_.sun_place->x) > kSunPlaceStepDeg ||
                     std::abs(std::remainder(place.y - s_.sun_place->y, 360.0)) > kSunPlaceStepDeg;
  if (!moved) return;
  send(command::SetSun{std::nullopt, std::nullopt, civilTimeOf(*s_.celestial), place});
  s_.sun_place = place;
}

// Targets after the entities they hang from: every changed entity, and every attached one
// (its parent may have moved). An entity refused here keeps what was last applied for it,
// so that the world and the session agree on which targets exist.
void Session::Mapping::placeTargets() {
  const State& applied = session_.state_;
  std::vector<std::uint16_t> refused_entities;
  for (const auto& [id, entity] : s_.entities) {
    if (!entity.target || !(changed_entities_.count(id) || entity.packet.attached)) continue;
    const std::optional<Pose> pose = session_.poseOf(s_, id);
    if (!pose) {
      ignore("Entity Control " + std::to_string(id) +
             ": attached to an entity the host has not placed");
      continue;
    }
    if (std::abs(pose->position.x) > Limits::kMaxCoordinate ||
        std::abs(pose->position.y) > Limits::kMaxCoordinate ||
        std::abs(pose->position.z) > Limits::kMaxCoordinate) {
      refuse("Entity Control " + std::to_string(id) + ": " + text(pose->position.x) + ", " +
             text(pose->position.y) + " m from the origin (allowed: within " +
             text(Limits::kMaxCoordinate) + " m)");
      refused_entities.push_back(id);
      continue;
    }
    const Orientation o = orientationOf(pose->attitude);
    if (applied.entities.count(id) && applied.entities.at(id).target)
      send(command::MoveTarget{entityName(id), pose->position, o.heading_deg, o.pitch_deg,
                               o.roll_deg});
    else
      send(
          command::AddTarget{{},
                             true,
                             command::EntityPlacement{entityName(id), *typeName(entity.packet.type),
                                                      pose->position, o}});
  }
  for (const std::uint16_t id : refused_entities) {
    if (const auto it = applied.entities.find(id); it != applied.entities.end())
      s_.entities[id] = it->second;
    else
      s_.entities.erase(id);
  }
}

// Every view again once the ownship, an offset or a frustum has changed.
void Session::Mapping::placeViews() {
  if (!views_moved_) return;
  for (std::uint16_t id = 0; id < settings_.views.size(); ++id)
    if (std::optional<command::SetView> c = viewCommand(id)) send(std::move(*c));
}

// A view at its offset from the entity carrying it, with its frustum; none when the entity is
// not placed or the view would lie below the ground or too far out.
std::optional<command::SetView> Session::Mapping::viewCommand(std::uint16_t id) {
  const ViewState view = s_.views.count(id) ? s_.views.at(id) : ViewState{};
  const ViewControl control = view.control.value_or(ViewControl{});
  const std::optional<Pose> carrier = session_.poseOf(s_, control.entity_id);
  if (!carrier) {
    ignore("View Control " + std::to_string(id) + ": entity " + std::to_string(control.entity_id) +
           " is not placed");
    return std::nullopt;
  }
  command::SetView c;
  c.view = settings_.views[id];
  ViewPatch& p = c.patch;
  const glm::dvec3 position =
      carrier->position + carrier->attitude * fromCigiBody(control.x, control.y, control.z);
  if (position.z < 0.0 || std::abs(position.x) > Limits::kMaxCoordinate ||
      std::abs(position.y) > Limits::kMaxCoordinate || position.z > Limits::kMaxCoordinate) {
    refuse("view " + std::to_string(id) + " at " + text(position.x) + ", " + text(position.y) +
           ", " + text(position.z) + " m (allowed: at or above the ground, within " +
           text(Limits::kMaxCoordinate) + " m of the origin)");
    return std::nullopt;
  }
  p.position = position;
  const Orientation o =
      orientationOf(carrier->attitude * bodyToWorld({control.yaw, control.pitch, control.roll}));
  p.heading = o.heading_deg;
  p.pitch = o.pitch_deg;
  p.roll = o.roll_deg;
  if (view.definition) {  // an off-axis view when the frustum is asymmetric
    const ViewDefinition& d = *view.definition;
    p.frustum = Frustum{d.left, d.right, d.bottom, d.top};
  }
  return c;
}

// Host frame numbering (docs/CIGI.md, "Frame numbers"): a late, repeated or jumped number is
// refused, until enough consecutive frames show a new run of the host. Otherwise `s` takes
// the message's number and timestamp, and `mapped` the host's frame time.
std::optional<Refusal> Session::takeFrameNumber(const IgControl& igc, State& s,
                                                MappedMessage& mapped) const {
  if (s.last_host_frame) {
    const std::int32_t ahead = std::int32_t(igc.host_frame - *s.last_host_frame);
    if (ahead <= 0 || ahead > kMaxFrameJump) {
      const bool late = ahead <= 0 && ahead > -kReorderWindow;
      const int run = s.jumped_to && igc.host_frame == *s.jumped_to + 1 ? s.jump_run + 1 : 1;
      if (run < (late ? kRestartRunBehind : kRestartRunElsewhere))
        return Refusal{
            late ? "out_of_order" : "frame_jump",
            "host frame " + std::to_string(igc.host_frame) + " after " +
                std::to_string(*s.last_host_frame) +
                (late ? " (a late or repeated datagram)" : " (a restart or a corrupted number)"),
            igc, late ? IgStatus::kLate : IgStatus::kFrameJump, run};
      s.last_timestamp.reset();  // a new run of the host: its clock starts again too
    }
  }
  s.jumped_to.reset();
  s.jump_run = 0;
  mapped.dt_s = settings_.default_frame_s;
  if (igc.timestamp_valid && s.last_timestamp)
    mapped.dt_s =
        double(std::uint32_t(igc.timestamp - *s.last_timestamp)) / double(kTimestampTicksPerSecond);
  mapped.dt_s = std::clamp(mapped.dt_s, 0.0, Limits::kMaxTick);
  s.last_host_frame = igc.host_frame;
  if (igc.timestamp_valid) s.last_timestamp = igc.timestamp;
  return std::nullopt;
}

// Re-centring (MODEL.md section 13): once the ownship is farther than the settings' distance
// from the origin, the origin moves to it, snapped to a 1/64-degree lattice so that every
// flight over a place re-centres there alike. The ownship is this message's, unless its
// altitude is refused, else the one last applied. None: the origin stays.
std::optional<Site> Session::recentredSite(const State& s, const EntityControl* ownship) const {
  if (!s.site || !(settings_.recentre_m > 0.0)) return std::nullopt;
  std::optional<Geodetic> own;
  if (ownship && std::isfinite(ownship->altitude))
    own = Geodetic{ownship->latitude, ownship->longitude, 0.0};
  else if (const auto it = s.entities.find(0);
           it != s.entities.end() && !it->second.packet.attached)
    own = Geodetic{it->second.packet.latitude, it->second.packet.longitude, 0.0};
  if (!own || !(glm::length(glm::dvec2(databaseOf(s).toLocal(*own))) > settings_.recentre_m))
    return std::nullopt;
  const double latitude = std::clamp(std::round(own->latitude_deg * 64.0) / 64.0, -90.0, 90.0);
  const double longitude = std::remainder(std::round(own->longitude_deg * 64.0) / 64.0, 360.0);
  return recentred(*s.site, latitude, longitude).to;
}

std::variant<Session::State, Refusal> Session::next(const Message& message,
                                                    MappedMessage& mapped) const {
  State s = state_;
  mapped.control = std::get<IgControl>(message.packets.front());
  if (std::optional<Refusal> refusal = takeFrameNumber(mapped.control, s, mapped)) return *refusal;
  if (mapped.control.mode == IgMode::kStandby) {
    if (message.packets.size() > 1)
      mapped.ignored.push_back(
          "IG Control mode is standby/reset: the message's other packets are not applied");
    return s;
  }
  const EntityControl* ownship = lastOwnship(message);
  if (!s.site) {
    if (const std::optional<glm::dvec2> place = firstPlace(message, ownship))
      s.site = Site{place->x, place->y, 0.0};
    mapped.site_adopted = s.site;
  }
  if (std::optional<Site> site = recentredSite(s, ownship)) {
    s.site = site;
    mapped.recentred = s.site;
  }
  Mapping mapping(*this, s, mapped);
  mapping.placeSite();
  for (std::size_t i = 1; i < message.packets.size(); ++i) mapping.apply(message.packets[i]);
  mapping.placeSun();
  mapping.placeTargets();
  mapping.placeViews();
  return s;
}

std::variant<MappedMessage, Refusal> Session::map(const Message& message) {
  MappedMessage mapped;
  auto result = next(message, mapped);
  pending_.reset();
  if (auto* r = std::get_if<Refusal>(&result)) {
    // A jump is remembered at once, refused or not, so that the next frame can confirm it.
    state_.jumped_to = r->control.host_frame;
    state_.jump_run = r->run;
    return *r;
  }
  pending_ = std::move(std::get<State>(result));
  return mapped;
}

void Session::forget() {
  pending_.reset();
  std::erase_if(state_.entities, [](const auto& entry) { return entry.second.target; });
  state_.atmosphere.reset();
  state_.maritime.reset();
  state_.waves.clear();
  state_.celestial.reset();
  state_.sun_place.reset();
}

void Session::commit() {
  if (pending_) state_ = std::move(*pending_);
  pending_.reset();
}

}  // namespace nephele::cigi
