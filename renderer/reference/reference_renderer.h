#pragma once
// The CPU reference renderer (MODEL.md section 7): double precision, exact ray-plane hits, every
// texture term, exact ray-ellipsoid hits and limb function, per-pixel depth order,
// supersampled. Slow and simple enough to trust.
#include <atomic>
#include <functional>
#include <memory>

#include "image/image.h"
#include "renderer/frame.h"
#include "renderer/frame_plan.h"
#include "renderer/render_settings.h"
#include "world/scene.h"

namespace nephele {

// `progress`, if given, is called on the calling thread with the fraction of rows started,
// about every tenth of the image.
FloatImage renderReference(const Scene& scene, const ReferenceSettings& settings = {},
                           const std::function<void(double)>& progress = {});

// Stops a frame early: every thread reads `flag` before each row it takes, and `alive` is
// called on the calling thread wherever it reads it (Renderer::setCancel).
struct ReferenceCancel {
  const std::atomic<bool>* flag = nullptr;
  std::function<void()> alive;
};

// Every channel of renderer/frame.h that `request` asks for. Colour and coverage (and
// visibility, 1 - coverage) are supersampled; depth, cloud depth and object id come from each
// pixel's centre ray, where a rasteriser samples them. `cancelled`, when given, is set to
// whether `cancel` stopped the frame before its last row (its channels then incomplete).
Frame renderReferenceFrame(const Scene& scene, const ReferenceSettings& settings,
                           const FrameRequest& request,
                           const std::function<void(double)>& progress = {},
                           const ReferenceCancel& cancel = {}, bool* cancelled = nullptr);
// The same of a frame planned already (the GL's label channels: one plan a frame), its clouds
// and heaps, shadows and rain shafts as `plan` holds them; settings.heaps is not read.
Frame renderReferenceFrame(const FramePlan& plan, const ReferenceSettings& settings,
                           const FrameRequest& request,
                           const std::function<void(double)>& progress = {},
                           const ReferenceCancel& cancel = {}, bool* cancelled = nullptr);

// Cloud transmittance along rays from the scene's camera up to a distance, as the reference
// composites it: how the dataset generator places targets behind cloud or in the clear. The
// scene's clouds (and its fields' heaps) are prepared once; its targets are ignored.
class CloudProbe {
 public:
  explicit CloudProbe(const Scene& scene, const HeapDrawing& heaps = {});
  ~CloudProbe();
  double transmittance(glm::dvec3 direction, double distance) const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace nephele
