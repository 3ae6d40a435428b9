#pragma once
// The requests waiting for the world thread: a bounded queue that the transports fill from
// their threads and the world thread empties in one go, with the clients gone since it last
// looked. Full or stopping, it refuses work, and the transport answers `busy`
// (docs/RELIABILITY.md).
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <vector>

#include "protocol/messages.h"
#include "server/reply.h"
#include "server/telemetry.h"

namespace nephele {

// One queued piece of work: a request of a socket or CIGI client, or a Modbus write.
struct Job {
  std::chrono::steady_clock::time_point queued = std::chrono::steady_clock::now();
  enum class Kind { kRequest, kBatch } kind = Kind::kRequest;
  Request request;
  std::int64_t client = 0;
  PushSink push;
  ReplySink reply;
  std::vector<Command> batch;
  bool render = false;  // a batch with the render coil
  std::shared_ptr<BatchTicket> ticket;
  DoneSink done;
  std::shared_ptr<RequestTrace> trace;  // a socket request's stage times, or null
};

class RequestQueue {
 public:
  explicit RequestQueue(std::size_t limit) : limit_(limit) {}

  // False, and nothing queued, when the queue is full or stopping.
  bool push(Job job);
  // A socket client has gone: the world thread hears it at its next wake.
  void clientGone(std::int64_t client);
  // Refuses work from now on and wakes the world thread; true when it was stopping already.
  bool stop();
  bool stopping() const;
  std::size_t depth() const;

  // What the world thread takes at once: every queued job, the clients gone, and whether the
  // daemon is stopping.
  struct Taken {
    std::deque<Job> jobs;
    std::vector<std::int64_t> gone;
    bool stopping = false;
  };
  // Waits until there is something to take or `until` has come (world thread).
  Taken wait(std::chrono::steady_clock::time_point until);

 private:
  const std::size_t limit_;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Job> jobs_;
  std::vector<std::int64_t> gone_;
  bool stopping_ = false;
};

}  // namespace nephele
