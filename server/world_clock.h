#pragma once
// The world's clock (PROTOCOL.md, "Time"): in realtime mode the daemon ticks itself at the tick
// rate, each tick advancing the world by time_scale / tick_rate seconds (none while paused); in
// lockstep mode the host's `tick` requests advance it. It counts ticks, schedules the realtime
// ones, tells the CIGI listener when each realtime frame starts, and measures ticks per second.
// World thread, except `lockstep` and `onFrameStart` (any thread).
#include <atomic>
#include <chrono>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <utility>

#include "server/daemon_config.h"

namespace nephele {

// A configured number of seconds as a steady-clock duration.
inline std::chrono::steady_clock::duration secondsToDuration(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(s));
}

inline const char* modeName(TickMode mode) {
  return mode == TickMode::kRealtime ? "realtime" : "lockstep";
}

class WorldClock {
 public:
  using Clock = std::chrono::steady_clock;
  // After a stall, the most realtime ticks made up in one go; the rest are dropped.
  static constexpr int kMaxCatchUpTicks = 100;

  WorldClock(TickMode mode, double tick_rate_hz, double time_scale);

  TickMode mode() const { return mode_; }
  bool lockstep() const { return lockstep_.load(); }  // any thread
  // False when `mode` is the mode already; else the realtime schedule starts from now.
  bool setMode(TickMode mode);
  double timeScale() const { return time_scale_; }
  void setTimeScale(double scale) { time_scale_ = scale; }
  bool paused() const { return paused_; }
  void setPaused(bool paused) { paused_ = paused; }
  double tickRate() const { return tick_rate_hz_; }

  std::uint64_t ticks() const { return ticks_; }
  void countTicks(std::uint64_t n) { ticks_ += n; }
  void restoreTicks(std::uint64_t ticks) { ticks_ = ticks; }

  // Realtime: starts the schedule at `now` (the world thread's start).
  void start(Clock::time_point now) { next_tick_ = now; }
  // Realtime: how many ticks are due at `now` (0 in lockstep or before the next one), with the
  // schedule moved past them; a frame with ticks due is a frame start for the listener.
  int dueTicks(Clock::time_point now);
  Clock::time_point nextTick() const { return next_tick_; }
  // The world seconds `ticks` realtime ticks advance by.
  double secondsFor(int ticks) const { return ticks * time_scale_ / tick_rate_hz_; }

  // Called on the world thread at the start of each realtime frame (any thread sets it).
  void onFrameStart(std::function<void()> started);
  // Ticks per second over the last five seconds, sampled once a second (world thread).
  double ticksPerSecond(Clock::time_point now);

 private:
  TickMode mode_;
  std::atomic<bool> lockstep_;
  const double tick_rate_hz_;
  double time_scale_;
  bool paused_ = false;
  std::uint64_t ticks_ = 0;
  Clock::time_point next_tick_ = Clock::now();
  std::deque<std::pair<Clock::time_point, std::uint64_t>> history_;  // one per second
  std::mutex listener_mutex_;
  std::function<void()> listener_;
};

}  // namespace nephele
