#include <spdlog/spdlog.h>

#include <filesystem>
#include <variant>

#include "config/table_reader.h"
#include "server/engine_detail.h"
#include "world/file_output.h"
#include "world/limits.h"

// Snapshots: the World saves its clouds, the weather layers as set, targets, sun, fog, haze,
// wind and clock; beside it (PATH.daemon.json) the daemon saves what the host set that the
// World does not hold: views, the sun's date, the clock's mode, scale and pause, and the tick
// and frame counters. The views are kept as the requests that set them, so a restore reads
// them through the one request parser, with its checks.
namespace nephele {

using namespace engine_detail;

namespace {

constexpr int kDaemonStateVersion = 2;
constexpr std::uintmax_t kMaxDaemonStateBytes = 4u << 20;

// A set_view request that sets every field of `v`.
json viewRequest(const ViewConfig& v) {
  json r = viewJson(v);
  r.erase("name");
  if (r.contains("frustum")) r.erase("vfov");  // the frustum gives it
  r["view"] = v.name;
  r["cmd"] = "set_view";
  return r;
}

}  // namespace

json Engine::daemonState() const {
  json requests = json::array();
  for (const ViewConfig& v : views_.all()) requests.push_back(viewRequest(v));
  json out{{"format", "nephele-daemon-state"}, {"version", kDaemonStateVersion},
           {"ticks", clock_.ticks()},          {"frames", telemetry_.frames()},
           {"mode", modeName(clock_.mode())},  {"time_scale", clock_.timeScale()},
           {"paused", clock_.paused()},        {"requests", requests}};
  if (sun_utc_) out["sun_utc"] = formatUtc(*sun_utc_);
  return out;
}

namespace {

// The daemon's part of a snapshot as read back: checked whole before anything is applied.
struct DaemonState {
  std::uint64_t ticks = 0, frames = 0;
  double time_scale = 1.0;
  bool paused = false;
  TickMode mode = TickMode::kRealtime;
  std::optional<CivilTime> sun_utc;
  std::vector<command::SetView> views;
};

// The one reader of a daemon state file's text, for restore and for the writer's proof; errors
// name the field.
std::variant<DaemonState, std::string> readDaemonState(const std::string& text) {
  json j = json::parse(text, nullptr, false);
  // json::value() throws when the key holds another type: every key is typed here first.
  auto has = [&](const char* key, json::value_t type) {
    return j.contains(key) && j[key].type() == type;
  };
  if (j.is_discarded() || !j.is_object() || !has("format", json::value_t::string) ||
      j["format"] != "nephele-daemon-state")
    return "not a daemon state file";
  if (!has("version", json::value_t::number_unsigned) || j["version"] != kDaemonStateVersion)
    return "version " + (j.contains("version") ? j["version"].dump() : "missing") + " is not " +
           std::to_string(kDaemonStateVersion);
  for (const char* key : {"ticks", "frames"})
    if (!j.contains(key) || !j[key].is_number_unsigned()) return std::string(key) + ": missing";
  DaemonState out;
  out.ticks = j["ticks"].get<std::uint64_t>();
  out.frames = j["frames"].get<std::uint64_t>();
  if (!j.contains("time_scale") || !j["time_scale"].is_number() ||
      !(j["time_scale"].get<double>() >= 0.0 &&
        j["time_scale"].get<double>() <= ProtocolLimits::kMaxTimeScale))
    return "time_scale: missing or out of range";
  out.time_scale = j["time_scale"].get<double>();
  if (!has("mode", json::value_t::string) || (j["mode"] != "realtime" && j["mode"] != "lockstep"))
    return "mode: not realtime or lockstep";
  out.mode = j["mode"] == "lockstep" ? TickMode::kLockstep : TickMode::kRealtime;
  if (!j.contains("paused") || !j["paused"].is_boolean()) return "paused: missing";
  out.paused = j["paused"].get<bool>();
  if (j.contains("sun_utc")) {
    CivilTime t;
    if (!j["sun_utc"].is_string()) return "sun_utc: not a string";
    if (std::string e = parseUtc(j["sun_utc"].get<std::string>(), t); !e.empty())
      return "sun_utc: " + e;
    out.sun_utc = t;
  }
  if (!j.contains("requests") || !j["requests"].is_array()) return "requests: missing";
  for (const json& r : j["requests"]) {
    auto parsed = parseRequest(r.dump());
    if (auto* b = std::get_if<BadRequest>(&parsed)) return b->error.message;
    auto* view = std::get_if<command::SetView>(&std::get<Request>(parsed).command);
    if (!view) return "requests: only set_view is restored";
    out.views.push_back(std::move(*view));
  }
  return out;
}

}  // namespace

std::string Engine::writeSnapshot(const std::string& path) {
  // Both parts are proven before either replaces the last: the daemon's text is read back by
  // restore's reader before anything is written, and the world's file before it is renamed.
  const std::string side = daemonStatePath(path);
  const std::string text = daemonState().dump(1) + "\n";
  if (const auto read = readDaemonState(text); const auto* e = std::get_if<std::string>(&read))
    return "daemon state: '" + side + "' not replaced: it would not read back: " + *e;
  if (std::string e = world_->saveSnapshot(path, std::size_t(config_.max_ellipsoids)); !e.empty())
    return e;
  return writeFileAtomically(
      side, std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()),
      "daemon state");
}

std::string Engine::restoreSnapshot(const std::string& path) {
  // The daemon's part is read and checked first, so that a bad file changes nothing.
  const std::string side = daemonStatePath(path);
  std::optional<DaemonState> state;
  if (std::filesystem::exists(side)) {
    std::error_code ec;
    if (std::filesystem::file_size(side, ec) > kMaxDaemonStateBytes || ec)
      return side + ": larger than 4 MiB or unreadable";
    std::string text;
    if (std::string e = config_detail::readTextFile(side, "daemon state", text); !e.empty())
      return e;
    auto read = readDaemonState(text);
    if (auto* e = std::get_if<std::string>(&read)) return side + ": " + *e;
    state = std::move(std::get<DaemonState>(read));
  }
  if (std::string e = world_->restoreSnapshot(path, std::size_t(config_.max_ellipsoids));
      !e.empty())
    return e;
  if (!state) return "";  // a snapshot from before daemon state was saved: the world alone
  clock_.restoreTicks(state->ticks);
  telemetry_.restoreFrames(state->frames);
  clock_.setTimeScale(state->time_scale);
  clock_.setPaused(state->paused);
  setMode(state->mode);
  sun_utc_ = state->sun_utc;
  for (const command::SetView& v : state->views) {
    ViewConfig* view = views_.find(v.view);
    if (!view) {  // the config no longer has it
      spdlog::warn("event=restore_view_skipped view={}", v.view);
      continue;
    }
    applyViewPatch(*view, v.patch);
  }
  return "";
}

std::string Engine::saveSnapshot(const std::string& path, const char* why) {
  const auto t0 = Clock::now();
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  if (std::string e = writeSnapshot(path); !e.empty()) {
    spdlog::error("event=snapshot_failed reason={} path={} error=\"{}\"", why, path, e);
    telemetry_.noteSnapshotFailed();
    return e;
  }
  spdlog::info("event=snapshot reason={} path={} time={:.3f} hash={} ticks={} ms={:.1f}", why, path,
               world_->timeSeconds(), hexHash(world_->hash()), clock_.ticks(), msSince(t0));
  return "";
}

}  // namespace nephele
