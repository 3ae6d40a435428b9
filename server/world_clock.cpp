#include "server/world_clock.h"

#include <spdlog/spdlog.h>

namespace nephele {

WorldClock::WorldClock(TickMode mode, double tick_rate_hz, double time_scale)
    : mode_(mode),
      lockstep_(mode == TickMode::kLockstep),
      tick_rate_hz_(tick_rate_hz),
      time_scale_(time_scale) {}

bool WorldClock::setMode(TickMode mode) {
  if (mode == mode_) return false;
  mode_ = mode;
  lockstep_ = mode == TickMode::kLockstep;
  next_tick_ = Clock::now();
  return true;
}

int WorldClock::dueTicks(Clock::time_point now) {
  if (mode_ != TickMode::kRealtime || now < next_tick_) return 0;
  const auto period = secondsToDuration(1.0 / tick_rate_hz_);
  int due = 1 + int((now - next_tick_) / period);
  if (due > kMaxCatchUpTicks) {  // a long stall: drop the backlog rather than race to catch up
    spdlog::warn("event=ticks_skipped count={}", due - kMaxCatchUpTicks);
    due = kMaxCatchUpTicks;
    next_tick_ = now;
  }
  next_tick_ += period * due;
  std::lock_guard lock(listener_mutex_);
  if (listener_) listener_();
  return due;
}

void WorldClock::onFrameStart(std::function<void()> started) {
  std::lock_guard lock(listener_mutex_);
  listener_ = std::move(started);
}

double WorldClock::ticksPerSecond(Clock::time_point now) {
  if (history_.empty() || now - history_.back().first >= std::chrono::seconds(1)) {
    history_.push_back({now, ticks_});
    if (history_.size() > 6) history_.pop_front();
  }
  if (history_.size() < 2) return 0.0;
  const auto& [t0, n0] = history_.front();
  const double seconds = std::chrono::duration<double>(now - t0).count();
  return seconds > 0.0 ? double(ticks_ - n0) / seconds : 0.0;
}

}  // namespace nephele
