#pragma once
// Keeps floods of connections, datagrams and bad requests from filling the disk with log
// lines. A listener asks before it writes a line about an event a peer can repeat without
// bound (a connection, a refusal, a malformed frame); each kind of event is logged in full
// while it is rare and summarised with its count while it floods. Only the log is limited:
// stats and metrics count every event, exactly, where they counted it before.
//
// The rule, for each kind on its own: time is cut into windows of `interval`, the first
// starting with the kind's first event. In a window the first `burst` lines are written and
// the rest held back and counted; a window that held any back ends with one line
//   event=log_suppressed kind=<kind> count=<lines held back> seconds=<window length>
// and the window after it writes no lines of its own, only its summary, until a window
// passes without the event. A flood that never stops writes `burst` lines, then one line
// per interval, whatever its rate.
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace nephele {

class LogLimiter {
 public:
  using Clock = std::chrono::steady_clock;
  struct Rule {
    int burst = 10;  // lines of a kind written in a window that follows a quiet one
    Clock::duration interval = std::chrono::seconds(10);  // a window: at most one summary
  };
  struct Summary {
    std::string kind;
    std::uint64_t count = 0;  // lines held back
    double seconds = 0.0;     // over how long
  };
  using SummaryWriter = std::function<void(const Summary&)>;

  LogLimiter();  // the default rule; summaries go to the daemon's log, as warnings
  LogLimiter(Rule rule, SummaryWriter write);

  // Whether to write this event's line; if not, it is counted for the kind's summary. Writes
  // the summary of the kind's last window first if that has ended. `kind` is a name fixed in
  // the code (an event, or event/reason), never text from a peer: every kind is remembered
  // for the life of the limiter. Safe to call from any thread.
  bool admit(std::string_view kind, Clock::time_point now = Clock::now());
  // Writes the summary of every window that has ended, so that a flood that stops is
  // summarised without waiting for the next event of its kind. Call it now and then.
  void flush(Clock::time_point now = Clock::now());
  // Writes the summary of everything held back so far, windows ended or not (at shutdown).
  void flushAll(Clock::time_point now = Clock::now());

  static void writeToLog(const Summary& summary);

 private:
  struct Window {
    Clock::time_point start;
    int written = 0;
    std::uint64_t held_back = 0;
    bool flooding = false;  // the window before held lines back: this one writes none
  };
  // Ends `window` if its interval is over, adding its summary (if any) to `summaries`.
  void endIfOver(const std::string& kind, Window& window, Clock::time_point now,
                 std::vector<Summary>& summaries) const;
  void write(const std::vector<Summary>& summaries) const;

  const Rule rule_;
  const SummaryWriter write_;
  std::mutex mutex_;
  std::map<std::string, Window, std::less<>> windows_;  // by kind
};

// The limiter that every listener of the daemon (socket, metrics, Modbus, CIGI) writes its
// per-event lines through: one log, one rule, one place that summarises it.
LogLimiter& listenerLog();

}  // namespace nephele
