#pragma once
// Timing of frames for benchmarks (never for tests): the median of repeated runs after one
// warm-up run (shader compiles, texture bakes), so one slow frame on a shared machine does
// not move the figure.
#include <algorithm>
#include <chrono>
#include <vector>

namespace nephele {

template <typename Frame>
double medianMilliseconds(int repeats, Frame&& frame) {
  frame();
  std::vector<double> ms;
  for (int i = 0; i < std::max(repeats, 1); ++i) {
    const auto start = std::chrono::steady_clock::now();
    frame();
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
                     .count());
  }
  std::sort(ms.begin(), ms.end());
  return ms[ms.size() / 2];
}

// Milliseconds from a to b.
inline double millisecondsBetween(std::chrono::steady_clock::time_point a,
                                  std::chrono::steady_clock::time_point b) {
  return std::chrono::duration<double, std::milli>(b - a).count();
}

// The p-quantile (0 to 1) of `values` by rank, 0 for none: what the benches print and the
// daemon's stats report.
inline double percentile(std::vector<double> values, double p) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  return values[std::min(values.size() - 1, std::size_t(p * double(values.size())))];
}

}  // namespace nephele
