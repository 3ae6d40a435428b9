#include "server/telemetry.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <vector>

#include "renderer/frame_timing.h"
#include "server/log_limiter.h"

namespace nephele {

using nlohmann::json;

namespace {

// Slow requests are logged in full while rare, summarised while they flood.
LogLimiter& slowLog() {
  static LogLimiter limiter;
  return limiter;
}

}  // namespace

void Histogram::add(double seconds) {
  std::size_t i = 0;
  while (i < kBounds.size() && seconds > kBounds[i]) ++i;
  ++counts[i];
  sum += seconds;
  ++count;
}

json Histogram::toJson() const {
  return {{"counts", counts}, {"sum", sum}, {"count", count}};
}

void Telemetry::noteError(ErrorCode code) {
  ++errors_;
  last_error_ = 1 + int(code);
}

void Telemetry::countCigi(const std::string& what) {
  std::lock_guard lock(cigi_mutex_);
  ++cigi_counts_[what];
}

double Telemetry::heartbeatAge() const {
  const std::int64_t beat = heartbeat_ns_.load();
  if (beat == 0) return 0.0;  // not started yet
  return std::chrono::duration<double>(Clock::now().time_since_epoch() - Clock::duration(beat))
      .count();
}

void Telemetry::noteRender(double ms) {
  last_render_ms_ = ms;
  render_ms_.push_back(ms);
  render_seconds_.add(ms * 1e-3);
  if (render_ms_.size() > kRenderHistory) render_ms_.pop_front();
  ++frames_;
}

void Telemetry::noteRequestDone(Clock::time_point queued) {
  request_seconds_.add(std::chrono::duration<double>(Clock::now() - queued).count());
}

json RequestTrace::toJson() const {
  const auto ms = [](Clock::time_point from, Clock::time_point to) {
    return std::chrono::duration<double, std::milli>(to - from).count();
  };
  return {{"cmd", command},
          {"client", client},
          {"total_ms", ms(queued, written)},
          {"queue_ms", ms(queued, started)},
          {"world_ms", ms(started, applied)},
          {"render_ms", render_ms},
          {"handoff_ms", ms(applied, replied)},
          {"encode_ms", encode_ms},
          {"write_ms", ms(replied, written)},
          {"behind_ms", behind}};
}

void Telemetry::noteBusy(const std::string& what, Clock::time_point from) {
  const Clock::time_point to = Clock::now();
  const double ms = std::chrono::duration<double, std::milli>(to - from).count();
  if (ms >= 1.0) {  // shorter work cannot account for a slow request
    std::lock_guard lock(traces_mutex_);
    spans_.push_back({what, from, to});
    while (spans_.size() > kSpans) spans_.pop_front();
  }
  Busy& b = busy_[what];
  ++b.count;
  b.total_ms += ms;
  b.max_ms = std::max(b.max_ms, ms);
}

void Telemetry::noteTrace(const RequestTrace& done) {
  if (done.started == Clock::time_point{}) return;  // refused at shutdown, never applied
  RequestTrace trace = done;
  const double seconds = trace.totalSeconds();
  const std::int64_t second =
      std::chrono::duration_cast<std::chrono::seconds>(trace.written - started_).count();
  {
    std::lock_guard lock(traces_mutex_);
    if (seconds > kSlowRequestSeconds)  // what the world thread did while it waited
      for (const Span& span : spans_) {
        const auto from = std::max(span.from, trace.queued), to = std::min(span.to, trace.started);
        if (from < to)
          trace.behind[span.what] += std::chrono::duration<double, std::milli>(to - from).count();
      }
    if (slowest_.empty() || slowest_.back().second != second)
      slowest_.push_back({second, trace});
    else if (seconds > slowest_.back().trace.totalSeconds())
      slowest_.back().trace = trace;
    while (slowest_.size() > kSlowestSeconds) slowest_.pop_front();
    if (seconds > kSlowRequestSeconds) ++slow_requests_;
  }
  if (seconds > kSlowRequestSeconds && slowLog().admit("slow_request")) {
    const json t = trace.toJson();
    std::string behind;
    for (const auto& [what, ms] : trace.behind) {
      if (!behind.empty()) behind += ',';
      behind.append(what).append(":").append(std::to_string(std::lround(ms)));
    }
    spdlog::warn(
        "event=slow_request cmd={} client={} total_ms={:.1f} queue_ms={:.1f} world_ms={:.1f} "
        "render_ms={:.1f} handoff_ms={:.1f} encode_ms={:.1f} write_ms={:.1f} behind={}",
        trace.command, trace.client, t["total_ms"].get<double>(), t["queue_ms"].get<double>(),
        t["world_ms"].get<double>(), trace.render_ms, t["handoff_ms"].get<double>(),
        trace.encode_ms, t["write_ms"].get<double>(), behind.empty() ? "-" : behind);
  }
}

void Telemetry::addRecords(json& stats) const {
  const std::vector<double> history(render_ms_.begin(), render_ms_.end());
  stats["frames"] = frames_;
  stats["render_ms"] = {{"last", last_render_ms_},
                        {"p50", percentile(history, 0.5)},
                        {"p99", percentile(history, 0.99)},
                        {"samples", history.size()}};
  stats["requests"] = requests_;
  json busy = json::object();
  for (const auto& [what, b] : busy_)
    busy[what] = {{"count", b.count}, {"total_ms", b.total_ms}, {"max_ms", b.max_ms}};
  stats["world_thread"] = std::move(busy);
  stats["histograms"] = {{"render_seconds", render_seconds_.toJson()},
                         {"request_seconds", request_seconds_.toJson()}};
}

void Telemetry::setInHand(std::string what, std::int64_t client) {
  std::lock_guard lock(published_mutex_);
  in_hand_ = {std::move(what), client, Clock::now()};
}

void Telemetry::publishStats(json stats) {
  std::lock_guard lock(published_mutex_);
  published_stats_ = std::move(stats);
}

void Telemetry::publishReadings(const HostReadings& readings, const HostStatus& status,
                                json hello) {
  std::lock_guard lock(published_mutex_);
  published_readings_ = readings;
  published_status_ = status;
  published_hello_ = std::move(hello);
}

HostReadings Telemetry::readings() const {
  std::lock_guard lock(published_mutex_);
  return published_readings_;
}

HostStatus Telemetry::status() const {
  std::lock_guard lock(published_mutex_);
  HostStatus status = published_status_;
  status.last_error = std::uint16_t(last_error_.load());
  return status;
}

std::optional<json> Telemetry::answerAtOnce(const Command& command, const Live& live) {
  if (std::holds_alternative<command::Stats>(command)) {
    ++answered_at_once_;  // counted among the requests, as the world thread counts its own
    json out = stats(live);
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

json Telemetry::stats(const Live& live) const {
  // The world thread's figures as of its last publish, with what other threads count read now
  // (each lock alone, none held while another is taken).
  json cigi;
  {
    std::lock_guard lock(cigi_mutex_);
    cigi = cigi_counts_;
  }
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
  out["snapshot_failures"] = snapshot_failures_.load();
  {
    std::lock_guard lock(traces_mutex_);
    json slowest = json::array();
    for (const Slowest& s : slowest_) {
      json entry = s.trace.toJson();
      entry["second"] = s.second;
      slowest.push_back(std::move(entry));
    }
    out["slow_requests"] = {{"count", slow_requests_},
                            {"over_seconds", kSlowRequestSeconds},
                            {"slowest_per_second", std::move(slowest)}};
  }
  out["frames_dropped"] = frames_dropped.load();
  out["clients"] = {{"socket", socket_clients.load()}, {"modbus", modbus_clients.load()}};
  out["queue"]["depth"] = live.queue_depth;
  out["queue"]["encoder"] = live.encoder_depth;
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

namespace {

void writeHistogram(std::ostringstream& out, const json& st, const char* name, const char* help) {
  const json& h = st["histograms"][name];
  out << "# HELP nephele_" << name << ' ' << help << "\n# TYPE nephele_" << name << " histogram\n";
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
}

}  // namespace

std::string Telemetry::prometheusText(const Live& live) const {
  const json st = stats(live);
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
  metric("slow_requests_total", "counter",
         "Socket requests whose reply was written more than 1 s after they were queued.",
         st["slow_requests"]["count"].get<double>());
  metric("snapshot_failures_total", "counter",
         "Snapshots not installed: not written, or would not read back.",
         st["snapshot_failures"].get<double>());
  metric("world_heartbeat_age_seconds", "gauge",
         "Since the world thread last ran its loop or made progress in a render.",
         st["heartbeat_age"].get<double>());
  // Latencies as histograms, in seconds (Prometheus base units).
  writeHistogram(out, st, "render_seconds", "Time to render one view.");
  writeHistogram(out, st, "request_seconds",
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
