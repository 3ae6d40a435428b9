#include "server/log_limiter.h"

#include <spdlog/spdlog.h>

#include <utility>

namespace nephele {

LogLimiter::LogLimiter() : LogLimiter(Rule{}, writeToLog) {}

LogLimiter::LogLimiter(Rule rule, SummaryWriter write) : rule_(rule), write_(std::move(write)) {}

bool LogLimiter::admit(std::string_view kind, Clock::time_point now) {
  std::vector<Summary> summaries;
  bool admitted = false;
  {
    std::lock_guard lock(mutex_);
    auto it = windows_.find(kind);
    if (it == windows_.end()) it = windows_.emplace(std::string(kind), Window{now}).first;
    Window& window = it->second;
    endIfOver(it->first, window, now, summaries);
    admitted = !window.flooding && window.written < rule_.burst;
    if (admitted)
      ++window.written;
    else
      ++window.held_back;
  }
  write(summaries);  // outside the lock: the log's own sinks may be slow
  return admitted;
}

void LogLimiter::flush(Clock::time_point now) {
  std::vector<Summary> summaries;
  {
    std::lock_guard lock(mutex_);
    for (auto& [kind, window] : windows_) endIfOver(kind, window, now, summaries);
  }
  write(summaries);
}

void LogLimiter::flushAll(Clock::time_point now) {
  std::vector<Summary> summaries;
  {
    std::lock_guard lock(mutex_);
    for (auto& [kind, window] : windows_) {
      endIfOver(kind, window, now, summaries);
      if (window.held_back == 0) continue;
      summaries.push_back(
          {kind, window.held_back, std::chrono::duration<double>(now - window.start).count()});
      window = Window{now, 0, 0, true};
    }
  }
  write(summaries);
}

void LogLimiter::endIfOver(const std::string& kind, Window& window, Clock::time_point now,
                           std::vector<Summary>& summaries) const {
  if (now - window.start < rule_.interval) return;
  if (window.held_back == 0) {
    // Quiet, or no more than its burst: the burst is there again for the next event.
    window = Window{now};
    return;
  }
  summaries.push_back(
      {kind, window.held_back, std::chrono::duration<double>(rule_.interval).count()});
  // The flood may go on: the next window follows directly and writes only its summary. If
  // that one has ended too, it passed without the event (an event would have ended this one).
  const Clock::time_point next = window.start + rule_.interval;
  window = now - next < rule_.interval ? Window{next, 0, 0, true} : Window{now};
}

void LogLimiter::write(const std::vector<Summary>& summaries) const {
  for (const Summary& s : summaries) write_(s);
}

void LogLimiter::writeToLog(const Summary& summary) {
  spdlog::warn("event=log_suppressed kind={} count={} seconds={:.1f}", summary.kind, summary.count,
               summary.seconds);
}

LogLimiter& listenerLog() {
  static LogLimiter limiter;
  return limiter;
}

}  // namespace nephele
