#include "server/engine.h"

#include <spdlog/spdlog.h>

#include <filesystem>
#include <map>

#include "server/engine_state.h"
#include "world/limits.h"
#include "world/world.h"

// The Engine's thread, queue and clock. Requests are dispatched in dispatch.cpp, frames made
// and delivered in delivery.cpp, weather and atmosphere mapped in atmosphere.cpp, snapshots
// in snapshots.cpp, stats and metrics in telemetry.cpp.
namespace nephele {

using namespace engine_detail;

Engine::Engine(DaemonConfig config)
    : config_(std::move(config)), state_(std::make_unique<State>()) {
  state_->views = config_.views;
  state_->time_scale = config_.time_scale;
  state_->mode = config_.mode;
  lockstep_ = config_.mode == TickMode::kLockstep;
}

Engine::~Engine() {
  stop();
}

std::string Engine::start() {
  std::promise<std::string> started;
  std::future<std::string> result = started.get_future();
  // The encoder exists before the world thread, which reads it (a race found by the tsan
  // preset when it was made after).
  encoder_ = std::make_unique<Encoder>();
  thread_ = std::thread([this, &started] { run(started); });
  std::string error = result.get();
  if (!error.empty()) {
    thread_.join();
    encoder_.reset();
    return error;
  }
  return "";
}

bool Engine::stop() {
  {
    std::lock_guard lock(queue_mutex_);
    if (stopping_ && !thread_.joinable()) return shutdown_saved_;
    stopping_ = true;
  }
  cancel_renders_ = true;
  queue_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
  if (encoder_) encoder_->finish();  // sends what it holds, then stops; kept for stats()
  return shutdown_saved_;
}

double Engine::heartbeatAge() const {
  const std::int64_t beat = heartbeat_ns_.load();
  if (beat == 0) return 0.0;  // not started yet
  return std::chrono::duration<double>(Clock::now().time_since_epoch() - Clock::duration(beat))
      .count();
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

bool Engine::submit(Request request, std::int64_t client, PushSink push, ReplySink done) {
  Job job;
  job.request = std::move(request);
  job.client = client;
  job.push = std::move(push);
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

std::string Engine::openWorld() {
  State& s = *state_;
  std::string error;
  s.platform = createGlPlatform(GlBackend::kAuto, error);
  if (!s.platform) return "no OpenGL context: " + error;
  s.renderer = std::make_unique<GlRenderer>(*s.platform);
  // A long render beats the heart at each point where it can be cancelled, so /healthz and the
  // systemd watchdog tell a render that makes progress from a stuck world thread.
  s.renderer->setCancel(&cancel_renders_, [this] { beatHeart(); });
  s.world =
      std::make_unique<World>(config_.scene.scene, config_.scene.dynamics, config_.world_threads);
  if (std::string e = s.world->advanceInPieces(config_.scene.scene.time_s); !e.empty())
    return "scene time: " + e;
  if (config_.site)
    s.world->setSite({config_.site->latitude_deg, config_.site->longitude_deg, 0.0});
  const std::string& snapshot = config_.snapshot_path;
  if (config_.restore_on_start && !snapshot.empty() && std::filesystem::exists(snapshot)) {
    if (std::string e = restoreSnapshot(snapshot); !e.empty())
      return e + " (move the file away to start from the scene instead)";
    spdlog::info("event=restored snapshot={} time={:.3f} ticks={} frames={} hash={}", snapshot,
                 s.world->timeSeconds(), s.ticks, s.frames, hexHash(s.world->hash()));
  }
  for (const command::Stream& stream : config_.streams) {
    const Outcome started = startStream(stream);
    if (const auto* e = std::get_if<ProtocolError>(&started))
      return "[[stream]] of view " + stream.view + ": " + e->message;
  }
  spdlog::info("event=world_ready gl=\"{}\" backend={} views={} mode={} tick_rate={}",
               s.platform->renderer(), s.platform->backendName(), s.views.size(), modeName(s.mode),
               config_.tick_rate_hz);
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
    beatHeart();
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
        setInHand(job.kind == Job::Kind::kBatch ? "modbus write"
                                                : std::string(commandName(job.request.command)),
                  job.client);
        try {
          execute(job);
          s.request_seconds.add(std::chrono::duration<double>(Clock::now() - job.queued).count());
          continue;
        } catch (const RenderCancelled&) {
          stopping = true;  // stop() cancelled its render: answered as the queued ones
        }
      }
      const ProtocolError cancelled{ErrorCode::kFailed, "the daemon is shutting down"};
      if (job.reply) job.reply(makeReply(errorReply(job.request.id, cancelled)));
      if (job.done) job.done(cancelled);
    }
    setInHand("", 0);
    if (stopping) break;
    try {
      setInHand("ticks", 0);
      realtimeTicks();
      // Realtime: subscriptions at their rate. Lockstep: a new subscription's first frame
      // (the ticks themselves deliver in advance()).
      setInHand("frames", 0);
      deliverFrames(s.mode == TickMode::kRealtime ? Delivery::kDue : Delivery::kEveryTick, "");
    } catch (const RenderCancelled&) {
      setInHand("", 0);
      break;  // stopping: the frames in hand are not sent
    }
    setInHand("", 0);
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
  if (s.mode == TickMode::kRealtime) {
    wake = std::min(wake, s.next_tick);  // the IG's frames go on while paused
    for (const Subscription& sub : s.subscriptions) wake = std::min(wake, sub.next_due);
  }
  return wake;
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
  // In lockstep every subscription gets exactly one frame of each tick.
  if (s.mode == TickMode::kLockstep) deliverFrames(Delivery::kEveryTick, "");
}

void Engine::onFrameStart(std::function<void()> started) {
  std::lock_guard lock(frame_listener_mutex_);
  frame_listener_ = std::move(started);
}

void Engine::realtimeTicks() {
  State& s = *state_;
  if (s.mode != TickMode::kRealtime) return;
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
  {
    std::lock_guard lock(frame_listener_mutex_);
    if (frame_listener_) frame_listener_();
  }
  // Paused, the frames go on (a host in asynchronous mode still hears them) but hold time.
  if (s.paused) return;
  double dt = due * s.time_scale / config_.tick_rate_hz;
  if (checkAdvance(dt)) dt = 0.0;  // too much automaton work for one go: hold time
  for (int i = 0; i < due; ++i) ++s.ticks;
  if (dt > 0.0) {
    if (std::string e = s.world->advance(dt); !e.empty())
      spdlog::warn("event=advance_refused error=\"{}\"", e);
  }
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
    if (job.render) {
      renderTrigger();  // the render coil reads 1 until the file is written
      // The frame counter it moved, published before the encoder writes the file and clears the
      // coil: a host that sees the coil at 0 reads the new count.
      publishReadings();
    }
    return;
  }
  std::optional<Outcome> outcome;
  if (auto error = check(job.request.command))
    outcome = *error;
  else
    outcome = apply(job.request.command, job);
  if (!outcome) return;  // the encoder replies
  // So that a register read, or a stats or hello answered at once (answerAtOnce), right after
  // the reply sees the change.
  publish();
  if (const auto* error = std::get_if<ProtocolError>(&*outcome)) {
    noteError(error->code);
    job.reply(makeReply(errorReply(job.request.id, *error)));
  } else {
    job.reply(makeReply(okReply(job.request.id, std::get<json>(*outcome))));
  }
}

}  // namespace nephele
