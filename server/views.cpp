#include "server/views.h"

#include <algorithm>

#include "image/video_stream.h"

namespace nephele {

ViewConfig* Views::find(const std::string& name) {
  for (ViewConfig& v : views_)
    if (v.name == name) return &v;
  return nullptr;
}

const ViewConfig* Views::find(const std::string& name) const {
  return const_cast<Views*>(this)->find(name);
}

ProtocolError Views::unknown(const std::string& name) const {
  std::string names;
  for (const ViewConfig& v : views_) names += (names.empty() ? "" : ", ") + v.name;
  return {ErrorCode::kNotFound, "view: \"" + name + "\" is not a view (allowed: " + names + ")"};
}

void Views::shiftAll(const glm::dvec3& shift) {
  for (ViewConfig& v : views_) v.camera.position -= shift;
}

std::int64_t Views::subscribe(Subscription sub) {
  sub.id = next_id_++;
  subscriptions_.push_back(std::move(sub));
  recount();
  return subscriptions_.back().id;
}

bool Views::unsubscribe(std::int64_t id, std::int64_t client) {
  const std::size_t removed = std::erase_if(subscriptions_, [&](const Subscription& sub) {
    return sub.id == id && sub.client == client;
  });
  recount();
  return removed > 0;
}

const Subscription* Views::stream(std::int64_t id) const {
  for (const Subscription& sub : subscriptions_)
    if (sub.video && sub.id == id) return &sub;
  return nullptr;
}

void Views::endStream(std::int64_t id) {
  std::erase_if(subscriptions_, [&](const Subscription& sub) { return sub.video && sub.id == id; });
  recount();
}

int Views::streams() const {
  return int(std::count_if(subscriptions_.begin(), subscriptions_.end(),
                           [](const Subscription& sub) { return sub.video != nullptr; }));
}

nlohmann::json Views::streamsJson() const {
  nlohmann::json out = nlohmann::json::array();
  for (const Subscription& sub : subscriptions_) {
    if (!sub.video) continue;
    const VideoStreamStats counts = sub.video->stats();
    out.push_back({{"stream", sub.id},
                   {"view", sub.view},
                   {"address", sub.address},
                   {"encoder", sub.video->encoderName()},
                   {"sent", counts.sent},
                   {"dropped", counts.dropped},
                   {"bytes", counts.bytes},
                   {"encode_ms", counts.encode_ms},
                   {"encode_cpu_ms", counts.encode_cpu_ms}});
  }
  return out;
}

void Views::dropClients(const std::vector<std::int64_t>& gone) {
  if (gone.empty()) return;
  std::erase_if(subscriptions_, [&](const Subscription& sub) {
    return std::find(gone.begin(), gone.end(), sub.client) != gone.end();
  });
  recount();
}

void Views::dropGone() {
  if (std::erase_if(subscriptions_, [](const Subscription& sub) { return sub.gone->load(); }))
    recount();
}

void Views::clear() {
  subscriptions_.clear();
  recount();
}

void Views::restartPeriods(Clock::time_point now) {
  for (Subscription& sub : subscriptions_) sub.next_due = now;
}

Views::Clock::time_point Views::nextDue(Clock::time_point wake) const {
  for (const Subscription& sub : subscriptions_) wake = std::min(wake, sub.next_due);
  return wake;
}

std::vector<std::pair<std::string, std::vector<Subscription*>>> Views::due(Delivery which,
                                                                           const std::string& view,
                                                                           std::uint64_t tick,
                                                                           Clock::time_point now) {
  std::map<std::string, std::vector<Subscription*>> by_view;
  std::map<std::string, Clock::time_point> since;  // the view's most overdue subscription
  for (Subscription& sub : subscriptions_) {
    const bool due = which == Delivery::kDue         ? now >= sub.next_due
                     : which == Delivery::kEveryTick ? sub.last_tick != tick
                                                     : sub.view == view;
    if (!due) continue;
    by_view[sub.view].push_back(&sub);
    auto [at, added] = since.try_emplace(sub.view, sub.next_due);
    if (!added) at->second = std::min(at->second, sub.next_due);
  }
  std::vector<std::pair<std::string, std::vector<Subscription*>>> out(by_view.begin(),
                                                                      by_view.end());
  std::stable_sort(out.begin(), out.end(),
                   [&](const auto& a, const auto& b) { return since[a.first] < since[b.first]; });
  return out;
}

std::vector<Subscription*> Views::take(const std::vector<Subscription*>& due, Delivery which,
                                       std::uint64_t tick, Clock::time_point now) {
  std::vector<Subscription*> out;
  for (Subscription* sub : due) {
    if (which == Delivery::kDue) {
      sub->next_due += sub->period;
      if (sub->next_due < now)
        sub->next_due = now + sub->period;  // a slow render: skip, never burst
    }
    sub->last_tick = tick;
    if (sub->video && sub->video->full()) {
      sub->video->countDropped();
      continue;
    }
    out.push_back(sub);
  }
  return out;
}

int Views::subscriptionsOf(std::int64_t client) const {
  std::lock_guard lock(counts_mutex_);
  const auto it = counts_.find(client);
  return it == counts_.end() ? 0 : it->second;
}

void Views::recount() {
  std::map<std::int64_t, int> counts;
  for (const Subscription& sub : subscriptions_) ++counts[sub.client];
  std::lock_guard lock(counts_mutex_);
  counts_ = std::move(counts);
}

}  // namespace nephele
