#include "renderer/gl/gpu_pass_timer.h"

namespace nephele {

GpuPassTimer::GpuPassTimer(const GlApi& gl, bool software) : gl_(gl), software_(software) {}

void GpuPassTimer::beginFrame() {
  spans_.clear();
  waited_ = {};
  open_ = -1;
}

int GpuPassTimer::enter(int pass) {
  const int before = open_;
  if (pass == open_) return before;
  if (open_ >= 0) {
    if (software_) {
      StageClock clock(waited_.gpu_ms[std::size_t(open_)]);
      gl_.Finish();
    } else {
      gl_.EndQuery(GL_TIME_ELAPSED);
    }
  }
  open_ = pass;
  if (pass < 0 || software_) return before;
  if (spans_.size() == queries_.size()) {
    GLuint name = 0;
    gl_.CreateQueries(GL_TIME_ELAPSED, 1, &name);
    queries_.emplace_back(gl_, GlObject::Kind::kQuery, name);
  }
  spans_.push_back({spans_.size(), pass});
  gl_.BeginQuery(GL_TIME_ELAPSED, queries_[spans_.back().query].get());
  return before;
}

void GpuPassTimer::settle() {
  if (!software_ || open_ < 0) return;
  StageClock clock(waited_.gpu_ms[std::size_t(open_)]);
  gl_.Finish();
}

void GpuPassTimer::collect(FrameTimes& times) {
  enter(-1);
  for (std::size_t i = 0; i < times.gpu_ms.size(); ++i) times.gpu_ms[i] += waited_.gpu_ms[i];
  for (const Span& span : spans_) {
    GLuint64 ns = 0;
    gl_.GetQueryObjectui64v(queries_[span.query].get(), GL_QUERY_RESULT, &ns);
    times.gpu_ms[std::size_t(span.pass)] += double(ns) * 1e-6;
  }
  spans_.clear();
  waited_ = {};
}

}  // namespace nephele
