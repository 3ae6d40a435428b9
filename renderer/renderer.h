#pragma once
// One interface over the two back ends, GL (EGL or OSMesa) and the CPU reference, made by one
// factory: the render command and the dataset generator draw through it, and a frame is the
// same set of named channels whichever back end drew it (renderer/frame.h).
#include <functional>
#include <memory>
#include <string>

#include "renderer/encode.h"
#include "renderer/frame.h"
#include "renderer/gl/gl_platform.h"
#include "renderer/render_settings.h"
#include "world/scene.h"

namespace nephele {

enum class RendererKind { kGl, kReference };

struct RendererOptions {
  RendererKind kind = RendererKind::kGl;
  GlBackend gl_backend = GlBackend::kAuto;
  RenderSettings render;
  ReferenceSettings reference;
};

class Renderer {
 public:
  virtual ~Renderer() = default;
  virtual Frame render(const Scene& scene, const FrameRequest& request) = 0;
  // Colour only, sRGB bytes: the GL back end reads its 8-bit target directly.
  virtual Srgb8Image renderSrgb8(const Scene& scene) = 0;
  // Empty when a width x height frame (float or 8-bit; with targets, or depth or object ids
  // asked, when `targets`) can be drawn, else why not. Call it before any work.
  virtual std::string reserve(int width, int height, bool linear, bool targets) = 0;
  // What the last frame did (GL: passes, ellipsoids drawn and culled, terms); may be empty.
  virtual std::string statsLine() const { return ""; }
  // "gl: osmesa, OpenGL 4.5 ..., GL_RENDERER llvmpipe ..." or "reference: 4x4 samples ...".
  virtual std::string description() const = 0;
  // Reports the fraction done of long renders (the reference), on the calling thread.
  void setProgress(std::function<void(double)> progress) { progress_ = std::move(progress); }

 protected:
  std::function<void(double)> progress_;
};

// Null and `error` set when the back end cannot start (no GL platform).
std::unique_ptr<Renderer> createRenderer(const RendererOptions& options, std::string& error);

// The visibility channel times the scene's precipitation's transmittance (MODEL.md section 17)
// on each pixel's centre ray up to its first opaque surface, the ground or a target: a target
// behind rain is less visible; the shafts under heaps are those of `heaps`' range, as drawn.
// Nothing without precipitation or without the channel.
void dimVisibilityByPrecipitation(Frame& frame, const Scene& scene, const HeapDrawing& heaps);

}  // namespace nephele
