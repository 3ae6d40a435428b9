#pragma once
// The world thread's state and work items, shared by the files that make up the Engine:
// engine.cpp (thread, queue and time), dispatch.cpp (requests), delivery.cpp (rendering and
// frame delivery), atmosphere.cpp (weather, fog, sun), snapshots.cpp and telemetry.cpp.
// Transports include engine.h only.
#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <deque>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include "image/image_encoding.h"
#include "renderer/encode.h"
#include "renderer/frame.h"
#include "renderer/frame_timing.h"
#include "renderer/gl/gl_platform.h"
#include "renderer/gl/gl_renderer.h"
#include "server/engine.h"
#include "world/solar.h"
#include "world/world.h"

namespace nephele {
namespace engine_detail {

using Clock = std::chrono::steady_clock;
using nlohmann::json;
using Outcome = std::variant<json, ProtocolError>;

constexpr int kProtocolVersion = 1;
constexpr int kMaxCatchUpTicks = 100;  // after a stall, ticks made up in one go
constexpr std::size_t kMaxClouds = 4096;
constexpr std::size_t kRenderHistory = 1024;  // renders kept for p50/p99
constexpr std::size_t kEncoderQueue = 16;

inline double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

inline std::string hexHash(std::uint64_t h) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
  return text;
}

inline ProtocolError badField(std::string message) {
  return {ErrorCode::kBadField, std::move(message)};
}

// What the last rendered frame did (renderer/gl/frame_stats.h).
inline json frameStatsJson(const FrameStats& f) {
  json out = json::object();
  for (const auto& [name, value] : f.fields()) out[name] = value;
  json& ms = out["ms"] = json::object();  // where its time went (FrameTimes)
  for (const auto& [name, value] : f.times.fields()) ms[name] = value;
  return out;
}

inline json frustumJson(const Frustum& f) {
  return {{"left", f.left}, {"right", f.right}, {"bottom", f.bottom}, {"top", f.top}};
}

inline json viewJson(const ViewConfig& v) {
  const Camera& c = v.camera;
  json out{{"name", v.name},
           {"position", {c.position.x, c.position.y, c.position.z}},
           {"heading", c.orientation.heading_deg},
           {"pitch", c.orientation.pitch_deg},
           {"roll", c.orientation.roll_deg},
           {"vfov", c.vfov_deg},
           {"width", c.width},
           {"height", c.height},
           {"format", imageFormatName(v.image.format)},
           {"channels", channelNames(v.image)}};
  if (v.frustum) out["frustum"] = frustumJson(*v.frustum);
  return out;
}

inline const char* modeName(TickMode mode) {
  return mode == TickMode::kRealtime ? "realtime" : "lockstep";
}

inline ProtocolError unknownView(const std::vector<ViewConfig>& views, const std::string& name) {
  std::string names;
  for (const ViewConfig& v : views) names += (names.empty() ? "" : ", ") + v.name;
  return {ErrorCode::kNotFound, "view: \"" + name + "\" is not a view (allowed: " + names + ")"};
}

// Latencies for Prometheus: counts per bucket of seconds (cumulative in the text format), with
// their sum and count since the daemon started.
struct Histogram {
  static constexpr std::array<double, 13> kBounds{0.001, 0.0025, 0.005, 0.01, 0.025, 0.05, 0.1,
                                                  0.25,  0.5,    1.0,   2.5,  5.0,   10.0};
  std::array<std::uint64_t, kBounds.size() + 1> counts{};  // the last: above every bound
  double sum = 0.0;
  std::uint64_t count = 0;
  void add(double seconds) {
    std::size_t i = 0;
    while (i < kBounds.size() && seconds > kBounds[i]) ++i;
    ++counts[i];
    sum += seconds;
    ++count;
  }
  json toJson() const { return {{"counts", counts}, {"sum", sum}, {"count", count}}; }
};

// A visitor of one lambda per alternative.
template <class... F>
struct Overloaded : F... {
  using F::operator()...;
};
template <class... F>
Overloaded(F...) -> Overloaded<F...>;

// The fields a patch sets; the others stay.
inline void applyViewPatch(ViewConfig& v, const ViewPatch& p) {
  Camera& cam = v.camera;
  if (p.position) cam.position = *p.position;
  if (p.heading) cam.orientation.heading_deg = *p.heading;
  if (p.pitch) cam.orientation.pitch_deg = *p.pitch;
  if (p.roll) cam.orientation.roll_deg = *p.roll;
  if (p.vfov) {
    cam.vfov_deg = *p.vfov;
    v.frustum.reset();
  }
  if (p.width) cam.width = *p.width;
  if (p.height) cam.height = *p.height;
  if (p.frustum) v.frustum = *p.frustum;
  if (v.frustum) {  // the vertical extent, and the width at this height with square pixels
    cam.vfov_deg = v.frustum->top - v.frustum->bottom;
    cam.width = offAxisView(cam, *v.frustum).width;
  }
  if (p.image) v.image = *p.image;
}

}  // namespace engine_detail

using engine_detail::Clock;
using engine_detail::kEncoderQueue;

// One queued piece of work.
struct Engine::Job {
  Clock::time_point queued = Clock::now();
  enum class Kind { kRequest, kBatch } kind = Kind::kRequest;
  Request request;
  std::int64_t client = 0;
  PushSink push;
  ReplySink reply;
  std::vector<Command> batch;
  bool render = false;  // a batch with the render coil
  std::shared_ptr<BatchTicket> ticket;
  DoneSink done;
};

struct Engine::Subscription {
  std::int64_t id = 0;
  std::int64_t client = 0;
  std::string view;
  ImageRequest image;
  Clock::duration period{};
  Clock::time_point next_due;
  std::uint64_t last_tick = UINT64_MAX;  // the tick of the last frame sent
  PushSink sink;
  std::shared_ptr<std::atomic<bool>> gone;  // set when the sink reports its client gone
  // A streamed view (stream): its frames go to the encoder in place of `sink`; its address.
  std::shared_ptr<VideoStream> video;
  std::string address;
};

// Thrown by Engine::renderFrame when the daemon's stop cancelled the render in hand; the run
// loop answers the request "shutting down".
struct RenderCancelled {};

// A thread that encodes images off the world thread, from a bounded queue.
class Engine::Encoder {
 public:
  Encoder() : thread_([this] { run(); }) {}
  ~Encoder() { finish(); }
  // Sends what it holds, then stops its thread; posts after this are refused. The Encoder
  // itself stays, so a stats request on the socket thread may still ask its depth.
  void finish() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
  }
  bool post(std::function<void()> job) {
    {
      std::lock_guard lock(mutex_);
      if (stop_ || jobs_.size() >= kEncoderQueue) return false;
      jobs_.push_back(std::move(job));
    }
    cv_.notify_one();
    return true;
  }
  std::size_t depth() const {
    std::lock_guard lock(mutex_);
    return jobs_.size();
  }

 private:
  void run() {
    for (;;) {
      std::function<void()> job;
      {
        std::unique_lock lock(mutex_);
        cv_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
        if (jobs_.empty()) return;  // stopping, and every queued image is out
        job = std::move(jobs_.front());
        jobs_.pop_front();
      }
      job();
    }
  }
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::function<void()>> jobs_;
  bool stop_ = false;
  std::thread thread_;
};

// Everything the world thread owns.
struct Engine::State {
  std::unique_ptr<GlPlatform> platform;
  std::unique_ptr<GlRenderer> renderer;
  std::unique_ptr<World> world;
  std::vector<ViewConfig> views;
  TickMode mode = TickMode::kRealtime;  // switchable at run time (set_time mode)
  double time_scale = 1.0;
  bool paused = false;
  std::optional<CivilTime> sun_utc;  // when the sun was last set from a date and time
  std::uint64_t ticks = 0;
  std::uint64_t frames = 0;
  std::uint64_t requests = 0;
  double last_render_ms = 0.0;
  std::deque<double> render_ms;
  engine_detail::Histogram render_seconds;   // one view's render
  engine_detail::Histogram request_seconds;  // a request or batch, from queueing to done
  std::deque<std::pair<Clock::time_point, std::uint64_t>> tick_history;  // one per second
  std::vector<Subscription> subscriptions;
  std::int64_t next_subscription = 1;
  Clock::time_point next_tick;
  Clock::time_point next_snapshot;
  std::uint64_t next_cloud_seed = 0;

  ViewConfig* view(const std::string& name) {
    for (ViewConfig& v : views)
      if (v.name == name) return &v;
    return nullptr;
  }
  const ViewConfig* view(const std::string& name) const {
    return const_cast<State*>(this)->view(name);
  }
};

// A view as rendered, before encoding: its frame (8-bit, linear or float planes, as its
// ImageRequest asked) and the fields of its image header.
struct RenderedView {
  Frame frame;
  nlohmann::json meta;
};

namespace engine_detail {
// The sea (atmosphere.cpp): the wind a new sea takes, the world's at altitude 0 (Sea's default
// in a world without wind); the sea after a set_sea, or the error naming the field and what is
// allowed; and the reply that describes it.
glm::dvec2 surfaceWind(const World& world);
std::variant<std::optional<Sea>, ProtocolError> seaAfter(const std::optional<Sea>& sea,
                                                         const command::SetSea& c,
                                                         glm::dvec2 surface_wind);
json seaJson(const std::optional<Sea>& sea);
// Where the world's database lies on the Earth (set_site's reply, stats' "site").
json siteJson(const World& world);

// The pixels an image request asks for: float planes with ground-truth channels, else colour
// and coverage, linear for EXR and 8-bit sRGB otherwise (PROTOCOL.md, "Images").
Channels channelsOf(const ImageRequest& image);
// The container of a protocol image format.
ImageFileFormat fileFormatOf(ImageFormat format);
// Encodes a rendered view as `image` asks (delivery.cpp); on failure returns the error.
Encoded encodeView(const RenderedView& view, const ImageRequest& image,
                   const EncodeOptions& options);
// An image header's fields: the frame's view, pose, time and tick, and how it is encoded.
json imageMeta(const RenderedView& view, const ImageRequest& image);
}  // namespace engine_detail

}  // namespace nephele
