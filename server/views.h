#pragma once
// The views the daemon renders (its config's, as the host has moved them since) and the
// subscriptions to them: a client's frames of one view at a rate, or a view streamed as video.
// World thread, except `subscriptionsOf` (any thread).
#include <atomic>
#include <chrono>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "protocol/messages.h"
#include "server/daemon_config.h"
#include "server/reply.h"

namespace nephele {

class VideoStream;

struct Subscription {
  std::int64_t id = 0;
  std::int64_t client = 0;  // 0: the daemon's own (a stream outlives the client that started it)
  std::string view;
  ImageRequest image;
  std::chrono::steady_clock::duration period{};
  std::chrono::steady_clock::time_point next_due;
  std::uint64_t last_tick = UINT64_MAX;  // the tick of the last frame sent
  PushSink sink;
  std::shared_ptr<std::atomic<bool>> gone;  // set when the sink reports its client gone
  // A streamed view (stream): its frames go to the encoder in place of `sink`; its address.
  std::shared_ptr<VideoStream> video;
  std::string address;
};

// Which subscriptions a round of delivery serves.
enum class Delivery {
  kDue,        // realtime: subscriptions whose period has come round
  kEveryTick,  // lockstep: every subscription, once per tick
  kView,       // the render coil: the subscribers of one view
};

class Views {
 public:
  using Clock = std::chrono::steady_clock;
  explicit Views(std::vector<ViewConfig> views) : views_(std::move(views)) {}

  const std::vector<ViewConfig>& all() const { return views_; }
  ViewConfig* find(const std::string& name);
  const ViewConfig* find(const std::string& name) const;
  // The error for a name that is not a view, listing those that are.
  ProtocolError unknown(const std::string& name) const;
  // Every view's camera moved by -shift (the world recentred under them).
  void shiftAll(const glm::dvec3& shift);

  const std::vector<Subscription>& subscriptions() const { return subscriptions_; }
  // Adds `sub` under a new id, which it returns.
  std::int64_t subscribe(Subscription sub);
  // False when `client` holds no subscription `id`.
  bool unsubscribe(std::int64_t id, std::int64_t client);
  // The streamed view `id`, or null.
  const Subscription* stream(std::int64_t id) const;
  void endStream(std::int64_t id);
  int streams() const;
  nlohmann::json streamsJson() const;  // the streamed views and their counts (stats)
  // Ends the subscriptions of clients gone, and of sinks that reported their client gone.
  void dropClients(const std::vector<std::int64_t>& gone);
  void dropGone();
  void clear();

  // Realtime periods start from `now` (a change of the clock's mode).
  void restartPeriods(Clock::time_point now);
  // The earliest of `wake` and every subscription's next due time.
  Clock::time_point nextDue(Clock::time_point wake) const;
  // The subscriptions `which` makes due at `now` and `tick`, by view, the most overdue view
  // first; nothing changes until take().
  std::vector<std::pair<std::string, std::vector<Subscription*>>> due(Delivery which,
                                                                      const std::string& view,
                                                                      std::uint64_t tick,
                                                                      Clock::time_point now);
  // Serves one view's due subscriptions: their next due time moves on, and those to render are
  // returned; a stream whose encoder is still busy drops the frame here, before it is rendered.
  std::vector<Subscription*> take(const std::vector<Subscription*>& due, Delivery which,
                                  std::uint64_t tick, Clock::time_point now);

  // How many subscriptions a socket client holds (any thread).
  int subscriptionsOf(std::int64_t client) const;

 private:
  void recount();  // refreshes counts_ from subscriptions_

  std::vector<ViewConfig> views_;
  std::vector<Subscription> subscriptions_;
  std::int64_t next_id_ = 1;
  mutable std::mutex counts_mutex_;
  std::map<std::int64_t, int> counts_;  // client: subscriptions, for subscriptionsOf
};

}  // namespace nephele
