// The frame plan (renderer/frame_plan.h): a view lists the scene's own clouds without copying
// them, then its fields' heaps as withFieldClouds adds them; the budget thins the list as
// withinEllipsoidBudget thins a scene; the sea's probe shares the view's clouds.
#include "renderer/frame_plan.h"
#include "world/limits.h"

#include <gtest/gtest.h>

#include "world/formations/ellipsoid.h"
#include "world/scene.h"

namespace nephele {
namespace {

// Two clouds of three lobes ahead of a camera at 1 km looking north, and a cumulus field.
Scene plannedScene() {
  Scene scene;
  scene.camera.position = {0.0, 0.0, 1000.0};
  scene.camera.width = 160;
  scene.camera.height = 90;
  for (int c = 0; c < 2; ++c) {
    EllipsoidCloud cloud;
    for (int i = 0; i < 3; ++i) {
      Ellipsoid e;
      e.centre = {300.0 * i - 300.0, 4000.0 + 2000.0 * c, 1500.0};
      e.radii = {200.0 + 50.0 * i, 200.0, 150.0};
      cloud.ellipsoids.push_back(e);
    }
    scene.clouds.push_back(cloud);
  }
  CloudField field;
  field.base_m = 1200.0;
  field.thickness_m = 800.0;
  field.coverage = 0.3;
  field.seed = 5;
  scene.fields.push_back(field);
  return scene;
}

// Whether two clouds hold the same lobes.
bool sameLobes(const EllipsoidCloud& a, const EllipsoidCloud& b) {
  if (a.ellipsoids.size() != b.ellipsoids.size()) return false;
  for (std::size_t i = 0; i < a.ellipsoids.size(); ++i)
    if (a.ellipsoids[i].centre != b.ellipsoids[i].centre ||
        a.ellipsoids[i].radii != b.ellipsoids[i].radii)
      return false;
  return true;
}

TEST(FramePlan, BorrowsTheScenesCloudsAndAddsItsFieldsHeaps) {
  const Scene scene = plannedScene();
  const FramePlan plan(scene, {});
  const Scene drawn = withFieldClouds(scene);
  ASSERT_EQ(plan.view.clouds.size(), drawn.clouds.size());
  ASSERT_GT(drawn.clouds.size(), scene.clouds.size());
  for (std::size_t i = 0; i < scene.clouds.size(); ++i)
    EXPECT_EQ(plan.view.clouds[i], &scene.clouds[i]);  // borrowed, not copied
  for (std::size_t i = 0; i < drawn.clouds.size(); ++i)
    EXPECT_TRUE(sameLobes(plan.view.cloud(i), drawn.clouds[i])) << i;
  // The view's scene holds the far decks and the shafts in place of the fields, and no clouds.
  EXPECT_TRUE(plan.view.scene->clouds.empty());
  EXPECT_TRUE(plan.view.scene->fields.empty());
  EXPECT_EQ(plan.view.scene->layers.size(), drawn.layers.size());
  EXPECT_EQ(plan.view.scene->rain_shafts, drawn.rain_shafts);
  EXPECT_FALSE(plan.thinned);
  EXPECT_FALSE(plan.sea_probe);
}

TEST(FramePlan, ABudgetThinsTheListAsItThinsAScene) {
  Scene scene = plannedScene();
  scene.fields.clear();
  FramePlanRequest request;
  request.ellipsoid_budget = 4.0;
  const FramePlan plan(scene, request);
  const std::optional<Scene> within = withinEllipsoidBudget(scene, 4.0);
  ASSERT_TRUE(within);
  ASSERT_TRUE(plan.thinned);
  EXPECT_EQ(plan.view.scene, &scene);  // nothing else of the scene changed
  ASSERT_EQ(plan.view.clouds.size(), within->clouds.size());
  for (std::size_t i = 0; i < within->clouds.size(); ++i)
    EXPECT_TRUE(sameLobes(plan.view.cloud(i), within->clouds[i])) << i;
}

TEST(FramePlan, TheSeasProbeOfAnyLegalViewIsALegalTarget) {
  // A view 1 pixel wide and 16,384 high asked the GL for a 32 x 524,288 probe and aborted the
  // daemon (the live fuzz of issue 62). Every probe stays within 32 to 16,384 a side and holds
  // about the view's rows at its scale.
  for (const auto& [width, height] :
       {std::pair{1, 16384}, {16384, 1}, {1, 1}, {16384, 16384}, {64, 16384}, {640, 480}})
    for (double scale : {Limits::kSeaProbeScale.lo, 0.5, Limits::kSeaProbeScale.hi}) {
      Camera view;
      view.width = width;
      view.height = height;
      view.vfov_deg = 60.0;
      const Camera probe = seaProbeCamera(view, scale);
      SCOPED_TRACE(std::to_string(width) + "x" + std::to_string(height) + " at " +
                   std::to_string(scale));
      EXPECT_GE(probe.width, 32);
      EXPECT_GE(probe.height, 32);
      EXPECT_LE(probe.width, Limits::kMaxImageSide);
      EXPECT_LE(probe.height, Limits::kMaxImageSide);
      EXPECT_LE(probe.height, std::max(32.0, std::ceil(height * scale)) + 1.0);
    }
}

TEST(FramePlan, TheSeasProbeSharesTheViewsCloudsFromTheSea) {
  Scene scene = plannedScene();
  scene.fields.clear();
  scene.sea.emplace();
  scene.targets.emplace_back();
  scene.camera.orientation.pitch_deg = -10.0;
  FramePlanRequest request;
  request.sea_view = true;
  request.cull = true;
  const FramePlan plan(scene, request);
  ASSERT_TRUE(plan.sea_probe);
  const ViewPlan& probe = *plan.sea_probe;
  EXPECT_EQ(probe.clouds, plan.view.clouds);
  EXPECT_FALSE(probe.scene->sea);
  EXPECT_TRUE(probe.scene->targets.empty());
  const Camera expected = seaProbeCamera(scene.camera, request.sea_probe_scale);
  EXPECT_EQ(probe.camera().position, expected.position);
  EXPECT_EQ(probe.camera().width, expected.width);
  EXPECT_EQ(probe.camera().vfov_deg, expected.vfov_deg);
  // Every cloud ahead is in view; a view that only climbs shows no sea and has no probe.
  EXPECT_EQ(plan.view.in_view.size(), scene.clouds.size());
  scene.camera.orientation.pitch_deg = 60.0;
  EXPECT_FALSE(FramePlan(scene, request).sea_probe);
  // A tracer's probe is the eye moved down to the sea, whatever the view.
  request.sea_view = false;
  request.sea_eye = true;
  const FramePlan traced(scene, request);
  ASSERT_TRUE(traced.sea_eye);
  EXPECT_EQ(traced.sea_eye->camera().position.z, 0.0);
  EXPECT_EQ(traced.sea_eye->camera().orientation.pitch_deg, 60.0);
}

}  // namespace
}  // namespace nephele
