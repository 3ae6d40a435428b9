// Leave out what a scene does not need: a frame pays only for the kinds of cloud it holds
// and for the texture terms its pixels can resolve (renderer/frame_stats.h).
#include <gtest/gtest.h>

#include <chrono>

#include "tests/gl_test_fixture.h"
#include "world/formations/weather.h"
#include "world/world.h"

namespace nephele {
namespace {

class FrameStatsTest : public GlRenderTest {
 protected:
  static FrameStats statsOf(const Scene& scene, const RenderSettings& settings = {}) {
    renderer_->renderSrgb8(scene, settings);
    return renderer_->lastFrameStats();
  }
};

// Ellipsoid clouds cost ellipsoid passes (and atlas passes with multipass); without them
// there is no ellipsoid, atlas or veil pass and nothing is drawn or culled.
TEST_F(FrameStatsTest, NoEllipsoidWorkWithoutEllipsoids) {
  Scene scene = preset("cumulus").scene;
  RenderSettings multipass;
  multipass.ellipsoid_passes = EllipsoidPasses::kMultipass;
  const FrameStats with = statsOf(scene), with_tiles = statsOf(scene, multipass);
  EXPECT_GE(with.ellipsoid_passes, 1);
  EXPECT_EQ(with.ellipsoids_drawn, 27);
  EXPECT_EQ(with.atlas_passes, 0);
  EXPECT_EQ(with_tiles.atlas_passes, 3 * 27);  // threshold, limb and colour per tile
  scene.clouds.clear();
  for (const RenderSettings& settings : {RenderSettings{}, multipass}) {
    const FrameStats without = statsOf(scene, settings);
    EXPECT_EQ(without.ellipsoid_passes + without.atlas_passes + without.veil_passes, 0);
    EXPECT_EQ(without.ellipsoids_drawn + without.ellipsoids_culled, 0);
    EXPECT_EQ(without.passes(), without.sky_passes);
  }
}

// Ellipsoids behind the camera are culled, not drawn.
TEST_F(FrameStatsTest, EllipsoidsOutOfViewAreCulled) {
  Scene scene = preset("cumulus").scene;
  scene.camera.orientation.heading_deg += 180.0;
  const FrameStats behind = statsOf(scene);
  EXPECT_EQ(behind.ellipsoids_drawn, 0);
  EXPECT_EQ(behind.ellipsoids_culled, 27);
  EXPECT_EQ(behind.ellipsoid_passes, 0);
}

// An automaton cloud costs a volume pass and an upload per new keyframe; without automata
// there is neither, and the World runs no automaton step or relight.
TEST_F(FrameStatsTest, NoAutomatonWorkWithoutAutomata) {
  const SceneFile file = preset("automaton_cloud");
  World world(file.scene, file.dynamics);
  world.advance(60.0);
  const FrameStats with = statsOf(world.scene());
  EXPECT_EQ(with.automaton_passes, 1);
  EXPECT_EQ(with.volume_uploads, 1);
  EXPECT_EQ(statsOf(world.scene()).volume_uploads, 0);  // the same keyframes: no upload

  WorldDynamics none = file.dynamics;
  none.automata.clear();
  World empty(file.scene, none);
  empty.advance(60.0);
  Sun sun = empty.base().sun;
  sun.elevation_deg += 10.0;
  empty.setSun(sun);
  EXPECT_EQ(empty.automatonStepsRun(), 0u);
  EXPECT_EQ(empty.relightsRun(), 0u);
  const FrameStats without = statsOf(empty.scene());
  EXPECT_EQ(without.automaton_passes + without.volume_uploads, 0);
}

// The term filter leaves out the terms a pixel cannot resolve: a layer 10 km up seen in a
// 16 x 12 image evaluates fewer terms than in a 1280 x 1024 one, and never more than it has.
TEST_F(FrameStatsTest, NoTermAboveTheSamplingFrequency) {
  SceneFile file = preset("cirrus", 1280, 1024);
  const FrameStats fine = statsOf(file.scene);
  file.scene.camera.width = 16;
  file.scene.camera.height = 12;
  const FrameStats coarse = statsOf(file.scene);
  ASSERT_GT(fine.layer_terms_total, 0);
  EXPECT_LE(fine.layer_terms, fine.layer_terms_total);
  EXPECT_LT(coarse.layer_terms, fine.layer_terms);
  RenderSettings every_term;
  every_term.term_filter = TermFilter::kNone;
  EXPECT_EQ(statsOf(file.scene, every_term).layer_terms, fine.layer_terms_total);
  // Without layers there is only the background.
  file.scene.layers.clear();
  const FrameStats bare = statsOf(file.scene);
  EXPECT_EQ(bare.layer_terms_total, 0);
  EXPECT_EQ(bare.passes(), bare.sky_passes);
  EXPECT_LE(bare.sky_passes, 2);  // one per side of the horizon
}

// A full deck hides the layers beyond it exactly, and they are left out: an altostratus over
// a full stratus, seen from under the stratus, costs the stratus's terms alone and draws the
// stratus's image to the bit; seen from between them, both are drawn.
TEST_F(FrameStatsTest, AFullDeckLeavesOutTheLayersBeyondIt) {
  Scene deck;
  deck.camera.width = 64, deck.camera.height = 48;
  deck.camera.orientation.pitch_deg = 30.0;
  WeatherLayer stratus = typicalWeatherLayer(CloudType::kStratus, 1.0);
  deck.layers = weatherClouds(stratus, "low", 3).layers;
  ASSERT_FALSE(deck.layers.empty());
  Scene both = deck;
  WeatherLayer altostratus = typicalWeatherLayer(CloudType::kAltostratus, 0.5);
  for (const CloudLayer& l : weatherClouds(altostratus, "high", 4).layers) both.layers.push_back(l);
  const FrameStats alone = statsOf(deck), under = statsOf(both);
  EXPECT_EQ(under.layer_terms_total, alone.layer_terms_total);
  EXPECT_EQ(renderer_->renderSrgb8(both, {}).rgba, renderer_->renderSrgb8(deck, {}).rgba);
  both.camera.position.z = 0.5 * (stratus.base_m + stratus.thickness_m + altostratus.base_m);
  EXPECT_GT(statsOf(both).layer_terms_total, alone.layer_terms_total);
}

// Where a frame's time goes (FrameTimes): a frame of heaps charges the heaps' GPU passes, their
// records and the readback; a clear frame charges the sky alone and no heap, record or upload.
// On a software GL the passes are timed by the wall clock, so they cannot sum past the frame.
TEST_F(FrameStatsTest, TimesGoToTheStagesThatRan) {
  Scene scene = preset("cumulus").scene;
  renderer_->renderSrgb8(scene, {});  // programs compiled, tables baked
  const auto start = std::chrono::steady_clock::now();
  const FrameTimes heaps = statsOf(scene).times;
  const double wall_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GT(heaps.gpu(GpuPass::kHeaps), 0.0);
  EXPECT_GT(heaps.gpu(GpuPass::kSky), 0.0);
  EXPECT_GT(heaps.cpu(CpuStage::kRecords), 0.0);
  EXPECT_GT(heaps.readback_ms, 0.0);
  EXPECT_EQ(heaps.gpu(GpuPass::kAutomata), 0.0);
  EXPECT_EQ(heaps.gpu(GpuPass::kTargets), 0.0);
  if (platform_->renderer().find("llvmpipe") != std::string::npos) {
    EXPECT_LE(heaps.submit_ms + heaps.gpuTotal() + heaps.wait_ms + heaps.readback_ms,
              wall_ms * 1.001 + 0.01);
  }
  double cpu = 0.0;
  for (double ms : heaps.cpu_ms) cpu += ms;
  EXPECT_NEAR(cpu, heaps.submit_ms, 1e-6);  // the stages share out the submission

  scene.clouds.clear();
  const FrameTimes clear = statsOf(scene).times;
  EXPECT_GT(clear.gpu(GpuPass::kSky), 0.0);
  EXPECT_EQ(clear.gpu(GpuPass::kHeaps), 0.0);
  EXPECT_EQ(clear.cpu(CpuStage::kRecords), 0.0);
  EXPECT_EQ(clear.cpu(CpuStage::kHeaps), 0.0);
  // Every figure has a name, and the log line carries them.
  const std::string line = renderer_->lastFrameStats().line();
  for (const auto& [name, ms] : clear.fields())
    EXPECT_NE(line.find(" " + name + "_ms="), std::string::npos) << name;
}

}  // namespace
}  // namespace nephele
