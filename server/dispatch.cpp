#include <algorithm>
#include <filesystem>

#include "config/scene_file.h"
#include "server/engine_detail.h"
#include "world/counter_random.h"
#include "world/limits.h"

// Requests: checked (check), then carried out on the world thread (apply), one handler per
// command of protocol/messages.h.
namespace nephele {

using namespace engine_detail;
using namespace command;

namespace {

// A name's 64-bit FNV-1a hash, for seeding clouds by name.
std::uint64_t nameHash(const std::string& name) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : name) h = (h ^ c) * 0x100000001b3ull;
  return h;
}

json targetJson(const Target& t, std::size_t object_id) {
  static constexpr const char* kShapes[] = {"box", "ellipsoid", "mesh"};
  return {{"name", t.name},
          {"shape", kShapes[int(t.shape)]},
          {"centre", {t.centre.x, t.centre.y, t.centre.z}},
          {"heading", t.orientation.heading_deg},
          {"pitch", t.orientation.pitch_deg},
          {"roll", t.orientation.roll_deg},
          {"size", {t.size.x, t.size.y, t.size.z}},
          {"object_id", object_id}};
}

}  // namespace

std::optional<ProtocolError> Engine::check(const Command& command) const {
  if (const auto* c = std::get_if<command::SetView>(&command)) {
    const ViewConfig* view = views_.find(c->view);
    if (!view) return views_.unknown(c->view);
    ViewConfig changed = *view;
    applyViewPatch(changed, c->patch);
    if (auto error = renders_->pixelLimit(changed)) return error;
    if (auto error = platformLimit(changed, changed.image)) return error;
  }
  if (const auto* c = std::get_if<command::Tick>(&command)) {
    if (!clock_.lockstep())
      return ProtocolError{ErrorCode::kFailed,
                           "tick: the daemon runs in realtime mode, where it ticks itself (switch "
                           "with set_time mode \"lockstep\", or use set_time advance)"};
    return checkAdvance(c->dt);
  }
  if (const auto* c = std::get_if<command::SetTime>(&command); c && c->advance)
    return checkAdvance(*c->advance);
  if (const auto* c = std::get_if<command::SetSite>(&command)) return siteError(*c);
  if (const auto* c = std::get_if<command::SetSea>(&command))  // the trains it would hold
    if (auto sea = seaAfter(world_->base().sea, *c, surfaceWind(*world_));
        std::holds_alternative<ProtocolError>(sea))
      return std::get<ProtocolError>(sea);
  return std::nullopt;
}

// One handler per command of protocol/commands.inc, on the world thread: a command added to
// the protocol without one here does not compile (Engine::apply visits them).
struct Engine::Handlers {
  Engine& engine;
  Job& job;
  World& world = *engine.world_;
  Views& views = engine.views_;
  WorldClock& clock = engine.clock_;
  const DaemonConfig& config_ = engine.config_;

  ProtocolError noSnapshotDirectory() const {
    return {ErrorCode::kFailed, "name: no snapshot directory is configured ([snapshot] directory)"};
  }
  std::string snapshotPath(const std::string& name) const {
    return (std::filesystem::path(config_.snapshotDirectory()) / (name + ".snap")).string();
  }

  std::optional<Outcome> operator()(const Hello& c) const {
    (void)c;  // the token is checked by the transport
    return engine.helloJson();
  }
  std::optional<Outcome> operator()(const GetView& c) const {
    if (c.view.empty()) {
      json all = json::array();
      for (const ViewConfig& v : views.all()) all.push_back(viewJson(v));
      return json{{"views", all}};
    }
    const ViewConfig* v = views.find(c.view);
    if (!v) return views.unknown(c.view);
    return viewJson(*v);
  }
  std::optional<Outcome> operator()(const SetView& c) const {
    ViewConfig* v = views.find(c.view);
    if (!v) return views.unknown(c.view);
    applyViewPatch(*v, c.patch);
    return viewJson(*v);
  }
  std::optional<Outcome> operator()(const SetWeather& c) const {
    if (auto error = engine.setWeather(c.layer, c.weather, c.region)) return *error;
    json reply{{"layer", c.layer},
               {"type", cloudTypeName(c.weather.type)},
               {"layers", world.base().layers.size()},
               {"clouds", world.base().clouds.size()},
               {"fields", world.base().fields.size()}};
    if (c.region) reply["region"] = *c.region;
    return reply;
  }
  std::optional<Outcome> operator()(const SetWind& c) const {
    std::string error = world.setWind({{{0.0, c.velocity}}});
    if (!error.empty()) return ProtocolError{ErrorCode::kFailed, error};
    return json{{"velocity", {c.velocity.x, c.velocity.y}}};
  }
  std::optional<Outcome> operator()(const SetSun& c) const { return engine.setSun(c); }
  std::optional<Outcome> operator()(const SetFog& c) const { return engine.setFog(c); }
  std::optional<Outcome> operator()(const SetHaze& c) const { return engine.setHaze(c); }
  std::optional<Outcome> operator()(const SetSea& c) const { return engine.setSea(c); }
  std::optional<Outcome> operator()(const SetSite& c) const { return engine.setSite(c); }
  std::optional<Outcome> operator()(const SetTime& c) const {
    if (c.time_scale) clock.setTimeScale(*c.time_scale);
    if (c.paused) clock.setPaused(*c.paused);
    if (c.mode) engine.setMode(*c.mode);
    if (c.advance) engine.advance(*c.advance);
    return json{{"time", world.timeSeconds()},
                {"time_scale", clock.timeScale()},
                {"paused", clock.paused()},
                {"mode", modeName(clock.mode())},
                {"ticks", clock.ticks()}};
  }
  std::optional<Outcome> operator()(const AddCloud& c) const {
    const auto name = c.cloud.find("name");
    if (name == c.cloud.end() || !name->is_string())
      return badField("cloud.name: is missing (a unique name, to change or remove the cloud by)");
    if (std::string e = nameError(name->get<std::string>()); !e.empty())
      return badField("cloud.name: " + e);
    EllipsoidCloud cloud;
    const std::string cloud_name = name->get<std::string>();
    if (std::string e = parseCloudJson(
            c.cloud, hashCounters(config_.scene.scene.seed, nameHash(cloud_name)), cloud);
        !e.empty())
      return badField(e);
    std::size_t ellipsoids = cloud.ellipsoids.size();
    // The world budget (docs/RELIABILITY.md): refused with `limit`, nothing added.
    if (world.base().clouds.size() >= kMaxClouds)
      return ProtocolError{ErrorCode::kLimit, "cloud: the world holds " +
                                                  std::to_string(kMaxClouds) +
                                                  " clouds already (the most it may)"};
    if (const std::size_t held = ellipsoidCount(world.base());
        held + ellipsoids > std::size_t(config_.max_ellipsoids))
      return ProtocolError{ErrorCode::kLimit,
                           "cloud: its " + std::to_string(ellipsoids) +
                               " ellipsoids would make the world's " + std::to_string(held) +
                               " more than its budget of " +
                               std::to_string(config_.max_ellipsoids) +
                               " ([world] max_ellipsoids in the daemon config; about " +
                               std::to_string(Limits::kBytesPerEllipsoid) + " bytes each)"};
    if (std::string error = world.addCloud(cloud); !error.empty()) return badField(error);
    return json{{"name", cloud.name}, {"ellipsoids", ellipsoids}};
  }
  std::optional<Outcome> operator()(const ChangeCloud& c) const {
    std::string error =
        world.changeCloud(c.name, {c.move, c.threshold, c.limb_threshold, c.transition, c.colour});
    if (!error.empty()) return ProtocolError{ErrorCode::kNotFound, error};
    return json{{"name", c.name}};
  }
  std::optional<Outcome> operator()(const RemoveCloud& c) const {
    std::string error = world.removeCloud(c.name);
    if (!error.empty()) return ProtocolError{ErrorCode::kNotFound, error};
    return json{{"name", c.name}};
  }
  std::optional<Outcome> operator()(const AddTarget& c) const {
    Target target;
    if (c.entity) {  // a CIGI entity: its type's prototype at its pose
      const auto type = std::find_if(config_.entity_types.begin(), config_.entity_types.end(),
                                     [&](const EntityType& t) { return t.name == c.entity->type; });
      if (type == config_.entity_types.end())
        return badField("target.type: \"" + c.entity->type +
                        "\" is not an entity type of the daemon config");
      target = type->prototype;
      target.name = c.entity->name;
      target.centre = c.entity->centre;
      target.orientation = c.entity->orientation;
    } else if (std::string e = parseTargetJson(c.target, config_.entity_types, target);
               !e.empty()) {
      return badField(e);
    }
    // A CIGI entity the world already holds (after a restart) is replaced.
    std::string error =
        world.addTarget(target, c.replace, std::size_t(ProtocolLimits::kMaxTargets));
    if (!error.empty()) return badField(error);
    return targetJson(target, world.base().targets.size());
  }
  std::optional<Outcome> operator()(const MoveTarget& c) const {
    if (std::string error = world.moveTarget(c.name, {c.centre, c.heading, c.pitch, c.roll});
        !error.empty())
      return ProtocolError{ErrorCode::kNotFound, error};
    const std::vector<Target>& targets = world.base().targets;
    const auto moved = std::find_if(targets.begin(), targets.end(),
                                    [&](const Target& t) { return t.name == c.name; });
    return targetJson(*moved, std::size_t(moved - targets.begin()) + 1);
  }
  std::optional<Outcome> operator()(const RemoveTarget& c) const {
    std::string error = world.removeTarget(c.name);
    if (!error.empty()) return ProtocolError{ErrorCode::kNotFound, error};
    return json{{"name", c.name}};
  }
  std::optional<Outcome> operator()(const ListTargets&) const {
    json all = json::array();
    const std::vector<Target>& targets = world.base().targets;
    for (std::size_t i = 0; i < targets.size(); ++i) all.push_back(targetJson(targets[i], i + 1));
    return json{{"targets", all}};
  }
  std::optional<Outcome> operator()(const Tick& c) const {
    engine.advance(c.dt);
    return json{{"time", world.timeSeconds()}, {"ticks", clock.ticks()}};
  }
  std::optional<Outcome> operator()(const Render& c) const { return engine.renderRequest(c, job); }
  std::optional<Outcome> operator()(const Subscribe& c) const {
    const ViewConfig* v = views.find(c.view);
    if (!v) return views.unknown(c.view);
    if (int(views.subscriptions().size()) >= config_.max_subscriptions)
      return ProtocolError{ErrorCode::kLimit, "subscribe: the daemon serves " +
                                                  std::to_string(config_.max_subscriptions) +
                                                  " subscriptions already (the configured limit)"};
    if (auto error = engine.platformLimit(*v, c.image.value_or(v->image))) return *error;
    Subscription sub;
    sub.client = job.client;
    sub.view = c.view;
    sub.image = c.image.value_or(v->image);
    sub.period = secondsToDuration(1.0 / c.rate_hz);
    sub.next_due = Clock::now();
    sub.sink = job.push;
    sub.gone = std::make_shared<std::atomic<bool>>(false);
    sub.id = views.subscribe(sub);
    return json{{"subscription", sub.id},
                {"view", sub.view},
                {"rate", c.rate_hz},
                {"format", imageFormatName(sub.image.format)},
                {"channels", channelNames(sub.image)}};
  }
  std::optional<Outcome> operator()(const Unsubscribe& c) const {
    if (!views.unsubscribe(c.subscription, job.client))
      return ProtocolError{ErrorCode::kNotFound,
                           "subscription: " + std::to_string(c.subscription) +
                               " is not one of this connection's subscriptions"};
    return json{{"subscription", c.subscription}};
  }
  std::optional<Outcome> operator()(const Stream& c) const { return engine.startStream(c); }
  std::optional<Outcome> operator()(const Unstream& c) const { return engine.stopStream(c); }
  std::optional<Outcome> operator()(const Snapshot& c) const {
    if (config_.snapshotDirectory().empty()) return noSnapshotDirectory();
    // saveSnapshot makes the snapshot directory when it is missing.
    if (std::string e = engine.saveSnapshot(snapshotPath(c.name), "request"); !e.empty())
      return ProtocolError{ErrorCode::kFailed, e};
    return json{{"name", c.name}, {"time", world.timeSeconds()}, {"hash", hexHash(world.hash())}};
  }
  std::optional<Outcome> operator()(const Restore& c) const {
    if (config_.snapshotDirectory().empty()) return noSnapshotDirectory();
    const std::string path = snapshotPath(c.name);
    if (!std::filesystem::exists(path))
      return ProtocolError{ErrorCode::kNotFound, "name: no snapshot \"" + c.name + "\""};
    if (std::string e = engine.restoreSnapshot(path); !e.empty())
      return ProtocolError{
          e.starts_with(World::kOverBudget) ? ErrorCode::kLimit : ErrorCode::kFailed, e};
    return json{{"name", c.name},
                {"time", world.timeSeconds()},
                {"hash", hexHash(world.hash())},
                {"ticks", clock.ticks()},
                {"frames", engine.telemetry_.frames()}};
  }
  std::optional<Outcome> operator()(const Stats&) const {
    engine.publish();
    return engine.stats();
  }
  std::optional<Outcome> operator()(const Hash&) const {
    return json{{"hash", hexHash(world.hash())},
                {"time", world.timeSeconds()},
                {"time_ns", world.timeNs()},
                {"ticks", clock.ticks()}};
  }
};

std::optional<Outcome> Engine::apply(const Command& command, Job& job) {
  return std::visit(Handlers{*this, job}, command);
}

}  // namespace nephele
