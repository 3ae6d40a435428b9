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

}  // namespace nephele
