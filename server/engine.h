#pragma once
// The daemon's world thread: it owns the World, the GL context and the views, advances time
// (in real time or in lockstep with the host), carries out requests one at a time from a
// bounded queue and delivers subscribed frames. Transports only parse bytes and queue work.
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <variant>
#include <vector>

#include <nlohmann/json.hpp>

#include "protocol/messages.h"
#include "server/daemon_config.h"

namespace nephele {

// A reply: one JSON line, and for images the bytes that follow it (shared, so that one
// encoded frame goes to every subscriber without a copy). `then` holds replies written right
// after it, as one unit (the images of a render of several views).
struct Reply {
  std::string header;
  std::shared_ptr<const std::vector<std::uint8_t>> body;
  std::vector<std::shared_ptr<const Reply>> then;
  std::size_t size() const {
    std::size_t n = header.size() + (body ? body->size() : 0);
    for (const auto& r : then) n += r->size();
    return n;
  }
};
using SharedReply = std::shared_ptr<const Reply>;

inline SharedReply makeReply(std::string header,
                             std::shared_ptr<const std::vector<std::uint8_t>> body = nullptr) {
  return std::make_shared<const Reply>(Reply{std::move(header), std::move(body), {}});
}

// Several replies written as one, in order.
inline SharedReply chainReplies(std::vector<SharedReply> replies) {
  if (replies.size() == 1) return replies.front();
  Reply first = *replies.front();
  first.then.assign(replies.begin() + 1, replies.end());
  return std::make_shared<const Reply>(std::move(first));
}

// Receives a request's reply, once, on a daemon thread (not the caller's).
using ReplySink = std::function<void(SharedReply)>;
// Receives what is pushed to a client unasked (its subscriptions' images); returns false
// once the client is gone, which ends its subscriptions.
using PushSink = std::function<bool(SharedReply)>;
// Receives the outcome of a Modbus write or render trigger.
using DoneSink = std::function<void(std::optional<ProtocolError>)>;

// A configured number of seconds as a steady-clock duration.
inline std::chrono::steady_clock::duration secondsToDuration(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(s));
}

// Decides, once, between the world thread applying a batch and its submitter withdrawing it.
class BatchTicket {
 public:
  bool claim() { return take(kClaimed); }
  bool withdraw() { return take(kWithdrawn); }

 private:
  enum : int { kOpen, kClaimed, kWithdrawn };
  bool take(int to) {
    int open = kOpen;
    return state_.compare_exchange_strong(open, to);
  }
  std::atomic<int> state_{kOpen};
};

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
  bool stopping() const;

  // Queues work; each returns false (and queues nothing) when the queue is full.
  bool submit(Request request, std::int64_t client, PushSink push, ReplySink done);
  // A Modbus write: every command is checked before any is applied; with `render` (the
  // render coil) the Modbus view is then rendered into the output directory and pushed to
  // the view's subscribers. `done` hears the outcome once the commands are applied and the
  // render queued. Unless the world thread has claimed `ticket` first, the submitter may
  // withdraw the batch, and then nothing of it is applied.
  bool submitBatch(std::vector<Command> commands, bool render, std::shared_ptr<BatchTicket> ticket,
                   DoneSink done);
  // A socket client has gone: its subscriptions end now, not at their next frame.
  void clientGone(std::int64_t client);
  // How many subscriptions a socket client holds (any thread).
  int subscriptionsOf(std::int64_t client) const;

  // Thread-safe readings for the transports (Modbus registers), stats and metrics.
  HostReadings readings() const;
  HostStatus status() const;
  bool renderTriggerPending() const { return trigger_pending_.load(); }
  void clearRenderTrigger() { trigger_pending_ = false; }  // a withdrawn render write
  nlohmann::json stats() const;
  std::string prometheusText() const;
  // The control plane: `hello` and `stats` answered on the caller's thread from what the world
  // thread published after its last request and what it has in hand now, so that they are
  // answered while the world thread renders (PROTOCOL.md, "Control plane"); nullopt for every
  // other command. A transport asks only for a client with nothing in flight, so that each
  // client still sees its replies in request order and the effects of its earlier requests.
  std::optional<nlohmann::json> answerAtOnce(const Command& command);

  // Counters kept by the transports.
  std::atomic<int> socket_clients{0};
  std::atomic<int> modbus_clients{0};
  std::atomic<std::uint64_t> frames_dropped{0};
  void noteError(ErrorCode code);
  // CIGI messages applied, refused (by reason) and packets ignored, for stats and metrics.
  void countCigi(const std::string& what);

  const DaemonConfig& config() const { return config_; }
  bool lockstep() const { return lockstep_.load(); }  // the clock's mode now (any thread)
  // Realtime mode: `started` is called on the world thread at the start of each of its frames
  // (each round of due ticks, at the tick rate, paused or not), before the frame's work: the
  // CIGI listener's asynchronous Start of Frame (docs/CIGI.md). One listener; any thread.
  void onFrameStart(std::function<void()> started);
  // Seconds since the world thread last went round its loop (any thread): the health check
  // of /healthz and the systemd watchdog.
  double heartbeatAge() const;
  static constexpr double kStuckSeconds = 20.0;

 private:
  using Clock = std::chrono::steady_clock;
  struct Job;
  struct Subscription;
  struct State;     // everything the world thread owns
  struct Handlers;  // a request's handler by command (dispatch.cpp)
  class Encoder;

  bool enqueue(Job job);
  void run(std::promise<std::string>& started);
  std::string openWorld();
  void execute(Job& job);
  // A request's result (or error); render and snapshot replies may come later from the
  // encoder, in which case it returns nothing and `job.reply` is called there.
  std::optional<std::variant<nlohmann::json, ProtocolError>> apply(const Command& command,
                                                                   Job& job);
  std::optional<ProtocolError> check(const Command& command) const;
  // A weather layer, global or of a CIGI region (command::SetWeather::region).
  std::optional<ProtocolError> setWeather(int layer, const WeatherLayer& weather,
                                          std::optional<int> region = std::nullopt);
  std::variant<nlohmann::json, ProtocolError> setSun(const command::SetSun& c);
  std::variant<nlohmann::json, ProtocolError> setFog(const command::SetFog& c);
  std::variant<nlohmann::json, ProtocolError> setHaze(const command::SetHaze& c);
  std::variant<nlohmann::json, ProtocolError> setSea(const command::SetSea& c);
  std::variant<nlohmann::json, ProtocolError> setSite(const command::SetSite& c);
  // A view streamed as video (delivery.cpp), and its end.
  std::variant<nlohmann::json, ProtocolError> startStream(const command::Stream& c);
  std::variant<nlohmann::json, ProtocolError> stopStream(const command::Unstream& c);
  nlohmann::json streamsJson() const;  // the streamed views and their counts (stats)
  void setMode(TickMode mode);
  std::optional<std::variant<nlohmann::json, ProtocolError>> renderRequest(const command::Render& c,
                                                                           Job& job);
  std::optional<ProtocolError> pixelLimit(const ViewConfig& view) const;
  // Whether this GL can allocate the target `view` needs for `image` (a size within the
  // configured pixel limit may still be more than the platform holds); asked before any work.
  std::optional<ProtocolError> platformLimit(const ViewConfig& view,
                                             const ImageRequest& image) const;
  // Snapshots: the World's file and the daemon's state beside it (snapshots.cpp).
  nlohmann::json daemonState() const;
  std::string writeSnapshot(const std::string& path);
  std::string restoreSnapshot(const std::string& path);
  std::optional<ProtocolError> checkAdvance(double dt_s) const;
  void advance(double dt_s);  // one tick
  // Renders a view (float for EXR, else 8-bit) and records its time.
  // `continuous`: a frame of a subscription's stream, which may reuse the view's last frame.
  void renderFrame(const ViewConfig& view, const ImageRequest& image, struct RenderedView& out,
                   bool continuous = false);
  void noteRender(double ms);  // a view's render time, for stats and metrics
  void realtimeTicks();
  enum class Delivery {
    kDue,        // realtime: subscriptions whose period has come round
    kEveryTick,  // lockstep: every subscription, once per tick
    kView,       // the render coil: the subscribers of one view
  };
  void deliverFrames(Delivery which, const std::string& view);
  // The subscriptions `which` makes due now, by view (their next due time moved on).
  std::map<std::string, std::vector<Subscription*>> dueByView(Delivery which,
                                                              const std::string& view);
  // One rendered view to the subscribers of one image request: streams to their encoders,
  // sockets through the image encoder (raw 8-bit at once).
  void sendToSubscribers(const std::shared_ptr<const struct RenderedView>& frame,
                         const ImageRequest& image, const std::vector<Subscription*>& members);
  void renderTrigger();
  bool saveSnapshot(const std::string& path, const char* why);
  void countSubscriptions();  // refreshes subscribers_ from the world thread's list
  Clock::time_point nextWake() const;
  void publish();                    // refreshes stats and the Modbus readings
  void publishReadings();            // the Modbus readings and hello (cheap: after every request)
  nlohmann::json helloJson() const;  // the hello reply (world thread)
  // What the world thread has in hand, for stats (world thread; empty `what` when idle).
  void setInHand(std::string what, std::int64_t client);

  DaemonConfig config_;
  std::unique_ptr<State> state_;
  std::unique_ptr<Encoder> encoder_;
  std::thread thread_;

  mutable std::mutex queue_mutex_;
  std::condition_variable queue_cv_;
  std::deque<Job> queue_;
  std::vector<std::int64_t> gone_clients_;
  bool stopping_ = false;
  bool shutdown_saved_ = true;

  mutable std::mutex published_mutex_;
  HostReadings published_settings_;
  HostStatus published_status_;
  nlohmann::json published_stats_;
  nlohmann::json published_hello_;
  struct InHand {
    std::string what;  // a command's name, "modbus write", "frames" or "ticks"; empty when idle
    std::int64_t client = 0;
    Clock::time_point since;
  } in_hand_;
  std::atomic<bool> trigger_pending_{false};
  // Raised by stop(): the render in hand ends at its next batch boundary (RenderCancelled).
  std::atomic<bool> cancel_renders_{false};
  std::atomic<bool> lockstep_{false};
  std::mutex frame_listener_mutex_;
  std::function<void()> frame_listener_;
  // Steady clock, at the top of each loop and wherever a render could be cancelled.
  void beatHeart() { heartbeat_ns_ = Clock::now().time_since_epoch().count(); }
  std::atomic<std::int64_t> heartbeat_ns_{0};
  std::atomic<std::uint64_t> errors_{0};
  std::atomic<std::uint64_t> answered_at_once_{0};  // requests the control plane answered
  std::atomic<int> last_error_{0};
  std::atomic<double> last_encode_ms_{0.0};  // the encoder thread's last image
  mutable std::mutex cigi_mutex_;
  std::map<std::string, std::uint64_t> cigi_counts_;
  mutable std::mutex subscribers_mutex_;
  std::map<std::int64_t, int> subscribers_;  // client: subscriptions, for subscriptionsOf
};

}  // namespace nephele
