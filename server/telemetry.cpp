#include <sstream>

#include "server/engine_state.h"

// Telemetry: the stats reply, the Modbus readings and the Prometheus text.
namespace nephele {

using namespace engine_detail;

void Engine::publish() {
  State& s = *state_;
  const auto now = Clock::now();
  if (s.tick_history.empty() || now - s.tick_history.back().first >= std::chrono::seconds(1)) {
    s.tick_history.push_back({now, s.ticks});
    if (s.tick_history.size() > 6) s.tick_history.pop_front();
  }
  double ticks_per_second = 0.0;
  if (s.tick_history.size() >= 2) {
    const auto& [t0, n0] = s.tick_history.front();
    const double seconds = std::chrono::duration<double>(now - t0).count();
    if (seconds > 0.0) ticks_per_second = double(s.ticks - n0) / seconds;
  }
  const std::vector<double> history(s.render_ms.begin(), s.render_ms.end());
  const World& world = *s.world;
  json stats = {
      {"time", world.timeSeconds()},
      {"ticks", s.ticks},
      {"ticks_per_second", ticks_per_second},
      {"mode", modeName(s.mode)},
      {"paused", s.paused},
      {"time_scale", s.time_scale},
      {"frames", s.frames},
      {"render_ms",
       {{"last", s.last_render_ms},
        {"p50", percentile(history, 0.5)},
        {"p99", percentile(history, 0.99)},
        {"samples", history.size()}}},
      // The counters other threads keep (clients, queue and encoder depth, frames dropped,
      // errors, CIGI) are added by stats() when it is read.
      {"queue", {{"limit", config_.max_queue}, {"encoder_limit", kEncoderQueue}}},
      {"subscriptions", s.subscriptions.size()},
      {"requests", s.requests},
      {"automaton_steps", world.automatonStepsRun()},
      {"relights", world.relightsRun()},
      {"site", siteJson(world)},
      {"streams", streamsJson()},
      {"last_frame", frameStatsJson(s.renderer->lastFrameStats())},
  };
  stats["histograms"] = {{"render_seconds", s.render_seconds.toJson()},
                         {"request_seconds", s.request_seconds.toJson()}};
  {
    std::lock_guard lock(published_mutex_);
    published_stats_ = std::move(stats);
  }
  publishReadings();
}

void Engine::publishReadings() {
  const State& s = *state_;
  const World& world = *s.world;
  HostReadings settings;
  const ViewConfig& view = *s.view(config_.modbus_view);
  settings.position = view.camera.position;
  settings.heading = view.camera.orientation.heading_deg;
  settings.pitch = view.camera.orientation.pitch_deg;
  settings.roll = view.camera.orientation.roll_deg;
  settings.vfov = view.camera.vfov_deg;
  settings.width = view.camera.width;
  settings.height = view.camera.height;
  const WindProfile& wind = world.dynamics().wind;
  settings.wind = wind.empty() ? glm::dvec2(0.0) : wind.samples.front().velocity;
  settings.sun_azimuth = world.base().sun.azimuth_deg;
  settings.sun_elevation = world.base().sun.elevation_deg;
  settings.time_scale = s.time_scale;
  for (int layer = 1; layer <= ProtocolLimits::kWeatherLayers; ++layer)  // the world's, as set
    if (auto w = world.base().weather.find({layer, std::nullopt}); w != world.base().weather.end())
      settings.layers[std::size_t(layer - 1)] = w->second;
  if (const std::optional<Fog>& fog = world.base().fog) {
    settings.fog_top = fog->top_m;
    settings.fog_visibility = fog->visibility_m;
    settings.fog_colour = fog->colour;
  }
  if (const std::optional<Haze>& haze = world.base().haze) {
    settings.haze_visibility = haze->visibility_m;
    settings.haze_scale_height = haze->scale_height_m;
  }
  settings.sun_utc = s.sun_utc;
  HostStatus status;
  status.status = s.mode == TickMode::kLockstep ? RunState::kLockstep
                  : s.paused                    ? RunState::kPaused
                                                : RunState::kRunning;
  status.frames = std::uint32_t(s.frames);
  status.render_ms = s.last_render_ms;
  status.ticks = s.ticks;
  status.time_s = world.timeSeconds();
  json hello = helloJson();
  std::lock_guard lock(published_mutex_);
  published_settings_ = settings;
  published_status_ = status;
  published_hello_ = std::move(hello);
}

json Engine::helloJson() const {
  const State& s = *state_;
  json views = json::array();
  for (const ViewConfig& v : s.views) views.push_back(v.name);
  return json{{"server", "nephele"},          {"version", NEPHELE_VERSION},
              {"protocol", kProtocolVersion}, {"views", views},
              {"mode", modeName(s.mode)},     {"tick_rate", config_.tick_rate_hz}};
}

void Engine::setInHand(std::string what, std::int64_t client) {
  std::lock_guard lock(published_mutex_);
  in_hand_ = {std::move(what), client, Clock::now()};
}

std::optional<json> Engine::answerAtOnce(const Command& command) {
  if (std::holds_alternative<command::Stats>(command)) {
    ++answered_at_once_;  // counted among the requests, as the world thread counts its own
    json out = stats();
    if (!out.is_null()) return out;
    --answered_at_once_;
  }
  if (std::holds_alternative<command::Hello>(command)) {
    std::lock_guard lock(published_mutex_);
    if (!published_hello_.is_null()) {
      ++answered_at_once_;
      return published_hello_;
    }
  }
  return std::nullopt;
}

HostReadings Engine::readings() const {
  std::lock_guard lock(published_mutex_);
  return published_settings_;
}

HostStatus Engine::status() const {
  std::lock_guard lock(published_mutex_);
  HostStatus status = published_status_;
  status.last_error = std::uint16_t(last_error_.load());
  return status;
}

void Engine::countCigi(const std::string& what) {
  std::lock_guard lock(cigi_mutex_);
  ++cigi_counts_[what];
}

json Engine::stats() const {
  // The world thread's figures as of its last request (publish), with what other threads
  // count read now (each lock alone, none held while another is taken).
  std::size_t depth = 0;
  {
    std::lock_guard lock(queue_mutex_);
    depth = queue_.size();
  }
  json cigi;
  {
    std::lock_guard lock(cigi_mutex_);
    cigi = cigi_counts_;
  }
  const std::size_t encoding = encoder_ ? encoder_->depth() : 0;
  json out;
  InHand in_hand;
  {
    std::lock_guard lock(published_mutex_);
    out = published_stats_;
    in_hand = in_hand_;
  }
  if (out.is_null()) return out;
  out["requests"] = out["requests"].get<std::uint64_t>() + answered_at_once_.load();
  out["errors"] = errors_.load();
  out["frames_dropped"] = frames_dropped.load();
  out["clients"] = {{"socket", socket_clients.load()}, {"modbus", modbus_clients.load()}};
  out["queue"]["depth"] = depth;
  out["queue"]["encoder"] = encoding;
  out["cigi"] = std::move(cigi);
  out["heartbeat_age"] = heartbeatAge();
  out["last_frame"]["ms"]["encode"] = last_encode_ms_.load();
  if (in_hand.what.empty()) {
    out["in_hand"] = nullptr;
  } else {
    out["in_hand"] = {
        {"what", in_hand.what},
        {"client", in_hand.client},
        {"seconds", std::chrono::duration<double>(Clock::now() - in_hand.since).count()}};
  }
  return out;
}

std::string Engine::prometheusText() const {
  const json st = stats();
  std::ostringstream out;
  auto metric = [&](const char* name, const char* type, const char* help, double value) {
    out << "# HELP nephele_" << name << ' ' << help << "\n# TYPE nephele_" << name << ' ' << type
        << "\nnephele_" << name << ' ' << value << '\n';
  };
  if (st.is_null()) return "";
  metric("world_time_seconds", "gauge", "Simulation time.", st["time"].get<double>());
  metric("ticks_total", "counter", "Ticks applied.", st["ticks"].get<double>());
  metric("ticks_per_second", "gauge", "Ticks per second over the last 5 s.",
         st["ticks_per_second"].get<double>());
  metric("frames_total", "counter", "Frames rendered.", st["frames"].get<double>());
  metric("socket_clients", "gauge", "Socket clients.", st["clients"]["socket"].get<double>());
  metric("modbus_clients", "gauge", "Modbus clients.", st["clients"]["modbus"].get<double>());
  metric("queue_depth", "gauge", "Requests waiting.", st["queue"]["depth"].get<double>());
  metric("subscriptions", "gauge", "Frame subscriptions.", st["subscriptions"].get<double>());
  metric("frames_dropped_total", "counter", "Frames dropped for slow clients.",
         st["frames_dropped"].get<double>());
  metric("errors_total", "counter", "Error replies and failed work.", st["errors"].get<double>());
  metric("world_heartbeat_age_seconds", "gauge",
         "Since the world thread last ran its loop or made progress in a render.",
         st["heartbeat_age"].get<double>());
  // Latencies as histograms, in seconds (Prometheus base units).
  auto histogram = [&](const char* name, const char* help) {
    const json& h = st["histograms"][name];
    out << "# HELP nephele_" << name << ' ' << help << "\n# TYPE nephele_" << name
        << " histogram\n";
    std::uint64_t cumulative = 0;
    for (std::size_t i = 0; i <= Histogram::kBounds.size(); ++i) {
      cumulative += h["counts"][i].get<std::uint64_t>();
      out << "nephele_" << name << "_bucket{le=\"";
      if (i < Histogram::kBounds.size())
        out << Histogram::kBounds[i];
      else
        out << "+Inf";
      out << "\"} " << cumulative << '\n';
    }
    out << "nephele_" << name << "_sum " << h["sum"].get<double>() << "\nnephele_" << name
        << "_count " << h["count"].get<std::uint64_t>() << '\n';
  };
  histogram("render_seconds", "Time to render one view.");
  histogram("request_seconds",
            "Time from a request's queueing to its reply (images: to the "
            "render, before encoding).");
  // The last frame's budget (FrameTimes): CPU stages, GPU passes, wait, readback, encoding.
  out << "# HELP nephele_last_frame_seconds Where the last rendered frame's time went: CPU "
         "stages (cpu_*), GPU passes by timer query (gpu_*), submit, wait, readback, encode.\n"
         "# TYPE nephele_last_frame_seconds gauge\n";
  for (const auto& [part, ms] : st["last_frame"]["ms"].items())
    out << "nephele_last_frame_seconds{part=\"" << part << "\"} " << ms.get<double>() * 1e-3
        << '\n';
  out << "# HELP nephele_cigi_total CIGI messages applied, refused by reason, packets ignored.\n"
         "# TYPE nephele_cigi_total counter\n";
  for (const auto& [what, n] : st["cigi"].items())
    out << "nephele_cigi_total{what=\"" << what << "\"} " << n.get<std::uint64_t>() << '\n';
  return out.str();
}

}  // namespace nephele
