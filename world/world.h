#pragma once
// The World: every cloud (layers, ellipsoid clouds, automaton clouds), the sun, wind by
// altitude and simulation time. advance(dt) moves it on; scene() is what a render sees now.
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "world/automaton/automaton_cloud.h"
#include "world/formations/weather.h"
#include "world/limits.h"
#include "world/scene.h"
#include "world/schedule.h"

namespace nephele {

// How a layer develops over time (clear to overcast): thresholds and contrast offset.
struct LayerDevelopment {
  Schedule threshold;   // T1
  Schedule transition;  // D
  Schedule t0;          // Gardner's contrast offset (rebakes the texture when it changes)
};

struct CloudDevelopment {
  Schedule threshold_centre;  // T1
  Schedule threshold_limb;    // T2
  Schedule transition;        // D
};

// Everything about a world that changes with time, beside the scene at time 0.
struct WorldDynamics {
  WindProfile wind;  // drifts layers, ellipsoid clouds and automaton grids; shears automata
  std::vector<LayerDevelopment> layers;  // empty, or one per scene layer
  std::vector<CloudDevelopment> clouds;  // empty, or one per ellipsoid cloud
  std::vector<AutomatonCloudSpec> automata;
};

// Empty when `dynamics` fits `scene` and is usable, else what is wrong.
std::string worldDynamicsError(const Scene& scene, const WorldDynamics& dynamics);

// Removes the entries of `items` (and the matching development entries, if any) for which
// `drop` holds.
template <class T, class D, class Pred>
void eraseWithDevelopment(std::vector<T>& items, std::vector<D>& development, Pred drop) {
  std::vector<T> kept_items;
  std::vector<D> kept_development;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (drop(items[i])) continue;
    kept_items.push_back(std::move(items[i]));
    if (!development.empty()) kept_development.push_back(std::move(development[i]));
  }
  items = std::move(kept_items);
  development = std::move(kept_development);
}

// A change to an ellipsoid cloud (the socket protocol's change_cloud): what is given changes.
struct CloudChange {
  std::optional<glm::dvec3> move;  // metres to move by; the texture moves with the cloud
  std::optional<double> threshold, limb_threshold, transition;
  std::optional<glm::dvec3> colour;
};
// A target's pose, in part: what is given changes.
struct TargetPose {
  std::optional<glm::dvec3> centre;
  std::optional<double> heading, pitch, roll;
};

// The names of what weather layer `key` makes: "weather/2", or "weather/region7/2" for a CIGI
// region's layer. Every name the world makes holds a '/', which no user name may
// (world/limits.h), so nothing a user added is ever replaced.
std::string weatherPrefix(const WeatherKey& key);
// Appends `clouds` (weatherClouds') to `scene`, its layers with no development beside them.
void appendWeatherClouds(Scene& scene, WorldDynamics& dynamics, const WeatherClouds& clouds);
// Sets weather layer `key` of `scene` to `weather` (type kNone removes it): records it in
// scene.weather and replaces the layers and fields it made before with weatherClouds' (MODEL.md
// section 10), seeded by the scene's seed and the key, so that the same layer from a scene
// file, set_weather, Modbus or CIGI draws the same sky. A layer naming a wind sets the wind at
// its middle. An invalid layer (weatherLayerError) is refused and nothing changes.
std::string placeWeather(Scene& scene, WorldDynamics& dynamics, const WeatherKey& key,
                         const WeatherLayer& weather);

// What is wrong with `sea` (a field out of its range in world/limits.h, a wind above
// Limits::kMaxWind, more than kMaxWaveTrains trains, two trains of one id), or empty: the one
// check of a whole sea, shared by scene files, requests and snapshots.
std::string seaError(const Sea& sea);

// What is wrong with `site` (a latitude or longitude out of world/limits.h's range, a grid
// north that is not a finite number), or empty: the one check of a site, shared by set_site
// and snapshots.
std::string siteError(const Site& site);
// The refusal of a re-centring by `shift` that would carry something out of range (`error`
// names it and the range): set_site's one wording, for the world's content and the daemon's
// views alike.
std::string recentringRefusal(glm::dvec2 shift, const std::string& error);

class World {
 public:
  // Simulation time is kept in whole nanoseconds, so that split advances add up exactly.
  static constexpr double kTimeResolutionS = 1e-9;

  // `scene` is the world at time 0 (its time_s is ignored); `threads` runs the automaton.
  World(const Scene& scene, const WorldDynamics& dynamics, int threads = 1);
  ~World();
  World(World&&) noexcept;
  World& operator=(World&&) noexcept;

  // Moves time on by dt seconds (rounded to the nanosecond): drift, development schedules and
  // automaton steps at their fixed interval. Returns an error (and changes nothing) for a
  // negative, non-finite or too large dt (Limits::kMaxAdvance).
  std::string advance(double dt_s);
  // The error advance(dt_s) would return, without advancing.
  std::string advanceError(double dt_s) const;
  // Moves time on by dt_s seconds, up to Limits::kMaxTime (a scene's latest start), in at
  // least `pieces` advances of at most Limits::kMaxAdvance each, landing on the same
  // nanosecond as one advance would; `after_piece(i, n)` runs after piece i of n (for a
  // progress line). On an error nothing after the failed piece happens.
  std::string advanceInPieces(double dt_s, int pieces = 1,
                              const std::function<void(int, int)>& after_piece = {});
  std::int64_t timeNs() const { return time_ns_; }
  double timeSeconds() const { return double(time_ns_) * kTimeResolutionS; }
  // Automaton steps run since construction or restore, summed over clouds.
  std::uint64_t automatonStepsRun() const { return steps_run_; }
  // Sunlight sweeps recomputed after the sun moved, summed over automaton clouds.
  std::uint64_t relightsRun() const { return relights_run_; }

  // Edits made since construction: what the world holds changed (a view that reuses earlier
  // frames starts anew after one).
  std::uint64_t edits() const { return edits_; }

  // Relights automaton clouds only if the sun's direction changed.
  void setSun(const Sun& sun);

  // Typed edits: each checks first and returns an error that changes nothing, or changes the
  // world in place, copying no scene. Layers, ellipsoid clouds, wind and their development
  // change while time, the sun and automaton clouds carry on; an edit sees the world as it
  // stands now (positions include the drift so far), and a layer or cloud whose wind changes
  // stays where it is and drifts on with the new wind. `changed` (if given) says whether the
  // world differs afterwards: a host repeating what it sent last changes nothing and costs a
  // comparison.
  std::string setWeather(const WeatherKey& key, const WeatherLayer& weather,
                         bool* changed = nullptr);
  std::string setFog(const std::optional<Fog>& fog, bool* changed = nullptr);
  std::string setHaze(const std::optional<Haze>& haze, bool* changed = nullptr);
  // The sea in place of the ground (none: the ground plane); an invalid one (seaError) is
  // refused. Its wind is the surface wind: every edit that changes the world's wind sets it to
  // the wind at altitude 0.
  std::string setSea(const std::optional<Sea>& sea, bool* changed = nullptr);
  // Where the database lies on the Earth (MODEL.md section 13). A world placed nowhere takes
  // `site` as it is. Otherwise the world re-centres: everything it holds (clouds, fields,
  // layers and their regions, weather, targets, automata, the sea, the camera) moves by the
  // new origin's place in the old database, so that it keeps its place on the Earth; a grid
  // north other than the one the move implies (recentred()) turns nothing. A site out of
  // range is refused.
  std::string setSite(const Site& site, bool* changed = nullptr);
  // What setSite(site) would refuse, changing nothing: a site out of range, or a re-centring
  // that would carry a target beyond the range its readers accept (placementError). The move
  // itself is recentreShift(site): the new origin in the database as it stands (zero for a
  // world placed nowhere, or one already there).
  std::string setSiteError(const Site& site) const;
  glm::dvec2 recentreShift(const Site& site) const;
  // The wind by altitude (layers, clouds and fields drift on from where they are; the sea
  // takes the wind at altitude 0). A profile worldDynamicsError refuses is refused.
  std::string setWind(const WindProfile& wind);
  // Ellipsoid clouds and targets by name (names are unique within each kind); a cloud keeps
  // its development schedules beside it and loses them with it. Errors name the key.
  std::string addCloud(const EllipsoidCloud& cloud);
  std::string changeCloud(const std::string& name, const CloudChange& change);
  std::string removeCloud(const std::string& name);
  // With `replace` a target of the same name is replaced (a CIGI entity the world already
  // holds after a restart); otherwise the name must be free and the world hold fewer than
  // `max_targets`.
  std::string addTarget(const Target& target, bool replace, std::size_t max_targets);
  std::string moveTarget(const std::string& name, const TargetPose& pose);
  std::string removeTarget(const std::string& name);

  // The render's view of the world now: drift, development schedules and the automata's views
  // applied. Brought up to date on the first read after a change (advance, an edit, setSun,
  // restore), once however many advances came before it, and valid until the next change.
  // Reading it may write the world's state now: like every other member, call it from one
  // thread at a time.
  const Scene& scene() const;
  // scene() seen from `camera`, without a copy: the state now with its camera set. A view's
  // camera is not the world's state (snapshots and hash() read base_), so this changes no hash;
  // scene() keeps the camera until the next seenFrom or change.
  const Scene& seenFrom(const Camera& camera) const;
  const Scene& base() const { return base_; }
  const WorldDynamics& dynamics() const { return dynamics_; }
  const std::vector<AutomatonCloud>& automata() const { return automata_; }

  // A hash of the whole state (XXH3 of the snapshot): equal worlds give equal hashes.
  std::uint64_t hash() const;
  // Snapshots restore bit-exactly. Errors name what is wrong; on error the world is unchanged.
  // A snapshot whose clouds hold more than `max_ellipsoids` is refused (a daemon's world
  // budget, which may be lower than the one the snapshot was written under), with an error
  // that begins with kOverBudget.
  static constexpr std::string_view kOverBudget = "snapshot: over the world's budget: ";
  std::vector<std::uint8_t> snapshot() const;
  std::string restore(std::span<const std::uint8_t> bytes,
                      std::size_t max_ellipsoids = Limits::kMaxWorldEllipsoids);
  // Writes the snapshot beside `path`, reads it back with restoreSnapshot's reader (under
  // `max_ellipsoids`) and only then renames it over `path`: a file that would not read back is
  // not installed, and the previous one stays.
  std::string saveSnapshot(const std::string& path,
                           std::size_t max_ellipsoids = Limits::kMaxWorldEllipsoids) const;
  std::string restoreSnapshot(const std::string& path,
                              std::size_t max_ellipsoids = Limits::kMaxWorldEllipsoids);

 private:
  World(const Scene& scene, const WorldDynamics& dynamics, int threads, bool warm_up);
  void refreshAutomata();
  void advanceNs(std::int64_t dt_ns);  // checked by the caller
  // Moves the drift up to now into (sign +1) or out of (sign -1) base_.
  void foldDrift(double sign);
  // Changes base_ and dynamics_ by `change`, already checked, as the world stands now: the drift
  // folded in, the change, the layers' drift velocities from the wind (and the sea's wind from
  // the surface wind when `wind_changes`), the drift folded out again.
  void editBase(const std::function<void(Scene& base, WorldDynamics& dynamics)>& change,
                bool wind_changes = false);
  // After editBase and the same change to now_'s parts that time does not set: now_'s layers
  // take base_'s drift, time is applied on the next read, and the edit is counted.
  void finishEdit();
  template <class T>
  std::string setPart(std::optional<T> Scene::*part, const std::optional<T>& value, bool* changed);
  // now_ from base_ (after base_ was made), or brought to the world's time in place: the
  // development schedules, the wind's drift (applyDrift) and the automata's views.
  void rebuildNow();
  void applyTime() const;
  void applyDrift(double t) const;
  void refreshAutomatonViews() const;

  Scene base_;  // the world at time 0 (drift folded out)
  // The world at time_ns_, what scene() hands out: its parts time does not set always equal
  // base_'s, the parts time sets (applyTime) are brought up to date when read after a change.
  mutable Scene now_;
  mutable bool now_stale_ = true;
  WorldDynamics dynamics_;
  int threads_ = 1;
  std::int64_t time_ns_ = 0;
  std::uint64_t steps_run_ = 0;
  std::uint64_t relights_run_ = 0;
  std::uint64_t edits_ = 0;
  std::vector<AutomatonCloud> automata_;
};

}  // namespace nephele
