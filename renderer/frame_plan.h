#pragma once
// A frame's preparation, a step of its own before any pass (no GL): what a view draws. The plan
// owns the content it makes (its fields' heaps around the camera, far decks and rain shafts,
// MODEL.md sections 10, 11 and 17; the clouds a work budget thins, section 15; the shadows of
// the clouds, section 16) and borrows the rest from the scene, which must outlive it. The GL
// renderer draws a plan in its passes, and the sea's probe (section 18) as a second view of it;
// the reference traces the same views.
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "world/formations/cloud_shadow.h"
#include "world/scene.h"

namespace nephele {

// What one camera draws: everything of `scene` but its clouds (its camera is the view's), and
// the clouds listed, in order.
struct ViewPlan {
  const Scene* scene = nullptr;
  std::vector<const EllipsoidCloud*> clouds;
  // The listed clouds whose bounding box may meet the view frustum, and the ellipsoids of
  // those that cannot (FramePlanRequest::cull; the eye inside a cloud is the veil's business).
  std::vector<std::size_t> in_view;
  int ellipsoids_culled = 0;
  // `scene` where the plan changed the one given (the fields' content in place of the fields; a
  // probe's camera without the sea and targets), with no clouds of its own.
  std::unique_ptr<const Scene> own;

  const Camera& camera() const { return scene->camera; }
  const EllipsoidCloud& cloud(std::size_t i) const { return *clouds[i]; }
};

struct FramePlanRequest {
  HeapDrawing heaps;
  // The work budget (RenderSettings::ellipsoid_budget and ellipsoid_overdraw; 0: none).
  double ellipsoid_budget = 0.0, ellipsoid_overdraw = 0.0;
  // The sea's probes, over a sea (MODEL.md section 18): a rasteriser's view of what the sea
  // mirrors (FramePlan::sea_probe, seaProbeCamera, when the view shows the sea), and the view's
  // camera moved down to the sea for a tracer that mirrors its rays (FramePlan::sea_eye; the
  // GL's label channels traced on the CPU ask for both).
  bool sea_view = false;
  bool sea_eye = false;
  double sea_probe_scale = 0.5;  // sea_view: of the view's resolution
  bool cull = false;             // list each view's clouds in view
  bool heap_shadows = false;     // the fields' and clouds' shadows (CloudShadows, with lookups)
  bool plane_shadows = false;    // the casting planes' shadows (PlaneShadows)
};

// The probe's camera for a rasteriser: at the sea below the eye, looking where the view's rays
// are mirrored, its field widened for the waves' tilts, at `scale` of the view's resolution
// (MODEL.md section 18, "what the sea mirrors").
Camera seaProbeCamera(const Camera& view, double scale);
// Whether some corner ray of the view descends (the view can show the sea).
bool viewShowsSea(const Camera& camera);

// The plan of one frame of `scene`, made once when constructed.
struct FramePlan {
  FramePlan(const Scene& scene, const FramePlanRequest& request);
  FramePlan(const FramePlan&) = delete;
  FramePlan& operator=(const FramePlan&) = delete;

  // The fields' heaps and the clouds the budget kept (empty when it kept all), which the views'
  // lists point into.
  std::vector<EllipsoidCloud> heaps, kept;
  bool thinned = false;  // the budget thinned the clouds: the views are within it
  ViewPlan view;
  std::optional<ViewPlan> sea_probe;  // FramePlanRequest::sea_view
  std::optional<ViewPlan> sea_eye;    // FramePlanRequest::sea_eye
  std::optional<CloudShadows> heap_shadows;
  PlaneShadows plane_shadows;
  // How long its stages took.
  double heaps_ms = 0.0, budget_ms = 0.0, shadows_ms = 0.0;
};

// Plans made in this process: a frame makes one, whatever channels it draws (tests count them).
std::uint64_t framePlansMade();

}  // namespace nephele
