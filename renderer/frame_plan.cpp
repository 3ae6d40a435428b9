#include "renderer/frame_plan.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include "world/limits.h"

namespace nephele {
namespace {

// Milliseconds since `start`, added to `ms`.
void addElapsed(double& ms, std::chrono::steady_clock::time_point start) {
  ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// The widening of the probe's field for the waves' tilts.
constexpr double kProbeMarginDeg = 20.0;

// `scene` without its clouds, which a view lists apart (Scene's other members are few).
std::unique_ptr<Scene> withoutClouds(const Scene& scene) {
  return std::make_unique<Scene>(withClouds(scene, {}));
}

// The clouds of `view` that may show, and those that cannot, by their bounding boxes.
void cullToView(ViewPlan& view) {
  const Camera& camera = view.camera();
  const ViewBasis basis = viewBasis(camera);
  for (std::size_t i = 0; i < view.clouds.size(); ++i) {
    const EllipsoidCloud& cloud = view.cloud(i);
    if (cloud.ellipsoids.empty()) continue;
    if (const BoundingBox box = boundingBox(cloud);
        !boxMayBeInView(basis, camera.position, box.lo, box.hi)) {
      view.ellipsoids_culled += int(cloud.ellipsoids.size());
      continue;
    }
    view.in_view.push_back(i);
  }
}

// The probe's view of `view` (MODEL.md section 18): the same clouds and sky without the sea and
// the targets, from `camera`.
ViewPlan seaProbeView(const ViewPlan& view, const Camera& camera, bool cull) {
  std::unique_ptr<Scene> probe = withoutClouds(*view.scene);
  probe->sea.reset();
  probe->targets.clear();
  probe->camera = camera;
  ViewPlan out;
  out.scene = probe.get();
  out.own = std::move(probe);
  out.clouds = view.clouds;
  if (cull) cullToView(out);
  return out;
}

}  // namespace

Camera seaProbeCamera(const Camera& view, double scale) {
  Camera probe = view;
  probe.position.z = 0.0;
  probe.orientation.pitch_deg = -view.orientation.pitch_deg;
  probe.orientation.roll_deg = -view.orientation.roll_deg;
  const double aspect = double(view.width) / view.height;
  // The widened field must hold the view's diagonal: its vertical half angle from the diagonal's.
  const double half =
      std::atan(std::tan(0.5 * glm::radians(view.vfov_deg)) * std::sqrt(1.0 + aspect * aspect));
  probe.vfov_deg = std::min(2.0 * glm::degrees(half) + 2.0 * kProbeMarginDeg, 160.0);
  // At least 32 pixels a side and at most a view's largest. The probe keeps the view's aspect,
  // except where its least width was imposed: a view 1 pixel wide and 16,384 high would
  // otherwise ask for a probe 32 x 524,288 (found by the live fuzz), so its height follows the
  // view's own at this scale (a probe wider than needed still holds the view's diagonal).
  const auto side = [](double pixels) {
    return std::clamp(int(std::lround(pixels)), 32, Limits::kMaxImageSide);
  };
  probe.width = side(view.width * scale);
  probe.height = view.width * scale < 32.0 ? side(view.height * scale) : side(probe.width / aspect);
  return probe;
}

bool viewShowsSea(const Camera& camera) {
  const ViewBasis basis = viewBasis(camera);
  bool below = false;
  for (double u : {-1.0, 1.0})
    for (double v : {-1.0, 1.0})
      below |= basis.forward.z + u * basis.right.z * basis.tan_half_vfov * basis.aspect +
                   v * basis.up.z * basis.tan_half_vfov <
               0.0;
  return below;
}

namespace {
std::atomic<std::uint64_t> plans_made{0};
}  // namespace

std::uint64_t framePlansMade() {
  return plans_made.load(std::memory_order_relaxed);
}

FramePlan::FramePlan(const Scene& scene, const FramePlanRequest& request) {
  plans_made.fetch_add(1, std::memory_order_relaxed);
  // Fields of heaps become the clouds around this camera (MODEL.md section 10): the scene's
  // own clouds first, then the heaps, as withFieldClouds lists them.
  view.scene = &scene;
  for (const EllipsoidCloud& cloud : scene.clouds) view.clouds.push_back(&cloud);
  if (!scene.fields.empty()) {
    const auto start = std::chrono::steady_clock::now();
    FieldContent content = fieldContent(scene, request.heaps);
    std::unique_ptr<Scene> fielded = withoutClouds(scene);
    fielded->layers.insert(fielded->layers.end(), content.far_decks.begin(),
                           content.far_decks.end());
    fielded->rain_shafts = std::move(content.rain_shafts);
    fielded->fields.clear();
    heaps = std::move(content.heaps);
    for (const EllipsoidCloud& heap : heaps) view.clouds.push_back(&heap);
    view.scene = fielded.get();
    view.own = std::move(fielded);
    addElapsed(heaps_ms, start);
  }
  {
    // The work budget, counted in ellipsoids and in views of their footprints (issue 31).
    const auto start = std::chrono::steady_clock::now();
    if (std::optional<std::vector<EllipsoidCloud>> within = cloudsWithinBudget(
            view.clouds, scene.camera, request.ellipsoid_budget, request.ellipsoid_overdraw)) {
      kept = std::move(*within);
      view.clouds.clear();
      for (const EllipsoidCloud& cloud : kept) view.clouds.push_back(&cloud);
      thinned = true;
    }
    addElapsed(budget_ms, start);
  }
  if (request.cull) cullToView(view);
  {
    // The shadows of the clouds (MODEL.md section 16), from the scene's own fields: their heaps
    // that shadow the view need not be in it.
    const auto start = std::chrono::steady_clock::now();
    if (request.heap_shadows) heap_shadows.emplace(scene, request.heaps, /*lookups=*/true);
    if (request.plane_shadows) plane_shadows = PlaneShadows(scene);
    addElapsed(shadows_ms, start);
  }
  if (!scene.sea) return;
  if (request.sea_view && viewShowsSea(scene.camera))
    sea_probe =
        seaProbeView(view, seaProbeCamera(scene.camera, request.sea_probe_scale), request.cull);
  if (request.sea_eye) {
    Camera eye = scene.camera;
    eye.position.z = 0.0;
    sea_eye = seaProbeView(view, eye, request.cull);
  }
}

}  // namespace nephele
