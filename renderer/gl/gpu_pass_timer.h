#pragma once
// The GPU's time per kind of pass (FrameTimes::gpu_ms). On a GPU, from GL_TIME_ELAPSED queries:
// one is open at a time, and entering another kind of pass ends it and begins the next. On a
// software GL (llvmpipe), whose "GPU" is threads of this machine, from the wall clock: the
// passes of a kind are finished (glFinish) before the next kind is queued, and the wait is
// theirs. llvmpipe answers timer queries too, but rasterises a whole queue one screen tile at
// a time through every pass and gives a query the span from the first tile its threads began
// to the last they ended, so passes queued together would each be charged the whole queue.
#include <chrono>
#include <vector>

#include "renderer/frame_stats.h"
#include "renderer/gl/gl_objects.h"

namespace nephele {

class GpuPassTimer {
 public:
  GpuPassTimer(const GlApi& gl, bool software);

  void beginFrame();
  // The passes queued from now on are of kind `pass` (-1: not timed); returns the kind before,
  // for the caller to restore.
  int enter(int pass);
  // Software: waits here for the passes queued so far and charges the wait to the open kind.
  // For a pass whose result the next one samples, which llvmpipe would otherwise wait for
  // inside the CPU's submission. On a GPU nothing.
  void settle();
  // Software: the time spent so far this frame waiting for passes, which is the GPU's, not
  // the submission's.
  double waitedMs() const { return waited_.gpuTotal(); }
  // Once the frame's work has finished: adds every pass's time to `times`.
  void collect(FrameTimes& times);

 private:
  struct Span {
    std::size_t query;
    int pass;
  };
  const GlApi& gl_;
  bool software_;
  std::vector<GlObject> queries_;  // a pool, reused from frame to frame
  std::vector<Span> spans_;        // this frame's, in order
  FrameTimes waited_;              // software: the waits, by kind
  int open_ = -1;
};

// Passes of one kind for the scope's lifetime, the kind before restored after it.
class GpuPassScope {
 public:
  GpuPassScope(GpuPassTimer& timer, GpuPass pass)
      : timer_(timer), before_(timer.enter(int(pass))) {}
  ~GpuPassScope() { timer_.enter(before_); }
  GpuPassScope(const GpuPassScope&) = delete;
  GpuPassScope& operator=(const GpuPassScope&) = delete;

 private:
  GpuPassTimer& timer_;
  int before_;
};

}  // namespace nephele
