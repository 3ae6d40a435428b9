#pragma once
// The daemon's world thread: it owns the World and carries out requests one at a time from a
// bounded queue, between the realtime ticks and the subscribed frames. Its jobs are parts of
// their own, each in one file:
//   RequestQueue   the requests waiting, filled by the transports (request_queue.h)
//   WorldClock     realtime or lockstep ticks, time scale and pause (world_clock.h)
//   Views          the views and their subscriptions and video streams (views.h)
//   RenderService  the GL renderer, size checks and the encoder thread (render_service.h)
//   Telemetry      stats, Modbus readings, Prometheus text and heartbeat (telemetry.h)
// The Engine joins them: requests in dispatch.cpp, frames in delivery.cpp, weather and the sun
// in atmosphere.cpp, snapshots in snapshots.cpp, the loop and publishing in engine.cpp.
// Transports include this header only, parse bytes and queue work.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "protocol/messages.h"
#include "server/daemon_config.h"
#include "server/reply.h"
#include "server/request_queue.h"
#include "server/telemetry.h"
#include "server/views.h"
#include "server/world_clock.h"

namespace nephele {

class RenderService;
class World;
struct RenderedView;

class Engine {
 public:
  explicit Engine(DaemonConfig config);
  ~Engine();
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  // Starts the world thread: GL context, world (restored from the snapshot if configured and
  // present). Returns an error if either fails.
  std::string start();
  // Finishes the request in hand, answers queued ones with an error, saves a snapshot if
  // configured and joins the thread. False when the shutdown snapshot could not be saved.
  bool stop();
  bool stopping() const { return queue_.stopping(); }

  // Queues work; each returns false (and queues nothing) when the queue is full.
  // `trace` (if given) is stamped as the request passes the world thread and the encoder.
  bool submit(Request request, std::int64_t client, PushSink push, ReplySink done,
              std::shared_ptr<RequestTrace> trace = nullptr);
  // A Modbus write: every command is checked before any is applied; with `render` (the
  // render coil) the Modbus view is then rendered into the output directory and pushed to
  // the view's subscribers. `done` hears the outcome once the commands are applied and the
  // render queued. Unless the world thread has claimed `ticket` first, the submitter may
  // withdraw the batch, and then nothing of it is applied.
  bool submitBatch(std::vector<Command> commands, bool render, std::shared_ptr<BatchTicket> ticket,
                   DoneSink done);
  // A socket client has gone: its subscriptions end now, not at their next frame.
  void clientGone(std::int64_t client) { queue_.clientGone(client); }
  // How many subscriptions a socket client holds (any thread).
  int subscriptionsOf(std::int64_t client) const { return views_.subscriptionsOf(client); }

  bool renderTriggerPending() const { return trigger_pending_.load(); }
  void clearRenderTrigger() { trigger_pending_ = false; }  // a withdrawn render write
  // The stats reply and the Prometheus text, with the queue's and encoder's depth read now.
  nlohmann::json stats() const { return telemetry_.stats(live()); }
  std::string prometheusText() const { return telemetry_.prometheusText(live()); }
  // The control plane: `hello` and `stats` answered on the caller's thread from what the world
  // thread published after its last request and what it has in hand now, so that they are
  // answered while the world thread renders (PROTOCOL.md, "Control plane"); nullopt for every
  // other command. A transport asks only for a client with nothing in flight, so that each
  // client still sees its replies in request order and the effects of its earlier requests.
  std::optional<nlohmann::json> answerAtOnce(const Command& command) {
    return telemetry_.answerAtOnce(command, live());
  }
  // Counters, readings and the heartbeat, for the transports (thread-safe parts only).
  Telemetry& telemetry() { return telemetry_; }
  const Telemetry& telemetry() const { return telemetry_; }

  const DaemonConfig& config() const { return config_; }
  bool lockstep() const { return clock_.lockstep(); }  // the clock's mode now (any thread)
  // Realtime mode: `started` is called on the world thread at the start of each of its frames
  // (each round of due ticks, at the tick rate, paused or not), before the frame's work: the
  // CIGI listener's asynchronous Start of Frame (docs/CIGI.md). One listener; any thread.
  void onFrameStart(std::function<void()> started) { clock_.onFrameStart(std::move(started)); }

 private:
  using Clock = std::chrono::steady_clock;
  using Outcome = std::variant<nlohmann::json, ProtocolError>;
  struct Handlers;  // a request's handler by command (dispatch.cpp)

  Telemetry::Live live() const;
  void run(std::promise<std::string>& started);
  std::string openWorld();
  // The configured snapshot restored at start, if there is one; "" or why the daemon cannot
  // start ([snapshot] on_error).
  std::string restoreAtStart();
  void execute(Job& job);
  void executeBatch(Job& job);
  // A request's result (or error); render and snapshot replies may come later from the
  // encoder, in which case it returns nothing and `job.reply` is called there.
  std::optional<Outcome> apply(const Command& command, Job& job);
  std::optional<ProtocolError> check(const Command& command) const;
  // A weather layer, global or of a CIGI region (command::SetWeather::region).
  std::optional<ProtocolError> setWeather(int layer, const WeatherLayer& weather,
                                          std::optional<int> region = std::nullopt);
  Outcome setSun(const command::SetSun& c);
  Outcome setFog(const command::SetFog& c);
  Outcome setHaze(const command::SetHaze& c);
  Outcome setSea(const command::SetSea& c);
  Outcome setSite(const command::SetSite& c);
  // What a set_site would refuse: a site out of range, or a re-centring that would carry a
  // target or a view beyond the range their readers accept (placementError).
  std::optional<ProtocolError> siteError(const command::SetSite& c) const;
  void setMode(TickMode mode);
  // Snapshots: the World's file and the daemon's state beside it (snapshots.cpp).
  nlohmann::json daemonState() const;
  std::string writeSnapshot(const std::string& path);
  std::string restoreSnapshot(const std::string& path);
  // Writes a snapshot (writeSnapshot), logging and counting a failure; "" or the error.
  std::string saveSnapshot(const std::string& path, const char* why);
  // Time: one tick (lockstep, or set_time advance) and the realtime ticks due (engine.cpp).
  std::optional<ProtocolError> checkAdvance(double dt_s) const;
  void advance(double dt_s);
  void realtimeTicks();
  Clock::time_point nextWake() const;
  // Frames (delivery.cpp): a render request, a view streamed as video and its end, the
  // subscriptions' frames, and the render coil's file.
  std::optional<Outcome> renderRequest(const command::Render& c, Job& job);
  Outcome startStream(const command::Stream& c);
  Outcome stopStream(const command::Unstream& c);
  void renderView(const ViewConfig& view, const ImageRequest& image, RenderedView& out,
                  bool continuous = false);
  std::optional<ProtocolError> platformLimit(const ViewConfig& view,
                                             const ImageRequest& image) const;
  void deliverFrames(Delivery which, const std::string& view);
  // One rendered view to the subscribers of one image request: streams to their encoders,
  // sockets through the image encoder (raw 8-bit at once).
  void sendToSubscribers(const std::shared_ptr<const RenderedView>& frame,
                         const ImageRequest& image, const std::vector<Subscription*>& members);
  void renderTrigger();
  // Telemetry (engine.cpp): the world thread's figures, and the cheap part after every request.
  void publish();
  void publishReadings();
  nlohmann::json helloJson() const;

  const DaemonConfig config_;
  Telemetry telemetry_;
  RequestQueue queue_;
  WorldClock clock_;
  Views views_;
  std::unique_ptr<RenderService> renders_;
  std::unique_ptr<World> world_;
  std::optional<CivilTime> sun_utc_;  // when the sun was last set from a date and time
  Clock::time_point next_snapshot_;
  std::atomic<bool> trigger_pending_{false};
  bool shutdown_saved_ = true;
  bool prewarming_ = false;  // [world] prewarm steps left (RenderService::prewarmStep)
  std::thread thread_;
};

}  // namespace nephele
