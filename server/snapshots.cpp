#include <spdlog/spdlog.h>

#include <filesystem>

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

std::string daemonStatePath(const std::string& snapshot) {
  return snapshot + ".daemon.json";
}

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

std::string Engine::writeSnapshot(const std::string& path) {
  if (std::string e = world_->saveSnapshot(path); !e.empty()) return e;
  const std::string text = daemonState().dump(1) + "\n";
  return writeFileAtomically(
      daemonStatePath(path),
      std::span(reinterpret_cast<const std::uint8_t*>(text.data()), text.size()), "daemon state");
}

std::string Engine::restoreSnapshot(const std::string& path) {
  // The daemon's part is read and checked first, so that a bad file changes nothing.
  const std::string side = daemonStatePath(path);
  std::optional<json> state;
  std::vector<Command> requests;
  std::optional<CivilTime> sun_utc;
  if (std::filesystem::exists(side)) {
    auto bad = [&](const std::string& what) { return side + ": " + what; };
    std::error_code ec;
    if (std::filesystem::file_size(side, ec) > kMaxDaemonStateBytes || ec)
      return bad("larger than 4 MiB or unreadable");
    std::string text;
    if (std::string e = config_detail::readTextFile(side, "daemon state", text); !e.empty())
      return e;
    json j = json::parse(text, nullptr, false);
    // json::value() throws when the key holds another type: every key is typed here first.
    auto has = [&](const char* key, json::value_t type) {
      return j.contains(key) && j[key].type() == type;
    };
    if (j.is_discarded() || !j.is_object() || !has("format", json::value_t::string) ||
        j["format"] != "nephele-daemon-state")
      return bad("not a daemon state file");
    if (!has("version", json::value_t::number_unsigned) || j["version"] != kDaemonStateVersion)
      return bad("version " + (j.contains("version") ? j["version"].dump() : "missing") +
                 " is not " + std::to_string(kDaemonStateVersion));
    for (const char* key : {"ticks", "frames"})
      if (!j.contains(key) || !j[key].is_number_unsigned())
        return bad(std::string(key) + ": missing");
    if (!j.contains("time_scale") || !j["time_scale"].is_number() ||
        !(j["time_scale"].get<double>() >= 0.0 &&
          j["time_scale"].get<double>() <= ProtocolLimits::kMaxTimeScale))
      return bad("time_scale: missing or out of range");
    if (!has("mode", json::value_t::string) || (j["mode"] != "realtime" && j["mode"] != "lockstep"))
      return bad("mode: not realtime or lockstep");
    if (!j.contains("paused") || !j["paused"].is_boolean()) return bad("paused: missing");
    if (j.contains("sun_utc")) {
      CivilTime t;
      if (!j["sun_utc"].is_string()) return bad("sun_utc: not a string");
      if (std::string e = parseUtc(j["sun_utc"].get<std::string>(), t); !e.empty())
        return bad("sun_utc: " + e);
      sun_utc = t;
    }
    if (!j.contains("requests") || !j["requests"].is_array()) return bad("requests: missing");
    for (const json& r : j["requests"]) {
      auto parsed = parseRequest(r.dump());
      if (auto* b = std::get_if<BadRequest>(&parsed)) return bad(b->error.message);
      Command c = std::get<Request>(parsed).command;
      if (!std::holds_alternative<command::SetView>(c))
        return bad("requests: only set_view is restored");
      requests.push_back(std::move(c));
    }
    state = std::move(j);
  }
  if (std::string e = world_->restoreSnapshot(path, std::size_t(config_.max_ellipsoids));
      !e.empty())
    return e;
  if (!state) return "";  // a snapshot from before daemon state was saved: the world alone
  clock_.restoreTicks((*state)["ticks"].get<std::uint64_t>());
  telemetry_.restoreFrames((*state)["frames"].get<std::uint64_t>());
  clock_.setTimeScale((*state)["time_scale"].get<double>());
  clock_.setPaused((*state)["paused"].get<bool>());
  setMode((*state)["mode"] == "lockstep" ? TickMode::kLockstep : TickMode::kRealtime);
  sun_utc_ = sun_utc;
  for (const Command& c : requests) {
    if (const auto* v = std::get_if<command::SetView>(&c)) {
      ViewConfig* view = views_.find(v->view);
      if (!view) {  // the config no longer has it
        spdlog::warn("event=restore_view_skipped view={}", v->view);
        continue;
      }
      applyViewPatch(*view, v->patch);
    }
  }
  return "";
}

bool Engine::saveSnapshot(const std::string& path, const char* why) {
  const auto t0 = Clock::now();
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  if (std::string e = writeSnapshot(path); !e.empty()) {
    spdlog::error("event=snapshot_failed reason={} error=\"{}\"", why, e);
    telemetry_.noteError(ErrorCode::kFailed);
    return false;
  }
  spdlog::info("event=snapshot reason={} path={} time={:.3f} hash={} ticks={} ms={:.1f}", why, path,
               world_->timeSeconds(), hexHash(world_->hash()), clock_.ticks(), msSince(t0));
  return true;
}

}  // namespace nephele
