#include "renderer/gl/ellipsoid_renderer.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>

#include "renderer/gl/ellipsoid_internal.h"

// The per-pixel pass (MODEL.md section 15): each batch's ellipsoids binned by screen tile, every
// hit of a pixel composited in depth order, at full or reduced rate.
namespace nephele {

using namespace ellipsoid_detail;

namespace {

constexpr std::int64_t kMaxListed = std::int64_t(1) << 24;  // per-pixel bin entries per batch

}  // namespace

std::optional<EllipsoidRenderer::BinLists> EllipsoidRenderer::binLists(
    const std::vector<EllipsoidRecord>& ordered, const PassTarget& target, bool history) const {
  // Screen bins over the batch's rectangle, each listing the ellipsoids whose rectangles
  // overlap it, in the records' order (two passes: count, then fill).
  auto bin = [&](float ndc, int size) {
    return std::clamp(int((double(ndc) + 1.0) * 0.5 * size) / kPerPixelBinSize, 0,
                      (size - 1) / kPerPixelBinSize);
  };
  BinLists out;
  glm::ivec4& area = out.area;
  area = {std::numeric_limits<int>::max(), std::numeric_limits<int>::max(), -1, -1};
  std::vector<glm::ivec4> spans(ordered.size());
  for (std::size_t i = 0; i < ordered.size(); ++i) {
    const glm::vec4 rect = ordered[i].v[10];
    spans[i] = {bin(rect.x, target.width), bin(rect.y, target.height), bin(rect.z, target.width),
                bin(rect.w, target.height)};
    area = {std::min(area.x, spans[i].x), std::min(area.y, spans[i].y),
            std::max(area.z, spans[i].z), std::max(area.w, spans[i].w)};
    out.listed += std::int64_t(spans[i].z - spans[i].x + 1) * (spans[i].w - spans[i].y + 1);
  }
  out.bins_x = area.z - area.x + 1, out.bins_y = area.w - area.y + 1;
  // Bin lists beyond kMaxListed entries (64 MiB) fall back to the centre pass as well.
  const std::int64_t max_listed = std::min<std::int64_t>(max_texels_, kMaxListed);
  if (out.listed > max_listed || std::int64_t(out.bins_x) * out.bins_y > max_listed)
    return std::nullopt;
  // A bin is first item and count.
  out.bins.assign(std::size_t(out.bins_x) * out.bins_y, glm::ivec2(0));
  for (const glm::ivec4& span : spans)
    for (int y = span.y; y <= span.w; ++y)
      for (int x = span.x; x <= span.z; ++x) ++out.at(x, y).y;
  int deepest = 0, first = 0;
  for (glm::ivec2& b : out.bins) {
    deepest = std::max(deepest, b.y);
    b.x = first;
    first += b.y;
    b.y = 0;
  }
  if (deepest <= 1 && !history) {
    out.centre_suffices = true;
    return out;
  }
  out.items.resize(static_cast<std::size_t>(first));
  for (std::size_t i = 0; i < spans.size(); ++i)
    for (int y = spans[i].y; y <= spans[i].w; ++y)
      for (int x = spans[i].x; x <= spans[i].z; ++x) {
        glm::ivec2& b = out.at(x, y);
        out.items[std::size_t(b.x + b.y++)] = GLint(i);
      }
  return out;
}

GLuint EllipsoidRenderer::perPixelProgram(const Batch& b, const BinLists& bins,
                                          EllipsoidProgram which, int rate, bool history_too) {
  EllipsoidPassLayout layout = b.base;
  layout.program = which;
  layout.shading_rate = rate;
  layout.history = history_too;
  const GLuint p = program(layout);
  setCloudUniforms(p, b.scene, b.cloud, b.texture, layout.texture, b.band);
  gl_.ProgramUniform2i(p, gl_.GetUniformLocation(p, "u_bin_origin"), bins.area.x, bins.area.y);
  gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, "u_bins_x"), bins.bins_x);
  gl_.ProgramUniform1i(p, gl_.GetUniformLocation(p, "u_bin_size"), kPerPixelBinSize);
  const double shown = std::max(b.target.seen, 1e-6);
  gl_.ProgramUniform1f(p, gl_.GetUniformLocation(p, "u_opaque"),
                       float(std::max(0.0, 1.0 - (1.0 - kOpaqueCoverage) / shown)));
  return p;
}

void EllipsoidRenderer::drawBinRect(GLuint program, glm::ivec2 size, int step, glm::ivec4 rect,
                                    int extra) {
  auto ndc = [&](int bins, int axis, int more) {
    return float(2.0 * std::min(double(bins * kPerPixelBinSize) / step + more, double(size[axis])) /
                     size[axis] -
                 1.0);
  };
  const float x0 = ndc(rect.x, 0, 0), y0 = ndc(rect.y, 1, 0), x1 = ndc(rect.z + 1, 0, extra),
              y1 = ndc(rect.w + 1, 1, extra);
  const glm::vec2 polygon[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
  gl_.UseProgram(program);
  gl_.ProgramUniform2fv(program, gl_.GetUniformLocation(program, "u_polygon"), 4, &polygon[0].x);
  gl_.DrawArrays(GL_TRIANGLE_FAN, 0, 4);
}

bool EllipsoidRenderer::drawArea(const BinLists& bins,
                                 const std::function<void(glm::ivec4)>& draw) {
  constexpr std::int64_t kBinPixels = std::int64_t(kPerPixelBinSize) * kPerPixelBinSize;
  const glm::ivec4 area = bins.area;
  if (!cancel_ || bins.listed * kBinPixels <= kCancelWork) {
    draw(area);
    queued_work_ += bins.listed * kBinPixels;
    return true;
  }
  // Heavy: bands of whole bin rows of about kCancelWork hit tests (a row heavier than that
  // alone in runs of its bins), each paced (paceQueued) before the flag is read.
  auto finished = [&] {
    paceQueued();
    return stopNow();
  };
  int band_from = area.y;
  std::int64_t band_work = 0;
  for (int y = area.y; y <= area.w; ++y) {
    std::int64_t row_work = 0;
    for (int x = area.x; x <= area.z; ++x) row_work += bins.at(x, y).y * kBinPixels;
    if (band_work > 0 && band_work + row_work > kCancelWork) {
      draw({area.x, band_from, area.z, y - 1});
      if (finished()) return false;
      band_from = y, band_work = 0;
    }
    if (row_work <= kCancelWork) {
      band_work += row_work;
      continue;
    }
    int run_from = area.x;
    std::int64_t run_work = 0;
    for (int x = area.x; x <= area.z; ++x) {
      const std::int64_t work = bins.at(x, y).y * kBinPixels;
      if (run_work > 0 && run_work + work > kCancelWork) {
        draw({run_from, y, x - 1, y});
        if (finished()) return false;
        run_from = x, run_work = 0;
      }
      run_work += work;
    }
    draw({run_from, y, area.z, y});
    if (finished()) return false;
    band_from = y + 1;
  }
  if (band_from <= area.w) draw({area.x, band_from, area.z, area.w});
  return true;
}

void EllipsoidRenderer::drawPerPixel(const Batch& b, const std::vector<EllipsoidRecord>& ordered,
                                     const BinLists& bins) {
  // Behind a thick veil the walk may err by what the veil hides (MODEL.md section 15, "behind
  // the veil"): it ends at a lower coverage, and where the error allowed is large enough it
  // runs first at one pixel in rate^2 into the samples texture, then over every pixel, which
  // blends its samples where they agree.
  // Elsewhere it runs so at the heaps' own shading rate when one is asked (RenderSettings::
  // heap_shading_rate), and the samples are blended everywhere (MODEL.md section 15, "reduced
  // rate").
  const double tolerance = kVeiledTolerance / std::max(b.target.seen, 1e-6);
  const bool veiled = tolerance >= kVeiledSamplingFrom;
  const bool reduced = !veiled && b.settings.heap_shading_rate > 1;
  // A continuous view walks one pixel in heap_refresh each frame, at a sample offset that goes
  // round them all, and reuses its last frame for the others; the first frame after a cut is
  // the exact one (MODEL.md section 15, "reuse across frames"; beginBand). Behind a veil too:
  // there the reuse takes the place of the veiled sampling, with the veil's lower opacity cut.
  const bool reuse = b.history && band_.reuse;
  const int rate = b.targets_drawn ? 1
                   : reuse         ? band_.rate
                   : b.history     ? 1
                   : veiled        ? kVeiledShadingRate
                   : reduced       ? b.settings.heap_shading_rate
                                   : 1;
  bindFrameTexture(kRecordTextureUnit, GL_RGBA32F, ordered.data(),
                   ordered.size() * sizeof(EllipsoidRecord));
  bindFrameTexture(kBinTextureUnit, GL_RG32I, bins.bins.data(),
                   bins.bins.size() * sizeof(glm::ivec2));
  bindFrameTexture(kBinItemTextureUnit, GL_R32I, bins.items.data(),
                   bins.items.size() * sizeof(GLint));
  ++stats_->ellipsoid_passes;
  if (rate != 1) return drawSampled(b, bins, rate, reduced, tolerance);
  const GLuint p = perPixelProgram(b, bins, EllipsoidProgram::kFusedPerPixel, 1, b.history);
  const glm::ivec2 frame_size(b.target.width, b.target.height);
  auto draw = [&] {
    return drawArea(bins, [&](glm::ivec4 rect) { drawBinRect(p, frame_size, 1, rect); });
  };
  if (!b.history)
    draw();
  else if (!drawWithHistory(b.target, true, draw))
    band_.cancelled = true;
}

void EllipsoidRenderer::drawSampled(const Batch& b, const BinLists& bins, int rate, bool reduced,
                                    double tolerance) {
  // Sample c stands at pixel c * rate; one more than the frame needs on each axis, so that
  // every pixel has samples on both sides. Those outside the area stay 0: nothing of the batch
  // is there. A continuous view's grid is its band's (beginBand), which every batch of the band
  // samples over the others.
  const bool reuse = b.history && band_.reuse;
  const glm::ivec2 frame_size(b.target.width, b.target.height);
  const glm::ivec2 origin = reuse ? band_.origin : glm::ivec2(0);
  const glm::ivec2 size = reuse ? band_.size : (frame_size - 1) / rate + 2;
  if (!reuse) {  // only the colours are read: the distances are a continuous view's
    prepareSamples(size);
    const GLfloat nothing[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    gl_.ClearNamedFramebufferfv(samples_framebuffer_.get(), GL_COLOR, 0, nothing);
  }
  const GLuint s = perPixelProgram(b, bins, EllipsoidProgram::kFusedSamples, rate);
  gl_.ProgramUniform2i(s, gl_.GetUniformLocation(s, "u_sample_origin"), origin.x, origin.y);
  gl_.ProgramUniform1i(s, gl_.GetUniformLocation(s, "u_bins_y"), bins.bins_y);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, samples_framebuffer_.get());
  gl_.Viewport(0, 0, size.x, size.y);
  if (reuse) {
    // Over the samples of the band's batches drawn before (farther): "over" in colour, the
    // nearest of the distances.
    gl_.Enable(GL_BLEND);
    gl_.BlendEquationi(1, GL_MIN);
  } else {
    gl_.Disable(GL_BLEND);
  }
  const bool done =
      drawArea(bins, [&](glm::ivec4 rect) { drawBinRect(s, size, rate, rect, reuse ? 2 : 0); });
  gl_.BlendEquationi(1, GL_FUNC_ADD);
  gl_.Enable(GL_BLEND);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, b.target.framebuffer);
  gl_.Viewport(0, 0, b.target.width, b.target.height);
  if (reuse) {
    if (!done) band_.cancelled = true;
    const glm::ivec4 area = bins.area;
    for (int y = area.y; y <= area.w; ++y)
      for (int x = area.x; x <= area.z; ++x)
        if (bins.at(x, y).y > 0) band_.bins[std::size_t(y) * band_.bins_x + x] = 1;
    ++stats_->sampled_passes;
    return;
  }
  if (!done) return;
  timer_->settle();  // the samples are read next
  resolveSamples(b, bins, rate, size, reduced, tolerance);
}

void EllipsoidRenderer::resolveSamples(const Batch& b, const BinLists& bins, int rate,
                                       glm::ivec2 size, bool reduced, double tolerance) {
  const glm::ivec4 area = bins.area;
  const glm::ivec2 from = glm::ivec2(area.x, area.y) * kPerPixelBinSize / rate;
  const glm::ivec2 end = (glm::ivec2(area.z, area.w) + 1) * kPerPixelBinSize / rate;  // samples
  gl_.BindTextureUnit(kSamplesTextureUnit, samples_.get());
  if (reduced) {
    // The samples are brought to full size by their bilinear blend over the whole area, with
    // no readback (MODEL.md section 15, "reduced rate").
    drawRuns(b, bins, EllipsoidProgram::kFusedBlend, rate, {glm::ivec4(from * rate, end * rate)});
    ++stats_->sampled_passes;
    return;
  }
  // The blocks of rate x rate pixels over the area: blended where their four corner samples
  // agree to within the tolerance, walked elsewhere, as runs along each row of blocks. A
  // block whose far samples were not drawn (past the area) is walked.
  std::vector<float> values(std::size_t(size.x) * size.y * 4);
  gl_.GetTextureImage(samples_.get(), 0, GL_RGBA, GL_FLOAT, GLsizei(values.size() * sizeof(float)),
                      values.data());
  auto sample = [&](int x, int y) { return &values[(std::size_t(y) * size.x + x) * 4]; };
  auto blends = [&](int x, int y) {
    if (x + 1 >= end.x || y + 1 >= end.y) return false;
    const float *a = sample(x, y), *b = sample(x + 1, y), *c = sample(x, y + 1),
                *d = sample(x + 1, y + 1);
    for (int k = 0; k < 4; ++k) {
      const float lo = std::min({a[k], b[k], c[k], d[k]}), hi = std::max({a[k], b[k], c[k], d[k]});
      if (hi - lo > tolerance) return false;
    }
    return true;
  };
  std::vector<glm::ivec4> blended, walked;  // pixel rectangles
  for (int y = from.y; y < end.y; ++y)
    for (int x = from.x; x < end.x;) {
      const bool blend = blends(x, y);
      int to = x + 1;
      while (to < end.x && blends(to, y) == blend) ++to;
      (blend ? blended : walked).push_back(glm::ivec4(x, y, to, y + 1) * rate);
      x = to;
    }
  if (!blended.empty()) drawRuns(b, bins, EllipsoidProgram::kFusedBlend, rate, blended);
  if (!walked.empty()) drawRuns(b, bins, EllipsoidProgram::kFusedRest, rate, walked);
  ++stats_->sampled_passes;
}

void EllipsoidRenderer::drawRuns(const Batch& b, const BinLists& bins, EllipsoidProgram which,
                                 int rate, const std::vector<glm::ivec4>& runs) {
  // The blended runs in one draw; the walked ones, when the frame can be cancelled, in groups
  // of about kCancelWork hit tests.
  const GLuint q = perPixelProgram(b, bins, which, rate);
  const bool chunked = cancel_ && which == EllipsoidProgram::kFusedRest;
  std::size_t first = 0;
  std::int64_t work = 0;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const glm::ivec4 r = runs[i];
    for (int bx = r.x / kPerPixelBinSize; chunked && bx * kPerPixelBinSize < r.z; ++bx)
      work += std::int64_t(bins.at(bx, r.y / kPerPixelBinSize).y) * rate *
              (std::min(r.z, (bx + 1) * kPerPixelBinSize) - std::max(r.x, bx * kPerPixelBinSize));
    const bool last = i + 1 == runs.size();
    if (!last && work <= kCancelWork) continue;
    bindFrameTexture(kRectTextureUnit, GL_RGBA32I, runs.data() + first,
                     (i + 1 - first) * sizeof(glm::ivec4));
    gl_.UseProgram(q);
    gl_.DrawArrays(GL_TRIANGLES, 0, GLsizei(6 * (i + 1 - first)));
    if (last) break;
    paceQueued();
    if (stopNow()) return;
    first = i + 1, work = 0;
  }
}

void EllipsoidRenderer::prepareSamples(glm::ivec2 size) {
  if (samples_ && samples_size_ == size) return;
  createColourTarget(gl_, GL_RGBA16F, size, "samples", samples_, samples_framebuffer_);
  sample_distance_ = createTexture(gl_, GL_TEXTURE_2D);
  gl_.TextureStorage2D(sample_distance_.get(), 1, GL_R32F, size.x, size.y);
  gl_.NamedFramebufferTexture(samples_framebuffer_.get(), GL_COLOR_ATTACHMENT1,
                              sample_distance_.get(), 0);
  const GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  gl_.NamedFramebufferDrawBuffers(samples_framebuffer_.get(), 2, buffers);
  samples_size_ = size;
}

}  // namespace nephele
