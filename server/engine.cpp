#include "server/engine.h"

#include <spdlog/spdlog.h>

#include <filesystem>

#include "server/engine_detail.h"
#include "world/limits.h"
#include "world/world.h"

// The Engine's thread and loop, its time, and what it publishes after each request.
namespace nephele {

using namespace engine_detail;

Engine::Engine(DaemonConfig config)
    : config_(std::move(config)),
      queue_(std::size_t(config_.max_queue)),
      clock_(config_.mode, config_.tick_rate_hz, config_.time_scale),
      views_(config_.views),
      renders_(std::make_unique<RenderService>(config_, telemetry_)) {}

Engine::~Engine() {
  stop();
}

std::string Engine::start() {
  std::promise<std::string> started;
  std::future<std::string> result = started.get_future();
  // The encoder exists before the world thread, which posts to it (a race found by the tsan
  // preset when it was made after).
  renders_->startEncoder();
  thread_ = std::thread([this, &started] { run(started); });
  std::string error = result.get();
  if (!error.empty()) {
    thread_.join();
    renders_->finishEncoder();
    return error;
  }
  return "";
}

bool Engine::stop() {
  if (queue_.stop() && !thread_.joinable()) return shutdown_saved_;
  renders_->cancel();
  if (thread_.joinable()) thread_.join();
  renders_->finishEncoder();  // sends what it holds, then stops
  return shutdown_saved_;
}

Telemetry::Live Engine::live() const {
  return {queue_.depth(), renders_->encoderDepth()};
}

bool Engine::submit(Request request, std::int64_t client, PushSink push, ReplySink done,
                    std::shared_ptr<RequestTrace> trace) {
  Job job;
  job.trace = std::move(trace);
  if (job.trace) job.queued = job.trace->queued;
  job.request = std::move(request);
  job.client = client;
  job.push = std::move(push);
  job.reply = std::move(done);
  return queue_.push(std::move(job));
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
  if (queue_.push(std::move(job))) return true;
  if (render) trigger_pending_ = false;
  return false;
}

std::string Engine::openWorld() {
  if (std::string error = renders_->open(); !error.empty()) return error;
  world_ =
      std::make_unique<World>(config_.scene.scene, config_.scene.dynamics, config_.world_threads);
  if (std::string e = world_->advanceInPieces(config_.scene.scene.time_s); !e.empty())
    return "scene time: " + e;
  if (config_.site) world_->setSite({config_.site->latitude_deg, config_.site->longitude_deg, 0.0});
  if (std::string e = restoreAtStart(); !e.empty()) return e;
  for (const command::Stream& stream : config_.streams) {
    const Outcome started = startStream(stream);
    if (const auto* e = std::get_if<ProtocolError>(&started))
      return "[[stream]] of view " + stream.view + ": " + e->message;
  }
  spdlog::info("event=world_ready gl=\"{}\" backend={} views={} mode={} tick_rate={}",
               renders_->glName(), renders_->backendName(), views_.all().size(),
               modeName(clock_.mode()), config_.tick_rate_hz);
  return "";
}

std::string Engine::restoreAtStart() {
  const std::string& snapshot = config_.snapshot_path;
  if (!config_.restore_on_start || snapshot.empty() || !std::filesystem::exists(snapshot))
    return "";
  const std::string e = restoreSnapshot(snapshot);
  if (e.empty()) {
    spdlog::info("event=restored snapshot={} time={:.3f} ticks={} frames={} hash={}", snapshot,
                 world_->timeSeconds(), clock_.ticks(), telemetry_.frames(),
                 hexHash(world_->hash()));
    return "";
  }
  if (config_.snapshot_on_error != DaemonConfig::SnapshotOnError::kStartFresh)
    return e +
           " (move the file away, or set [snapshot] on_error = \"start_fresh\", to start from "
           "the scene instead)";
  // Kept for whoever looks into it; the next snapshot takes the path. A restore that fails
  // changes nothing, so the world is still the scene's.
  std::error_code ec;
  for (const std::string& file : {snapshot, daemonStatePath(snapshot)})
    if (std::filesystem::exists(file, ec)) std::filesystem::rename(file, file + ".rejected", ec);
  spdlog::error(
      "event=snapshot_rejected path={} moved_to={}.rejected error=\"{}\" "
      "action=start_fresh",
      snapshot, snapshot, e);
  telemetry_.noteSnapshotFailed();
  return "";
}

void Engine::run(std::promise<std::string>& started) {
  if (std::string error = openWorld(); !error.empty()) {
    renders_->close();
    started.set_value(error);
    return;
  }
  clock_.start(Clock::now());
  prewarming_ = config_.prewarm;
  next_snapshot_ = Clock::now() + secondsToDuration(config_.snapshot_interval_s);
  publish();
  started.set_value("");

  for (;;) {
    telemetry_.beat();
    RequestQueue::Taken taken = queue_.wait(nextWake());
    bool stopping = taken.stopping;
    views_.dropClients(taken.gone);
    for (Job& job : taken.jobs) {
      if (!stopping) {
        const std::string what = job.kind == Job::Kind::kBatch
                                     ? "modbus write"
                                     : std::string(commandName(job.request.command));
        telemetry_.setInHand(what, job.client);
        try {
          const auto t0 = Clock::now();
          if (job.trace) job.trace->started = t0;
          execute(job);
          telemetry_.noteRequestDone(job.queued);
          telemetry_.noteBusy(what, t0);
          continue;
        } catch (const RenderCancelled&) {
          stopping = true;  // stop() cancelled its render: answered as the queued ones
        }
      }
      const ProtocolError cancelled{ErrorCode::kFailed, "the daemon is shutting down"};
      if (job.reply) job.reply(makeReply(errorReply(job.request.id, cancelled)));
      if (job.done) job.done(cancelled);
    }
    telemetry_.setInHand("", 0);
    if (stopping) break;
    try {
      auto t0 = Clock::now();
      telemetry_.setInHand("ticks", 0);
      realtimeTicks();
      telemetry_.noteBusy("ticks", t0);
      // Realtime: subscriptions at their rate. Lockstep: a new subscription's first frame
      // (the ticks themselves deliver in advance()).
      t0 = Clock::now();
      telemetry_.setInHand("frames", 0);
      deliverFrames(clock_.lockstep() ? Delivery::kEveryTick : Delivery::kDue, "");
      telemetry_.noteBusy("frames", t0);
    } catch (const RenderCancelled&) {
      telemetry_.setInHand("", 0);
      break;  // stopping: the frames in hand are not sent
    }
    telemetry_.setInHand("", 0);
    if (config_.snapshot_interval_s > 0.0 && !config_.snapshot_path.empty() &&
        Clock::now() >= next_snapshot_) {
      const auto t0 = Clock::now();
      if (!saveSnapshot(config_.snapshot_path, "periodic").empty())
        telemetry_.noteError(ErrorCode::kFailed);
      telemetry_.noteBusy("snapshot", t0);
      next_snapshot_ = Clock::now() + secondsToDuration(config_.snapshot_interval_s);
    }
    auto t0 = Clock::now();
    publish();
    telemetry_.noteBusy("publish", t0);
    if (prewarming_) {  // a step after each round of what the world thread has to do
      t0 = Clock::now();
      prewarming_ = renders_->prewarmStep(views_.all());
      telemetry_.noteBusy("prewarm", t0);
    }
  }
  if (!config_.snapshot_path.empty())
    shutdown_saved_ = saveSnapshot(config_.snapshot_path, "shutdown").empty();
  views_.clear();
  renders_->close();  // GL objects go while their context is current
}

Engine::Clock::time_point Engine::nextWake() const {
  if (prewarming_) return Clock::now();  // its next step, after what is queued
  const Clock::time_point wake = Clock::now() + std::chrono::milliseconds(500);
  if (clock_.lockstep()) return wake;
  // The IG's frames go on while paused.
  return views_.nextDue(std::min(wake, clock_.nextTick()));
}

std::optional<ProtocolError> Engine::checkAdvance(double dt_s) const {
  // The World's own refusal, asked before anything is applied, so a refused advance is an
  // error reply and changes nothing.
  if (std::string e = world_->advanceError(dt_s); !e.empty())
    return ProtocolError{ErrorCode::kLimit, e};
  if (std::string e = automatonAdvanceError(world_->dynamics().automata, dt_s); !e.empty())
    return ProtocolError{ErrorCode::kLimit, e};
  return std::nullopt;
}

void Engine::advance(double dt_s) {
  if (std::string e = world_->advance(dt_s); !e.empty()) {
    spdlog::warn("event=advance_refused error=\"{}\"", e);
    telemetry_.noteError(ErrorCode::kLimit);
    return;
  }
  clock_.countTicks(1);
  // In lockstep every subscription gets exactly one frame of each tick.
  if (clock_.lockstep()) deliverFrames(Delivery::kEveryTick, "");
}

void Engine::realtimeTicks() {
  const int due = clock_.dueTicks(Clock::now());
  // Paused, the frames go on (a host in asynchronous mode still hears them) but hold time.
  if (due == 0 || clock_.paused()) return;
  double dt = clock_.secondsFor(due);
  if (checkAdvance(dt)) dt = 0.0;  // too much automaton work for one go: hold time
  clock_.countTicks(std::uint64_t(due));
  if (dt > 0.0) {
    if (std::string e = world_->advance(dt); !e.empty())
      spdlog::warn("event=advance_refused error=\"{}\"", e);
  }
}

void Engine::setMode(TickMode mode) {
  if (!clock_.setMode(mode)) return;
  // Realtime ticks and subscription periods start from now, not from when they last ran.
  views_.restartPeriods(Clock::now());
  spdlog::info("event=mode mode={}", modeName(mode));
}

void Engine::execute(Job& job) {
  telemetry_.noteRequest();
  if (job.kind == Job::Kind::kBatch) return executeBatch(job);
  std::optional<Outcome> outcome;
  if (auto error = check(job.request.command))
    outcome = *error;
  else
    outcome = apply(job.request.command, job);
  if (!outcome) return;  // the encoder replies
  // So that a register read, or a stats or hello answered at once (answerAtOnce), right after
  // the reply sees the change.
  publish();
  if (job.trace) job.trace->applied = Clock::now();  // before the reply hands the trace on
  if (const auto* error = std::get_if<ProtocolError>(&*outcome)) {
    telemetry_.noteError(error->code);
    job.reply(makeReply(errorReply(job.request.id, *error)));
  } else {
    job.reply(makeReply(okReply(job.request.id, std::get<json>(*outcome))));
  }
}

void Engine::executeBatch(Job& job) {
  if (job.ticket && !job.ticket->claim()) return;  // withdrawn: its sender answered busy
  auto refuse = [&](const ProtocolError& error) {
    telemetry_.noteError(error.code);
    if (job.render) trigger_pending_ = false;
    job.done(error);
  };
  for (const Command& c : job.batch)
    if (auto error = check(c)) return refuse(*error);
  if (job.render && renders_->encoderFull())
    return refuse({ErrorCode::kBusy, "the image encoder is busy"});
  for (const Command& c : job.batch)
    if (auto outcome = apply(c, job); outcome && std::holds_alternative<ProtocolError>(*outcome)) {
      publishReadings();
      return refuse(std::get<ProtocolError>(*outcome));
    }
  // So that a register read, or stats answered at once, right after the reply sees the change
  // (a CIGI frame that re-centred the world: its site).
  publish();
  job.done(std::nullopt);
  if (job.render) renderTrigger();  // the render coil reads 1 until the file is written
}

void Engine::publish() {
  const World& world = *world_;
  json stats = {
      {"time", world.timeSeconds()},
      {"ticks", clock_.ticks()},
      {"ticks_per_second", clock_.ticksPerSecond(Clock::now())},
      {"mode", modeName(clock_.mode())},
      {"paused", clock_.paused()},
      {"time_scale", clock_.timeScale()},
      // The counters other threads keep (clients, queue and encoder depth, frames dropped,
      // errors, CIGI) are added by Telemetry::stats when it is read.
      {"queue", {{"limit", config_.max_queue}, {"encoder_limit", RenderService::kEncoderQueue}}},
      {"subscriptions", views_.subscriptions().size()},
      {"automaton_steps", world.automatonStepsRun()},
      {"relights", world.relightsRun()},
      {"site", siteJson(world)},
      {"streams", views_.streamsJson()},
      {"last_frame", renders_->lastFrameJson()},
  };
  telemetry_.addRecords(stats);
  telemetry_.publishStats(std::move(stats));
  publishReadings();
}

void Engine::publishReadings() {
  const World& world = *world_;
  const Scene& base = world.base();
  HostReadings settings;
  const Camera& camera = views_.find(config_.modbus_view)->camera;
  settings.position = camera.position;
  settings.heading = camera.orientation.heading_deg;
  settings.pitch = camera.orientation.pitch_deg;
  settings.roll = camera.orientation.roll_deg;
  settings.vfov = camera.vfov_deg;
  settings.width = camera.width;
  settings.height = camera.height;
  const WindProfile& wind = world.dynamics().wind;
  settings.wind = wind.empty() ? glm::dvec2(0.0) : wind.samples.front().velocity;
  settings.sun_azimuth = base.sun.azimuth_deg;
  settings.sun_elevation = base.sun.elevation_deg;
  settings.time_scale = clock_.timeScale();
  for (int layer = 1; layer <= ProtocolLimits::kWeatherLayers; ++layer)  // the world's, as set
    if (auto w = base.weather.find({layer, std::nullopt}); w != base.weather.end())
      settings.layers[std::size_t(layer - 1)] = w->second;
  if (const std::optional<Fog>& fog = base.fog) {
    settings.fog_top = fog->top_m;
    settings.fog_visibility = fog->visibility_m;
    settings.fog_colour = fog->colour;
  }
  if (const std::optional<Haze>& haze = base.haze) {
    settings.haze_visibility = haze->visibility_m;
    settings.haze_scale_height = haze->scale_height_m;
  }
  settings.sun_utc = sun_utc_;
  HostStatus status;
  status.status = clock_.lockstep() ? RunState::kLockstep
                  : clock_.paused() ? RunState::kPaused
                                    : RunState::kRunning;
  status.frames = std::uint32_t(telemetry_.frames());
  status.render_ms = telemetry_.lastRenderMs();
  status.ticks = clock_.ticks();
  status.time_s = world.timeSeconds();
  telemetry_.publishReadings(settings, status, helloJson());
}

json Engine::helloJson() const {
  json views = json::array();
  for (const ViewConfig& v : views_.all()) views.push_back(v.name);
  return json{{"server", "nephele"},
              {"version", NEPHELE_VERSION},
              {"protocol", kProtocolVersion},
              {"views", views},
              {"mode", modeName(clock_.mode())},
              {"tick_rate", config_.tick_rate_hz}};
}

}  // namespace nephele
