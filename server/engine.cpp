#include "server/engine.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <map>
#include <numeric>
#include <sstream>

#include "image/image_encoding.h"
#include "renderer/gl/gl_platform.h"
#include "renderer/gl/gl_renderer.h"
#include "renderer/renderer.h"
#include "world/counter_random.h"
#include "world/limits.h"
#include "world/world.h"

namespace nephele {
namespace {

using Clock = std::chrono::steady_clock;
using nlohmann::json;
using Outcome = std::variant<json, ProtocolError>;

constexpr int kProtocolVersion = 1;
constexpr int kMaxCatchUpTicks = 100;  // after a stall, ticks made up in one go
constexpr std::size_t kMaxClouds = 4096;
constexpr std::size_t kRenderHistory = 1024;  // renders kept for p50/p99
constexpr std::size_t kEncoderQueue = 16;

double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

std::string hexHash(std::uint64_t h) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
  return text;
}

ProtocolError badField(std::string message) {
  return {ErrorCode::kBadField, std::move(message)};
}

// What the last rendered frame did (renderer/gl/frame_stats.h).
json frameStatsJson(const FrameStats& f) {
  json out = json::object();
  for (const auto& [name, value] : f.fields()) out[name] = value;
  return out;
}

json viewJson(const ViewConfig& v) {
  const Camera& c = v.camera;
  return {{"name", v.name},
          {"position", {c.position.x, c.position.y, c.position.z}},
          {"heading", c.orientation.heading_deg},
          {"pitch", c.orientation.pitch_deg},
          {"roll", c.orientation.roll_deg},
          {"vfov", c.vfov_deg},
          {"width", c.width},
          {"height", c.height},
          {"format", imageFormatName(v.image.format)},
          {"channels", channelNames(v.image)}};
}

const char* modeName(TickMode mode) {
  return mode == TickMode::kRealtime ? "realtime" : "lockstep";
}

ProtocolError unknownView(const std::vector<ViewConfig>& views, const std::string& name) {
  std::string names;
  for (const ViewConfig& v : views) names += (names.empty() ? "" : ", ") + v.name;
  return {ErrorCode::kNotFound, "view: \"" + name + "\" is not a view (allowed: " + names + ")"};
}

double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, std::size_t(p * double(values.size())))];
}

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

}  // namespace

// One queued piece of work.
struct Engine::Job {
  enum class Kind { kRequest, kBatch } kind = Kind::kRequest;
  Request request;
  std::int64_t client = 0;
  FrameSink frames;
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
  FrameSink sink;
  std::shared_ptr<std::atomic<bool>> gone;  // set when the sink reports its client gone
};

// A thread that encodes images off the world thread, from a bounded queue.
class Engine::Encoder {
 public:
  Encoder() : thread_([this] { run(); }) {}
  ~Encoder() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
  }
  bool post(std::function<void()> job) {
    {
      std::lock_guard lock(mutex_);
      if (jobs_.size() >= kEncoderQueue) return false;
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
  std::array<WeatherLayer, ProtocolLimits::kWeatherLayers> weather;
  double time_scale = 1.0;
  bool paused = false;
  std::uint64_t ticks = 0;
  std::uint64_t frames = 0;
  std::uint64_t requests = 0;
  double last_render_ms = 0.0;
  std::deque<double> render_ms;
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

Engine::Engine(DaemonConfig config)
    : config_(std::move(config)), state_(std::make_unique<State>()) {
  state_->views = config_.views;
  state_->time_scale = config_.time_scale;
}

Engine::~Engine() {
  stop();
}

std::string Engine::start() {
  std::promise<std::string> started;
  std::future<std::string> result = started.get_future();
  thread_ = std::thread([this, &started] { run(started); });
  std::string error = result.get();
  if (!error.empty()) {
    thread_.join();
    return error;
  }
  encoder_ = std::make_unique<Encoder>();
  return "";
}

bool Engine::stop() {
  {
    std::lock_guard lock(queue_mutex_);
    if (stopping_ && !thread_.joinable()) return shutdown_saved_;
    stopping_ = true;
  }
  queue_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  encoder_.reset();  // sends what it holds, then stops
  return shutdown_saved_;
}

bool Engine::stopping() const {
  std::lock_guard lock(queue_mutex_);
  return stopping_;
}

void Engine::clientGone(std::int64_t client) {
  {
    std::lock_guard lock(queue_mutex_);
    gone_clients_.push_back(client);
  }
  queue_cv_.notify_one();
}

int Engine::subscriptionsOf(std::int64_t client) const {
  std::lock_guard lock(subscribers_mutex_);
  const auto it = subscribers_.find(client);
  return it == subscribers_.end() ? 0 : it->second;
}

void Engine::countSubscriptions() {
  std::map<std::int64_t, int> counts;
  for (const Subscription& sub : state_->subscriptions) ++counts[sub.client];
  std::lock_guard lock(subscribers_mutex_);
  subscribers_ = std::move(counts);
}

bool Engine::enqueue(Job job) {
  {
    std::lock_guard lock(queue_mutex_);
    if (stopping_ || queue_.size() >= std::size_t(config_.max_queue)) return false;
    queue_.push_back(std::move(job));
  }
  queue_cv_.notify_one();
  return true;
}

bool Engine::submit(Request request, std::int64_t client, FrameSink frames, ReplySink done) {
  Job job;
  job.request = std::move(request);
  job.client = client;
  job.frames = std::move(frames);
  job.reply = std::move(done);
  return enqueue(std::move(job));
}

bool Engine::submitBatch(std::vector<Command> commands, bool render,
                         std::shared_ptr<BatchTicket> ticket, DoneSink done) {
  Job job;
  job.kind = Job::Kind::kBatch;
  job.batch = std::move(commands);
  job.render = render;
  job.ticket = std::move(ticket);
  job.done = std::move(done);
  if (render) trigger_pending_ = true;  // before queueing: the world thread clears it when done
  if (enqueue(std::move(job))) return true;
  if (render) trigger_pending_ = false;
  return false;
}

void Engine::noteError(ErrorCode code) {
  ++errors_;
  last_error_ = 1 + int(code);
}

// A rendered view, before encoding.
struct ViewFrame {
  Srgb8Image srgb;
  FloatImage linear;  // for EXR
  Frame planes;       // with ground-truth channels (ImageRequest::floatPlanes)
  nlohmann::json meta;
};

namespace {

// Encodes `frame` as `image` asks; on failure returns the error.
std::variant<std::vector<std::uint8_t>, std::string> encodeFrame(const ViewFrame& frame,
                                                                 const ImageRequest& image,
                                                                 const EncodeOptions& options) {
  std::vector<std::uint8_t> bytes;
  std::string error;
  if (image.floatPlanes()) {
    const Frame& f = frame.planes;
    if (image.format == ImageFormat::kExr) {
      error = encodeFrameExr(f, image.order, options, bytes);
      if (!error.empty()) return error;
      return bytes;
    }
    // Raw: float32 planes, host byte order (little-endian on x86-64 and ARM), in the order asked.
    const std::size_t pixels = std::size_t(f.width()) * f.height();
    std::vector<float> planes;
    planes.reserve(pixels * (image.order.size() + 2));
    for (Channel c : image.order) {
      if (c == Channel::kColour) {
        for (int k = 0; k < 3; ++k)
          for (std::size_t i = 0; i < pixels; ++i) planes.push_back(f.colour.rgba[i * 4 + k]);
      } else {
        const std::vector<float> plane = f.plane(c);
        planes.insert(planes.end(), plane.begin(), plane.end());
      }
    }
    const auto* raw = reinterpret_cast<const std::uint8_t*>(planes.data());
    return std::vector<std::uint8_t>(raw, raw + planes.size() * sizeof(float));
  }
  switch (image.format) {
    case ImageFormat::kRaw:
      return packRaw(frame.srgb, image.colour, image.coverage);
    case ImageFormat::kPng:
      error = encodeImage(ImageFileFormat::kPng, frame.srgb, image.colour, image.coverage, options,
                          bytes);
      break;
    case ImageFormat::kJpeg:
      error = encodeImage(ImageFileFormat::kJpeg, frame.srgb, image.colour, image.coverage, options,
                          bytes);
      break;
    case ImageFormat::kExr:
      error = encodeImage(frame.linear, image.colour, image.coverage, options, bytes);
      break;
  }
  if (!error.empty()) return error;
  return bytes;
}

json imageMeta(const ViewFrame& frame, const ImageRequest& image) {
  json meta = frame.meta;
  meta["format"] = imageFormatName(image.format);
  meta["channels"] = channelNames(image);
  meta["rows"] = "top-down";
  meta["encoding"] = image.format == ImageFormat::kExr ? "linear"
                     : image.floatPlanes()             ? "float32-planes"
                                                       : "srgb";
  return meta;
}

// A name's 64-bit FNV-1a hash, for seeding clouds by name.
std::uint64_t nameHash(const std::string& name) {
  std::uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : name) h = (h ^ c) * 0x100000001b3ull;
  return h;
}

void setWindSample(WindProfile& profile, double altitude, glm::dvec2 velocity) {
  auto& samples = profile.samples;
  std::erase_if(samples,
                [&](const WindSample& w) { return std::abs(w.altitude_m - altitude) < 1.0; });
  samples.push_back({altitude, velocity});
  std::sort(samples.begin(), samples.end(),
            [](const WindSample& a, const WindSample& b) { return a.altitude_m < b.altitude_m; });
}

}  // namespace

std::string Engine::openWorld() {
  State& s = *state_;
  std::string error;
  s.platform = createGlPlatform(GlBackend::kAuto, error);
  if (!s.platform) return "no OpenGL context: " + error;
  s.renderer = std::make_unique<GlRenderer>(*s.platform);
  s.world =
      std::make_unique<World>(config_.scene.scene, config_.scene.dynamics, config_.world_threads);
  if (std::string e = s.world->advanceInPieces(config_.scene.scene.time_s); !e.empty())
    return "scene time: " + e;
  const std::string& snapshot = config_.snapshot_path;
  if (config_.restore_on_start && !snapshot.empty() && std::filesystem::exists(snapshot)) {
    if (std::string e = s.world->restoreSnapshot(snapshot); !e.empty())
      return e + " (move the file away to start from the scene instead)";
    spdlog::info("event=restored snapshot={} time={:.3f} hash={}", snapshot, s.world->timeSeconds(),
                 hexHash(s.world->hash()));
  }
  spdlog::info("event=world_ready gl=\"{}\" backend={} views={} mode={} tick_rate={}",
               s.platform->renderer(), s.platform->backendName(), s.views.size(),
               modeName(config_.mode), config_.tick_rate_hz);
  return "";
}

void Engine::run(std::promise<std::string>& started) {
  State& s = *state_;
  if (std::string error = openWorld(); !error.empty()) {
    s.renderer.reset();
    s.platform.reset();
    started.set_value(error);
    return;
  }
  s.next_tick = Clock::now();
  s.next_snapshot = Clock::now() + secondsToDuration(config_.snapshot_interval_s);
  publish();
  started.set_value("");

  for (;;) {
    std::deque<Job> jobs;
    std::vector<std::int64_t> gone;
    bool stopping = false;
    {
      std::unique_lock lock(queue_mutex_);
      queue_cv_.wait_until(lock, nextWake(),
                           [&] { return stopping_ || !queue_.empty() || !gone_clients_.empty(); });
      jobs.swap(queue_);
      gone.swap(gone_clients_);
      stopping = stopping_;
    }
    if (!gone.empty()) {
      std::erase_if(s.subscriptions, [&](const Subscription& sub) {
        return std::find(gone.begin(), gone.end(), sub.client) != gone.end();
      });
      countSubscriptions();
    }
    for (Job& job : jobs) {
      if (!stopping) {
        execute(job);
        continue;
      }
      const ProtocolError cancelled{ErrorCode::kFailed, "the daemon is shutting down"};
      if (job.reply) job.reply(makeReply(errorReply(job.request.id, cancelled)));
      if (job.done) job.done(cancelled);
    }
    if (stopping) break;
    realtimeTicks();
    deliverFrames(true, "");
    if (config_.snapshot_interval_s > 0.0 && !config_.snapshot_path.empty() &&
        Clock::now() >= s.next_snapshot) {
      saveSnapshot(config_.snapshot_path, "periodic");
      s.next_snapshot = Clock::now() + secondsToDuration(config_.snapshot_interval_s);
    }
    publish();
  }
  if (!config_.snapshot_path.empty())
    shutdown_saved_ = saveSnapshot(config_.snapshot_path, "shutdown");
  s.subscriptions.clear();
  countSubscriptions();
  s.renderer.reset();  // GL objects go while their context is current
  s.platform.reset();
}

Engine::Clock::time_point Engine::nextWake() const {
  const State& s = *state_;
  Clock::time_point wake = Clock::now() + std::chrono::milliseconds(500);
  if (config_.mode == TickMode::kRealtime && !s.paused) wake = std::min(wake, s.next_tick);
  for (const Subscription& sub : s.subscriptions) wake = std::min(wake, sub.next_due);
  return wake;
}

bool Engine::saveSnapshot(const std::string& path, const char* why) {
  const auto t0 = Clock::now();
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  if (std::string e = state_->world->saveSnapshot(path); !e.empty()) {
    spdlog::error("event=snapshot_failed reason={} error=\"{}\"", why, e);
    noteError(ErrorCode::kFailed);
    return false;
  }
  spdlog::info("event=snapshot reason={} path={} time={:.3f} hash={} ms={:.1f}", why, path,
               state_->world->timeSeconds(), hexHash(state_->world->hash()), msSince(t0));
  return true;
}

std::optional<ProtocolError> Engine::checkAdvance(double dt_s) const {
  // The World's own refusal, asked before anything is applied, so a refused advance is an
  // error reply and changes nothing.
  if (std::string e = state_->world->advanceError(dt_s); !e.empty())
    return ProtocolError{ErrorCode::kLimit, e};
  if (std::string e = automatonAdvanceError(state_->world->dynamics().automata, dt_s); !e.empty())
    return ProtocolError{ErrorCode::kLimit, e};
  return std::nullopt;
}

void Engine::advance(double dt_s) {
  State& s = *state_;
  if (std::string e = s.world->advance(dt_s); !e.empty()) {
    spdlog::warn("event=advance_refused error=\"{}\"", e);
    noteError(ErrorCode::kLimit);
    return;
  }
  ++s.ticks;
}

void Engine::realtimeTicks() {
  State& s = *state_;
  if (config_.mode != TickMode::kRealtime || s.paused) return;
  const auto now = Clock::now();
  if (now < s.next_tick) return;
  const auto period = secondsToDuration(1.0 / config_.tick_rate_hz);
  int due = 1 + int((now - s.next_tick) / period);
  if (due > kMaxCatchUpTicks) {  // a long stall: drop the backlog rather than race to catch up
    spdlog::warn("event=ticks_skipped count={}", due - kMaxCatchUpTicks);
    due = kMaxCatchUpTicks;
    s.next_tick = now;
  }
  s.next_tick += period * due;
  double dt = due * s.time_scale / config_.tick_rate_hz;
  if (checkAdvance(dt)) dt = 0.0;  // too much automaton work for one go: hold time
  for (int i = 0; i < due; ++i) ++s.ticks;
  if (dt > 0.0) {
    if (std::string e = s.world->advance(dt); !e.empty())
      spdlog::warn("event=advance_refused error=\"{}\"", e);
  }
}

std::optional<ProtocolError> Engine::check(const Command& command) const {
  const State& s = *state_;
  if (const auto* c = std::get_if<command::SetView>(&command)) {
    const ViewConfig* view = s.view(c->view);
    if (!view) return unknownView(s.views, c->view);
    const std::int64_t w = c->patch.width.value_or(view->camera.width);
    const std::int64_t h = c->patch.height.value_or(view->camera.height);
    if (w * h > config_.max_image_pixels)
      return ProtocolError{ErrorCode::kLimit, "width x height: " + std::to_string(w) + "x" +
                                                  std::to_string(h) + " is above the limit of " +
                                                  std::to_string(config_.max_image_pixels) +
                                                  " pixels"};
  }
  if (const auto* c = std::get_if<command::Tick>(&command)) return checkAdvance(c->dt);
  if (const auto* c = std::get_if<command::SetTime>(&command); c && c->advance)
    return checkAdvance(*c->advance);
  return std::nullopt;
}

void Engine::execute(Job& job) {
  State& s = *state_;
  ++s.requests;
  if (job.kind == Job::Kind::kBatch) {
    if (job.ticket && !job.ticket->claim()) return;  // withdrawn: its sender answered busy
    auto refuse = [&](const ProtocolError& error) {
      noteError(error.code);
      if (job.render) trigger_pending_ = false;
      job.done(error);
    };
    for (const Command& c : job.batch)
      if (auto error = check(c)) return refuse(*error);
    if (job.render && encoder_->depth() >= kEncoderQueue)
      return refuse({ErrorCode::kBusy, "the image encoder is busy"});
    for (const Command& c : job.batch)
      if (auto outcome = apply(c, job);
          outcome && std::holds_alternative<ProtocolError>(*outcome)) {
        publishReadings();
        return refuse(std::get<ProtocolError>(*outcome));
      }
    publishReadings();  // so that a register read right after the reply sees the change
    job.done(std::nullopt);
    if (job.render) renderTrigger();  // the render coil reads 1 until the file is written
    return;
  }
  std::optional<Outcome> outcome;
  if (auto error = check(job.request.command))
    outcome = *error;
  else
    outcome = apply(job.request.command, job);
  if (!outcome) return;  // the encoder replies
  publishReadings();     // so that a register read right after the reply sees the change
  if (const auto* error = std::get_if<ProtocolError>(&*outcome)) {
    noteError(error->code);
    job.reply(makeReply(errorReply(job.request.id, *error)));
  } else {
    job.reply(makeReply(okReply(job.request.id, std::get<json>(*outcome))));
  }
}

std::optional<Outcome> Engine::apply(const Command& command, Job& job) {
  State& s = *state_;
  World& world = *s.world;
  using namespace command;
  auto notFoundView = [&](const std::string& name) -> Outcome {
    return unknownView(s.views, name);
  };
  const ProtocolError noSnapshotDirectory{
      ErrorCode::kFailed, "name: no snapshot directory is configured ([snapshot] directory)"};
  auto snapshotPath = [&](const std::string& name) {
    return (std::filesystem::path(config_.snapshotDirectory()) / (name + ".snap")).string();
  };

  if (const auto* c = std::get_if<Hello>(&command)) {
    (void)c;  // the token is checked by the transport
    json views = json::array();
    for (const ViewConfig& v : s.views) views.push_back(v.name);
    return json{{"server", "nephele"},
                {"version", NEPHELE_VERSION},
                {"protocol", kProtocolVersion},
                {"views", views},
                {"mode", modeName(config_.mode)},
                {"tick_rate", config_.tick_rate_hz}};
  }
  if (const auto* c = std::get_if<GetView>(&command)) {
    if (c->view.empty()) {
      json all = json::array();
      for (const ViewConfig& v : s.views) all.push_back(viewJson(v));
      return json{{"views", all}};
    }
    const ViewConfig* v = s.view(c->view);
    if (!v) return notFoundView(c->view);
    return viewJson(*v);
  }
  if (const auto* c = std::get_if<SetView>(&command)) {
    ViewConfig* v = s.view(c->view);
    if (!v) return notFoundView(c->view);
    const ViewPatch& p = c->patch;
    Camera& cam = v->camera;
    if (p.position) cam.position = *p.position;
    if (p.heading) cam.orientation.heading_deg = *p.heading;
    if (p.pitch) cam.orientation.pitch_deg = *p.pitch;
    if (p.roll) cam.orientation.roll_deg = *p.roll;
    if (p.vfov) cam.vfov_deg = *p.vfov;
    if (p.width) cam.width = *p.width;
    if (p.height) cam.height = *p.height;
    if (p.image) v->image = *p.image;
    return viewJson(*v);
  }
  if (const auto* c = std::get_if<SetWeather>(&command)) {
    if (auto error = setWeather(c->layer, c->weather)) return *error;
    return json{{"layer", c->layer},
                {"type", cloudTypeName(c->weather.type)},
                {"layers", world.base().layers.size()},
                {"clouds", world.base().clouds.size()},
                {"fields", world.base().fields.size()}};
  }
  if (const auto* c = std::get_if<SetWind>(&command)) {
    std::string error = world.edit([&](Scene&, WorldDynamics& d) {
      d.wind.samples = {{0.0, c->velocity}};
      return std::string();
    });
    if (!error.empty()) return ProtocolError{ErrorCode::kFailed, error};
    return json{{"velocity", {c->velocity.x, c->velocity.y}}};
  }
  if (const auto* c = std::get_if<SetSun>(&command)) {
    Sun sun = world.base().sun;
    if (c->azimuth) sun.azimuth_deg = *c->azimuth;
    if (c->elevation) sun.elevation_deg = *c->elevation;
    world.setSun(sun);
    return json{{"azimuth", sun.azimuth_deg}, {"elevation", sun.elevation_deg}};
  }
  if (const auto* c = std::get_if<SetTime>(&command)) {
    if (c->time_scale) s.time_scale = *c->time_scale;
    if (c->paused) s.paused = *c->paused;
    if (c->advance) advance(*c->advance);
    return json{{"time", world.timeSeconds()}, {"time_scale", s.time_scale}, {"paused", s.paused}};
  }
  if (const auto* c = std::get_if<AddCloud>(&command)) {
    const auto name = c->cloud.find("name");
    if (name == c->cloud.end() || !name->is_string())
      return badField("cloud.name: is missing (a unique name, to change or remove the cloud by)");
    if (std::string e = nameError(name->get<std::string>()); !e.empty())
      return badField("cloud.name: " + e);
    EllipsoidCloud cloud;
    const std::string cloud_name = name->get<std::string>();
    if (std::string e = parseCloudJson(
            c->cloud, hashCounters(config_.scene.scene.seed, nameHash(cloud_name)), cloud);
        !e.empty())
      return badField(e);
    std::size_t ellipsoids = cloud.ellipsoids.size();
    std::string error = world.edit([&](Scene& now, WorldDynamics& d) -> std::string {
      if (now.clouds.size() >= kMaxClouds)
        return "cloud: the world holds " + std::to_string(kMaxClouds) + " clouds already";
      for (const EllipsoidCloud& other : now.clouds)
        if (other.name == cloud.name) return "cloud.name: \"" + cloud.name + "\" is taken";
      now.clouds.push_back(cloud);
      if (!d.clouds.empty()) d.clouds.emplace_back();
      return "";
    });
    if (!error.empty()) return badField(error);
    return json{{"name", cloud.name}, {"ellipsoids", ellipsoids}};
  }
  if (const auto* c = std::get_if<ChangeCloud>(&command)) {
    std::string error = world.edit([&](Scene& now, WorldDynamics&) -> std::string {
      for (EllipsoidCloud& cloud : now.clouds) {
        if (cloud.name != c->name) continue;
        if (c->move) {
          for (Ellipsoid& e : cloud.ellipsoids) e.centre += *c->move;
          cloud.drift_m += *c->move;  // the texture moves with the cloud
        }
        if (c->threshold) cloud.threshold_centre = *c->threshold;
        if (c->limb_threshold) cloud.threshold_limb = *c->limb_threshold;
        if (c->transition) cloud.transition = *c->transition;
        if (c->colour) cloud.colour = *c->colour;
        return "";
      }
      return "name: no cloud is called \"" + c->name + "\"";
    });
    if (!error.empty()) return ProtocolError{ErrorCode::kNotFound, error};
    return json{{"name", c->name}};
  }
  if (const auto* c = std::get_if<RemoveCloud>(&command)) {
    std::string error = world.edit([&](Scene& now, WorldDynamics& d) -> std::string {
      const std::size_t before = now.clouds.size();
      eraseWithDevelopment(now.clouds, d.clouds,
                           [&](const EllipsoidCloud& cloud) { return cloud.name == c->name; });
      return now.clouds.size() == before ? "name: no cloud is called \"" + c->name + "\"" : "";
    });
    if (!error.empty()) return ProtocolError{ErrorCode::kNotFound, error};
    return json{{"name", c->name}};
  }
  if (const auto* c = std::get_if<Tick>(&command)) {
    advance(c->dt);
    return json{{"time", world.timeSeconds()}, {"ticks", s.ticks}};
  }
  if (const auto* c = std::get_if<Render>(&command)) {
    const ViewConfig* v = s.view(c->view);
    if (!v) return notFoundView(c->view);
    const ImageRequest image = c->image.value_or(v->image);
    auto frame = std::make_shared<ViewFrame>();
    renderFrame(*v, image, *frame);
    json meta = imageMeta(*frame, image);
    if (image.format == ImageFormat::kRaw && !image.floatPlanes()) {
      auto body = packRaw(frame->srgb, image.colour, image.coverage);
      std::string header = imageReplyHeader(job.request.id, std::move(meta), body.size());
      job.reply(makeReply(std::move(header),
                          std::make_shared<const std::vector<std::uint8_t>>(std::move(body))));
      return std::nullopt;
    }
    const bool queued = encoder_->post([frame, image, meta, id = job.request.id, reply = job.reply,
                                        options = config_.encode]() mutable {
      auto encoded = encodeFrame(*frame, image, options);
      if (auto* e = std::get_if<std::string>(&encoded)) {
        reply(makeReply(errorReply(id, {ErrorCode::kFailed, *e})));
        return;
      }
      auto& bytes = std::get<std::vector<std::uint8_t>>(encoded);
      std::string header = imageReplyHeader(id, std::move(meta), bytes.size());
      reply(makeReply(std::move(header),
                      std::make_shared<const std::vector<std::uint8_t>>(std::move(bytes))));
    });
    if (!queued) return ProtocolError{ErrorCode::kBusy, "the image encoder is busy; try again"};
    return std::nullopt;
  }
  if (const auto* c = std::get_if<Subscribe>(&command)) {
    const ViewConfig* v = s.view(c->view);
    if (!v) return notFoundView(c->view);
    if (int(s.subscriptions.size()) >= config_.max_subscriptions)
      return ProtocolError{ErrorCode::kLimit, "subscribe: the daemon serves " +
                                                  std::to_string(config_.max_subscriptions) +
                                                  " subscriptions already (the configured limit)"};
    Subscription sub;
    sub.id = s.next_subscription++;
    sub.client = job.client;
    sub.view = c->view;
    sub.image = c->image.value_or(v->image);
    sub.period = secondsToDuration(1.0 / c->rate_hz);
    sub.next_due = Clock::now();
    sub.sink = job.frames;
    sub.gone = std::make_shared<std::atomic<bool>>(false);
    s.subscriptions.push_back(sub);
    countSubscriptions();
    return json{{"subscription", sub.id},
                {"view", sub.view},
                {"rate", c->rate_hz},
                {"format", imageFormatName(sub.image.format)},
                {"channels", channelNames(sub.image)}};
  }
  if (const auto* c = std::get_if<Unsubscribe>(&command)) {
    const std::size_t before = s.subscriptions.size();
    std::erase_if(s.subscriptions, [&](const Subscription& sub) {
      return sub.id == c->subscription && sub.client == job.client;
    });
    countSubscriptions();
    if (s.subscriptions.size() == before)
      return ProtocolError{ErrorCode::kNotFound,
                           "subscription: " + std::to_string(c->subscription) +
                               " is not one of this connection's subscriptions"};
    return json{{"subscription", c->subscription}};
  }
  if (const auto* c = std::get_if<Snapshot>(&command)) {
    if (config_.snapshotDirectory().empty()) return noSnapshotDirectory;
    std::error_code ec;
    std::filesystem::create_directories(config_.snapshotDirectory(), ec);
    if (std::string e = world.saveSnapshot(snapshotPath(c->name)); !e.empty())
      return ProtocolError{ErrorCode::kFailed, e};
    return json{{"name", c->name}, {"time", world.timeSeconds()}, {"hash", hexHash(world.hash())}};
  }
  if (const auto* c = std::get_if<Restore>(&command)) {
    if (config_.snapshotDirectory().empty()) return noSnapshotDirectory;
    const std::string path = snapshotPath(c->name);
    if (!std::filesystem::exists(path))
      return ProtocolError{ErrorCode::kNotFound, "name: no snapshot \"" + c->name + "\""};
    if (std::string e = world.restoreSnapshot(path); !e.empty())
      return ProtocolError{ErrorCode::kFailed, e};
    return json{{"name", c->name}, {"time", world.timeSeconds()}, {"hash", hexHash(world.hash())}};
  }
  if (std::holds_alternative<Stats>(command)) {
    publish();
    std::lock_guard lock(published_mutex_);
    return published_stats_;
  }
  if (std::holds_alternative<Hash>(command))
    return json{{"hash", hexHash(world.hash())},
                {"time", world.timeSeconds()},
                {"time_ns", world.timeNs()},
                {"ticks", s.ticks}};
  return ProtocolError{ErrorCode::kUnknownCommand, "unhandled command"};
}

void Engine::renderFrame(const ViewConfig& view, const ImageRequest& image, ViewFrame& frame) {
  State& s = *state_;
  Scene scene = s.world->scene();
  scene.camera = view.camera;
  const auto t0 = Clock::now();
  if (image.floatPlanes()) {
    FrameRequest request;
    request.channels = image.planes;
    if (image.colour) request.channels.add(Channel::kColour);
    if (image.coverage) request.channels.add(Channel::kCoverage);
    request.tick = std::uint64_t(s.ticks);
    frame.planes = s.renderer->renderFrame(scene, config_.scene.render, request);
  } else if (image.format == ImageFormat::kExr) {
    frame.linear = s.renderer->renderFloat(scene, config_.scene.render);
  } else {
    frame.srgb = s.renderer->renderSrgb8(scene, config_.scene.render);
  }
  s.last_render_ms = msSince(t0);
  s.render_ms.push_back(s.last_render_ms);
  if (s.render_ms.size() > kRenderHistory) s.render_ms.pop_front();
  ++s.frames;
  frame.meta = {{"view", view.name},
                {"width", view.camera.width},
                {"height", view.camera.height},
                {"time", s.world->timeSeconds()},
                {"tick", s.ticks},
                {"frame", s.frames},
                {"camera", cameraJson(frameInfo(view.camera, s.world->timeSeconds(),
                                                std::uint64_t(s.ticks)))}};
}

std::optional<ProtocolError> Engine::setWeather(int layer, const WeatherLayer& weather) {
  State& s = *state_;
  // The daemon's own names hold a '/', which no user name may (world/limits.h): set_weather
  // replaces exactly what it made before.
  const std::string prefix = "weather/" + std::to_string(layer);
  const WeatherClouds add =
      weatherClouds(weather, prefix, weatherSeed(config_.scene.scene.seed, layer));
  std::string error = s.world->edit([&](Scene& now, WorldDynamics& d) -> std::string {
    auto made = [&](const std::string& name) {
      return name == prefix || name.rfind(prefix + "/", 0) == 0;
    };
    eraseWithDevelopment(now.layers, d.layers, [&](const CloudLayer& l) { return made(l.name); });
    std::erase_if(now.fields, [&](const CloudField& f) { return made(f.name); });
    now.fields.insert(now.fields.end(), add.fields.begin(), add.fields.end());
    for (const CloudLayer& l : add.layers) {
      now.layers.push_back(l);
      if (!d.layers.empty()) d.layers.emplace_back();
    }
    if (weather.wind)
      setWindSample(d.wind, weather.base_m + 0.5 * weather.thickness_m, *weather.wind);
    return "";
  });
  if (!error.empty()) return ProtocolError{ErrorCode::kFailed, error};
  s.weather[std::size_t(layer - 1)] = weather;
  spdlog::info(
      "event=weather layer={} type={} base={} thickness={} coverage={:.2f} planes={} "
      "fields={}",
      layer, cloudTypeName(weather.type), weather.base_m, weather.thickness_m, weather.coverage,
      add.layers.size(), add.fields.size());
  return std::nullopt;
}

void Engine::deliverFrames(bool only_due, const std::string& view_name) {
  State& s = *state_;
  if (std::erase_if(s.subscriptions, [](const Subscription& sub) { return sub.gone->load(); }))
    countSubscriptions();
  const auto now = Clock::now();
  // Group the subscriptions that are due by view and by image request: one render per view
  // (and per kind of pixel), one encoding per request.
  std::map<std::string, std::vector<Subscription*>> by_view;
  for (Subscription& sub : s.subscriptions) {
    const bool due = only_due ? now >= sub.next_due : sub.view == view_name;
    if (!due) continue;
    sub.next_due += sub.period;
    if (sub.next_due < now) sub.next_due = now + sub.period;  // a slow render: skip, never burst
    by_view[sub.view].push_back(&sub);
  }
  for (auto& [name, subs] : by_view) {
    const ViewConfig* view = s.view(name);
    if (!view) continue;
    std::shared_ptr<ViewFrame> frames[2];  // 8-bit and linear
    std::vector<std::pair<ImageRequest, std::vector<Subscription*>>> groups;
    for (Subscription* sub : subs) {
      auto it = std::find_if(groups.begin(), groups.end(),
                             [&](const auto& g) { return g.first == sub->image; });
      if (it == groups.end())
        groups.push_back({sub->image, {sub}});
      else
        it->second.push_back(sub);
    }
    for (auto& [image, members] : groups) {
      const bool linear = image.format == ImageFormat::kExr;
      std::shared_ptr<ViewFrame> planes;  // ground-truth channels: rendered for this group
      std::shared_ptr<ViewFrame>& frame = image.floatPlanes() ? planes : frames[linear ? 1 : 0];
      if (!frame) {
        frame = std::make_shared<ViewFrame>();
        renderFrame(*view, image, *frame);
      }
      std::vector<Subscription> sinks;  // copies: the encoder may run after a change
      for (Subscription* sub : members) sinks.push_back(*sub);
      auto send = [frame, image = image, sinks, options = config_.encode]() {
        auto encoded = encodeFrame(*frame, image, options);
        if (auto* e = std::get_if<std::string>(&encoded)) {
          spdlog::error("event=encode_failed error=\"{}\"", *e);
          return;
        }
        auto bytes = std::make_shared<const std::vector<std::uint8_t>>(
            std::move(std::get<std::vector<std::uint8_t>>(encoded)));
        const json meta = imageMeta(*frame, image);
        for (const Subscription& sub : sinks)
          if (!sub.sink(makeReply(frameEventHeader(sub.id, meta, bytes->size()), bytes)))
            sub.gone->store(true);
      };
      if (image.format == ImageFormat::kRaw && !image.floatPlanes())
        send();
      else if (!encoder_->post(send))
        frames_dropped += members.size();
    }
  }
}

void Engine::renderTrigger() {
  State& s = *state_;
  const ViewConfig& view = *s.view(config_.modbus_view);
  const bool linear = config_.output_format == ImageFormat::kExr;
  auto frame = std::make_shared<ViewFrame>();
  ImageRequest image;
  image.format = config_.output_format;
  renderFrame(view, image, *frame);
  const std::string extension = config_.output_format == ImageFormat::kPng    ? ".png"
                                : config_.output_format == ImageFormat::kJpeg ? ".jpg"
                                                                              : ".exr";
  const std::filesystem::path path = std::filesystem::path(config_.output_directory) /
                                     (view.name + "_" + std::to_string(s.frames) + extension);
  // The caller checked that the encoder has room, and only this thread feeds it; the
  // subscribers' frames come after.
  encoder_->post([this, frame, linear, path, options = config_.encode]() {
    std::error_code ec;
    std::filesystem::create_directories(path.parent_path(), ec);
    // writeImageFile picks the format from the extension and renames into place.
    const std::string e = linear ? writeImageFile(path.string(), frame->linear, options)
                                 : writeImageFile(path.string(), frame->srgb, options);
    if (!e.empty()) {
      spdlog::error("event=render_trigger_failed error=\"{}\"", e);
      noteError(ErrorCode::kFailed);
    } else {
      spdlog::info("event=render_trigger path={}", path.string());
    }
    trigger_pending_ = false;
  });
  deliverFrames(false, view.name);
}

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
  std::size_t depth = 0;
  {
    std::lock_guard lock(queue_mutex_);
    depth = queue_.size();
  }
  const std::vector<double> history(s.render_ms.begin(), s.render_ms.end());
  const World& world = *s.world;
  json stats = {
      {"time", world.timeSeconds()},
      {"ticks", s.ticks},
      {"ticks_per_second", ticks_per_second},
      {"mode", modeName(config_.mode)},
      {"paused", s.paused},
      {"time_scale", s.time_scale},
      {"frames", s.frames},
      {"render_ms",
       {{"last", s.last_render_ms},
        {"p50", percentile(history, 0.5)},
        {"p99", percentile(history, 0.99)},
        {"samples", history.size()}}},
      {"clients", {{"socket", socket_clients.load()}, {"modbus", modbus_clients.load()}}},
      {"queue",
       {{"depth", depth},
        {"limit", config_.max_queue},
        {"encoder", encoder_ ? encoder_->depth() : 0},
        {"encoder_limit", kEncoderQueue}}},
      {"subscriptions", s.subscriptions.size()},
      {"frames_dropped", frames_dropped.load()},
      {"requests", s.requests},
      {"errors", errors_.load()},
      {"automaton_steps", world.automatonStepsRun()},
      {"relights", world.relightsRun()},
      {"last_frame", frameStatsJson(s.renderer->lastFrameStats())},
  };
  {
    std::lock_guard lock(published_mutex_);
    published_stats_ = std::move(stats);
  }
  publishReadings();
}

void Engine::publishReadings() {
  const State& s = *state_;
  const World& world = *s.world;
  ModbusSettings settings;
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
  settings.layers = s.weather;
  ModbusStatus status;
  status.status = config_.mode == TickMode::kLockstep ? ModbusStatusCode::kLockstep
                  : s.paused                          ? ModbusStatusCode::kPaused
                                                      : ModbusStatusCode::kRunning;
  status.frames = std::uint32_t(s.frames);
  status.render_ms = s.last_render_ms;
  status.ticks = s.ticks;
  status.time_s = world.timeSeconds();
  std::lock_guard lock(published_mutex_);
  published_settings_ = settings;
  published_status_ = status;
}

ModbusSettings Engine::modbusSettings() const {
  std::lock_guard lock(published_mutex_);
  return published_settings_;
}

ModbusStatus Engine::modbusStatus() const {
  std::lock_guard lock(published_mutex_);
  ModbusStatus status = published_status_;
  status.last_error = std::uint16_t(last_error_.load());
  return status;
}

json Engine::stats() const {
  std::lock_guard lock(published_mutex_);
  return published_stats_;
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
  metric("render_ms_p50", "gauge", "Median render time (last 1024).",
         st["render_ms"]["p50"].get<double>());
  metric("render_ms_p99", "gauge", "99th percentile render time (last 1024).",
         st["render_ms"]["p99"].get<double>());
  metric("socket_clients", "gauge", "Socket clients.", st["clients"]["socket"].get<double>());
  metric("modbus_clients", "gauge", "Modbus clients.", st["clients"]["modbus"].get<double>());
  metric("queue_depth", "gauge", "Requests waiting.", st["queue"]["depth"].get<double>());
  metric("subscriptions", "gauge", "Frame subscriptions.", st["subscriptions"].get<double>());
  metric("frames_dropped_total", "counter", "Frames dropped for slow clients.",
         st["frames_dropped"].get<double>());
  metric("errors_total", "counter", "Error replies and failed work.", st["errors"].get<double>());
  return out.str();
}

}  // namespace nephele
