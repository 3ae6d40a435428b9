#pragma once
// What the world thread hands back to a transport: replies and pushed images as shared bytes,
// and the sinks that carry them to the client's thread.
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "protocol/messages.h"

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

}  // namespace nephele
