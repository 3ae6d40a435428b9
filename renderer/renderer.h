#pragma once
// One interface over the two back ends, GL (EGL or OSMesa) and the CPU reference, made by one
// factory: the render, dataset and bench commands, the benchmarks and the daemon draw through
// it, and a frame is the same set of named channels whichever back end drew it
// (renderer/frame.h).
#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "renderer/encode.h"
#include "renderer/frame.h"
#include "renderer/frame_plan.h"
#include "renderer/frame_stats.h"
#include "renderer/gl/gl_platform.h"
#include "renderer/render_settings.h"
#include "world/scene.h"

namespace nephele {

enum class RendererKind { kGl, kReference };

struct RendererOptions {
  RendererKind kind = RendererKind::kGl;
  GlBackend gl_backend = GlBackend::kAuto;
  // The knobs of the calls that take none (render(scene, request), renderSrgb8(scene)).
  RenderSettings render;
  // The reference's threads (0: one per hardware thread). The rest of what it draws (its
  // samples, the heaps, the sea, the label channels' divisor) comes with each call's
  // RenderSettings.
  int reference_threads = 0;
};

// What a renderer runs on, as the benchmarks and the daemon print it.
struct RendererPlatform {
  std::string backend;  // "egl-device", "egl-surfaceless", "osmesa" or "reference"
  std::string version;  // GL_VERSION; empty for the reference
  std::string device;   // GL_RENDERER; for the reference "cpu, N threads"
};

class Renderer {
 public:
  virtual ~Renderer() = default;

  // The channels `request` asks for (renderer/frame.h), drawn with `settings`. The reference
  // takes from `settings` what it draws alike (heaps, sea_waves, channel_divisor as its label
  // divisor) and samples as RendererOptions::reference says.
  virtual Frame render(const Scene& scene, const RenderSettings& settings,
                       const FrameRequest& request) = 0;
  // Linear float RGB plus coverage (EXR, and measuring error).
  virtual FloatImage renderFloat(const Scene& scene, const RenderSettings& settings) = 0;
  // Colour only, sRGB bytes: the GL back end reads its 8-bit target directly.
  virtual Srgb8Image renderSrgb8(const Scene& scene, const RenderSettings& settings) = 0;
  // The same with the renderer's own settings (RendererOptions::render).
  Frame render(const Scene& scene, const FrameRequest& request) {
    return render(scene, settings_, request);
  }
  Srgb8Image renderSrgb8(const Scene& scene) { return renderSrgb8(scene, settings_); }

  // The platform floor: a constant colour over a width x height 8-bit frame and its readback
  // (GL: one blended full-screen pass; the reference: the colour filled and encoded).
  // Benchmarks print frame times as multiples of it, since absolute times on shared machines
  // vary by 30 % between runs.
  virtual Srgb8Image renderFloor(int width, int height) = 0;

  // Empty when a width x height frame (float or 8-bit; with targets, or depth or object ids
  // asked, when `targets`) can be drawn, else why not. Call it before any work.
  virtual std::string reserve(int width, int height, bool linear, bool targets) = 0;

  // What the last frame did (renderer/frame_stats.h); all zero from the reference.
  virtual const FrameStats& lastFrameStats() const = 0;
  // The same in one line, for logs; empty from the reference.
  virtual std::string statsLine() const { return ""; }

  // The view the frames from now on belong to, one of a stream that moves continuously, or
  // empty (the default) when every frame must be exact: GL reuses a continuous view's heaps
  // from its last frame (RenderSettings::heap_refresh, MODEL.md section 15); the reference
  // draws every frame exact and ignores it.
  virtual void setContinuousView(std::string view) { (void)view; }

  // A flag another thread may raise to cancel the frame being drawn; `alive` is called
  // wherever the flag is read (GL: between batches of heaps; the reference: between rows). A
  // cancelled frame is incomplete and lastFrameCancelled() says so.
  virtual void setCancel(const std::atomic<bool>* flag, std::function<void()> alive = {}) = 0;
  virtual bool lastFrameCancelled() const = 0;

  virtual RendererPlatform platform() const = 0;
  // "gl: osmesa, OpenGL 4.5 ..., GL_RENDERER llvmpipe ..." or "reference: 4x4 samples ...".
  virtual std::string description() const = 0;

  // A renderer of the same back end and options with none of this one's state (caches,
  // continuous views); GL shares this one's context, so both draw on this thread. For
  // benchmarks that measure a renderer's first frames.
  virtual std::unique_ptr<Renderer> another() const = 0;

  // Reports the fraction done of long renders (the reference), on the calling thread.
  void setProgress(std::function<void(double)> progress) { progress_ = std::move(progress); }

 protected:
  explicit Renderer(const RenderSettings& settings) : settings_(settings) {}

  RenderSettings settings_;
  std::function<void(double)> progress_;
};

// Null and `error` set when the back end cannot start (no GL platform).
std::unique_ptr<Renderer> createRenderer(const RendererOptions& options, std::string& error);

// The visibility channel times the precipitation's transmittance (MODEL.md section 17) on each
// pixel's centre ray up to its first opaque surface, the ground or a target: a target behind
// rain is less visible. The slabs and shafts are the frame plan's (`view`, whose scene holds the
// shafts under the heaps it drew), as the colour drew them. Nothing without precipitation or
// without the channel.
void dimVisibilityByPrecipitation(Frame& frame, const ViewPlan& view);

}  // namespace nephele
