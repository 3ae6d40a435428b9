#include "server/log_limiter.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>
#include <vector>

namespace nephele {
namespace {

using namespace std::chrono_literals;
using Clock = LogLimiter::Clock;

// A limiter with a burst of 3 lines and 10 s windows, on a clock the test moves, whose
// summaries are kept for the test to read.
struct Limited {
  Limited() : limiter({3, 10s}, [this](const LogLimiter::Summary& s) { summaries.push_back(s); }) {}
  // How many of `n` events of `kind` at `at` are written.
  int admitted(std::string_view kind, int n, Clock::time_point at) {
    int written = 0;
    for (int i = 0; i < n; ++i) written += limiter.admit(kind, at);
    return written;
  }
  std::vector<LogLimiter::Summary> summaries;
  LogLimiter limiter;
  const Clock::time_point t0 = Clock::now();
};

TEST(LogLimiter, WritesEveryLineOfARareEvent) {
  Limited l;
  for (int i = 0; i < 20; ++i) EXPECT_EQ(l.admitted("rare", 1, l.t0 + i * 4s), 1) << i;
  l.limiter.flushAll(l.t0 + 100s);
  EXPECT_TRUE(l.summaries.empty());
}

TEST(LogLimiter, AFloodWritesItsBurstThenOneSummaryPerWindowWithTheExactCount) {
  Limited l;
  EXPECT_EQ(l.admitted("flood", 1000, l.t0), 3);
  EXPECT_EQ(l.admitted("flood", 500, l.t0 + 9s), 0);
  EXPECT_TRUE(l.summaries.empty());
  // The window ends: one summary, and the next window writes no line of its own.
  l.limiter.flush(l.t0 + 10s);
  ASSERT_EQ(l.summaries.size(), 1u);
  EXPECT_EQ(l.summaries[0].kind, "flood");
  EXPECT_EQ(l.summaries[0].count, 1497u);
  EXPECT_DOUBLE_EQ(l.summaries[0].seconds, 10.0);
  EXPECT_EQ(l.admitted("flood", 200, l.t0 + 15s), 0);
  // The next event after that window summarises it first.
  EXPECT_EQ(l.admitted("flood", 1, l.t0 + 21s), 0);
  ASSERT_EQ(l.summaries.size(), 2u);
  EXPECT_EQ(l.summaries[1].count, 200u);
}

TEST(LogLimiter, AWindowWithoutTheEventGivesTheBurstBack) {
  Limited l;
  EXPECT_EQ(l.admitted("flood", 10, l.t0), 3);
  l.limiter.flush(l.t0 + 10s);  // summary of 7; the next window would write nothing
  l.limiter.flush(l.t0 + 20s);  // it passed without the event
  EXPECT_EQ(l.admitted("flood", 10, l.t0 + 25s), 3);
  ASSERT_EQ(l.summaries.size(), 1u);
  // Without a flush in between, the same: a quiet window is noticed by the next event.
  Limited m;
  EXPECT_EQ(m.admitted("flood", 10, m.t0), 3);
  EXPECT_EQ(m.admitted("flood", 10, m.t0 + 35s), 3);
  ASSERT_EQ(m.summaries.size(), 1u);
  EXPECT_EQ(m.summaries[0].count, 7u);
}

TEST(LogLimiter, KindsAreLimitedApart) {
  Limited l;
  EXPECT_EQ(l.admitted("refused", 100, l.t0), 3);
  EXPECT_EQ(l.admitted("closed/eof", 2, l.t0), 2);
  EXPECT_EQ(l.admitted("closed/evicted_idle", 1, l.t0), 1);
}

TEST(LogLimiter, FlushAllSummarisesWhatIsHeldBackAtOnce) {
  Limited l;
  EXPECT_EQ(l.admitted("flood", 50, l.t0), 3);
  EXPECT_EQ(l.admitted("quiet", 2, l.t0), 2);
  l.limiter.flushAll(l.t0 + 2s);
  ASSERT_EQ(l.summaries.size(), 1u);
  EXPECT_EQ(l.summaries[0].count, 47u);
  EXPECT_DOUBLE_EQ(l.summaries[0].seconds, 2.0);
  l.limiter.flushAll(l.t0 + 3s);
  EXPECT_EQ(l.summaries.size(), 1u);  // nothing counted twice
}

TEST(LogLimiter, CountsEveryEventFromManyThreads) {
  Limited l;
  std::atomic<int> written{0};
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t)
    threads.emplace_back([&] { written += l.admitted("flood", 10000, l.t0); });
  for (std::thread& t : threads) t.join();
  l.limiter.flushAll(l.t0 + 1s);
  EXPECT_EQ(written, 3);
  ASSERT_EQ(l.summaries.size(), 1u);
  EXPECT_EQ(l.summaries[0].count, 80000u - 3u);
}

}  // namespace
}  // namespace nephele
