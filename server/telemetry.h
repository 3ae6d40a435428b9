#pragma once
// What the daemon tells about itself: the stats reply, the Modbus readings, the Prometheus
// text and the health check (docs/OPERATIONS.md). The world thread records its renders and
// requests and publishes its figures after each request; any thread reads what it published,
// together with the counters the transports and the encoder keep, which are read live.
#include <array>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "protocol/messages.h"

namespace nephele {

// Latencies for Prometheus: counts per bucket of seconds (cumulative in the text format), with
// their sum and count since the daemon started.
struct Histogram {
  static constexpr std::array<double, 13> kBounds{0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1,
                                                  0.25,  0.5,    1.0,   2.5,  5.0,   10.0};
  std::array<std::uint64_t, kBounds.size() + 1> counts{};  // the last: above every bound
  double sum = 0.0;
  std::uint64_t count = 0;
  void add(double seconds);
  nlohmann::json toJson() const;
};

// Where one socket request's time went, stage by stage, filled in by the threads it passes
// through in turn (each hands it on through a queue or a post, so no two touch it at once):
// the transport queues it, the world thread takes it and applies it (rendering, for a render),
// the encoder encodes its images, and the transport hands the reply over and writes it.
struct RequestTrace {
  using Clock = std::chrono::steady_clock;
  std::string command;
  std::int64_t client = 0;
  Clock::time_point queued = Clock::now(), started, applied, replied, written;
  double render_ms = 0.0;  // the views rendered for it, within applied - started
  double encode_ms = 0.0;  // its images encoded, within replied - applied
  // What the world thread did while this request waited in the queue, milliseconds by what it
  // had in hand (filled in by Telemetry::noteTrace).
  std::map<std::string, double> behind;
  double totalSeconds() const { return std::chrono::duration<double>(written - queued).count(); }
  nlohmann::json toJson() const;  // milliseconds by stage
};

class Telemetry {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr std::size_t kRenderHistory = 1024;  // renders kept for p50/p99

  // Kept by the transports (any thread).
  std::atomic<int> socket_clients{0};
  std::atomic<int> modbus_clients{0};
  std::atomic<std::uint64_t> frames_dropped{0};
  void noteError(ErrorCode code);
  // CIGI messages applied, refused (by reason) and packets ignored.
  void countCigi(const std::string& what);
  void noteEncode(double ms) { last_encode_ms_ = ms; }  // the encoder thread's last image
  // A snapshot that was not written, or would not read back, and was not installed.
  void noteSnapshotFailed() { ++snapshot_failures_; }

  // The world thread's heartbeat: at the top of its loop and wherever a render could be
  // cancelled. Its age (any thread) is the health check of /healthz and the systemd watchdog.
  void beat() { heartbeat_ns_ = Clock::now().time_since_epoch().count(); }
  double heartbeatAge() const;
  static constexpr double kStuckSeconds = 20.0;

  // The world thread's records (world thread only).
  void noteRender(double ms);  // one view rendered: the frame counter, history and histogram
  std::uint64_t frames() const { return frames_; }
  void restoreFrames(std::uint64_t frames) { frames_ = frames; }
  double lastRenderMs() const { return last_render_ms_; }
  void noteRequest() { ++requests_; }
  void noteRequestDone(Clock::time_point queued);
  // A request written out (any thread): the slowest of each second is kept for stats, and one
  // that took longer than kSlowRequestSeconds is counted and logged with its stages.
  void noteTrace(const RequestTrace& trace);
  static constexpr double kSlowRequestSeconds = 1.0;
  static constexpr std::size_t kSlowestSeconds = 10;  // seconds whose slowest stats lists
  // The render and request figures of the stats reply: render_ms, requests, histograms.
  void addRecords(nlohmann::json& stats) const;
  // Where the world thread's time went since the start, by what it had in hand (a command's
  // name, "frames", "ticks", "snapshot", "publish"): stats' world_thread, each with its count,
  // total and longest milliseconds.
  // A span is also kept a while, so that a slow request can say what the world thread did
  // while it waited in the queue (RequestTrace::behind).
  void noteBusy(const std::string& what, Clock::time_point from);
  // What the world thread has in hand, for stats (empty `what` when idle).
  void setInHand(std::string what, std::int64_t client);

  // Published by the world thread, read by any.
  void publishStats(nlohmann::json stats);
  void publishReadings(const HostReadings& readings, const HostStatus& status,
                       nlohmann::json hello);
  HostReadings readings() const;
  HostStatus status() const;

  // What is read live when stats are asked.
  struct Live {
    std::size_t queue_depth = 0;
    std::size_t encoder_depth = 0;
  };
  // The last published stats with the live counters; null before the first publish.
  nlohmann::json stats(const Live& live) const;
  std::string prometheusText(const Live& live) const;
  // `hello` and `stats` answered on the caller's thread (PROTOCOL.md, "Control plane"); nullopt
  // for every other command, and before the world thread first published.
  std::optional<nlohmann::json> answerAtOnce(const Command& command, const Live& live);

 private:
  // World thread.
  std::uint64_t frames_ = 0;
  std::uint64_t requests_ = 0;
  double last_render_ms_ = 0.0;
  std::deque<double> render_ms_;
  Histogram render_seconds_;   // one view's render
  Histogram request_seconds_;  // a request or batch, from queueing to done
  struct Busy {
    std::uint64_t count = 0;
    double total_ms = 0.0, max_ms = 0.0;
  };
  std::map<std::string, Busy> busy_;

  // Any thread.
  std::atomic<std::int64_t> heartbeat_ns_{0};
  std::atomic<std::uint64_t> errors_{0};
  std::atomic<std::uint64_t> snapshot_failures_{0};
  std::atomic<std::uint64_t> answered_at_once_{0};  // requests the control plane answered
  std::atomic<int> last_error_{0};
  std::atomic<double> last_encode_ms_{0.0};
  mutable std::mutex traces_mutex_;
  struct Slowest {
    std::int64_t second = 0;  // since the daemon started
    RequestTrace trace;
  };
  std::deque<Slowest> slowest_;  // one per second that wrote a request, the last kSlowestSeconds
  struct Span {
    std::string what;
    Clock::time_point from, to;
  };
  std::deque<Span> spans_;  // the world thread's last kSpans spans of work
  static constexpr std::size_t kSpans = 4096;
  std::uint64_t slow_requests_ = 0;
  const Clock::time_point started_ = Clock::now();
  mutable std::mutex cigi_mutex_;
  std::map<std::string, std::uint64_t> cigi_counts_;

  mutable std::mutex published_mutex_;
  HostReadings published_readings_;
  HostStatus published_status_;
  nlohmann::json published_stats_;
  nlohmann::json published_hello_;
  struct InHand {
    std::string what;  // a command's name, "modbus write", "frames" or "ticks"; empty when idle
    std::int64_t client = 0;
    Clock::time_point since;
  } in_hand_;
};

}  // namespace nephele
