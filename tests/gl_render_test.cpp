// GL renderer against the CPU reference (MODEL.md section 7). Metric: PSNR over sRGB-encoded RGB
// in [0, 1] and the largest sRGB channel difference; tolerances are stated per test. On
// failure the actual, expected and 8x difference images go to NEPHELE_TEST_OUTPUT.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <numbers>

#include "image/cloud_statistics.h"
#include "tests/gl_test_fixture.h"

namespace nephele {
namespace {

// Every preset at 160x120 against the 4x4-supersampled reference. The GL renderer drops
// texture terms above the pixel's sampling frequency where the reference averages them, so
// the images differ in fine, distant texture: 38 dB and 0.25 bound that difference.
TEST_F(GlRenderTest, PresetsMatchReference) {
  for (const char* name : {"cirrus", "stratus", "overcast", "ground_fog"}) {
    const SceneFile file = preset(name);
    const FloatImage reference = renderReference(file.scene, file.reference());
    expectClose(renderer_->renderFloat(file.scene, file.render), reference, 38.0, 0.25,
                std::string("preset_") + name);
  }
}

TEST_F(GlRenderTest, KnobsMatchReference) {
  const SceneFile file = preset("cirrus");
  const FloatImage reference = renderReference(file.scene, file.reference());
  RenderSettings procedural = file.render;
  procedural.texture_evaluation = TextureEvaluation::kProcedural;
  expectClose(renderer_->renderFloat(file.scene, procedural), reference, 38.0, 0.25, "procedural");
  RenderSettings cut = file.render;
  cut.term_filter = TermFilter::kCut;
  expectClose(renderer_->renderFloat(file.scene, cut), reference, 38.0, 0.25, "cut");
}

// Multipass and fused passes composite the same layers in the same order.
TEST_F(GlRenderTest, MultipassEqualsFused) {
  SceneFile file = preset("ground_fog");
  file.scene.layers.push_back(file.scene.layers[0]);
  file.scene.layers.back().altitude_m = 3000.0;
  file.scene.layers.back().texture.seed = 99;
  RenderSettings multipass = file.render;
  multipass.sky_passes = SkyPasses::kMultipass;
  expectClose(renderer_->renderFloat(file.scene, multipass),
              renderer_->renderFloat(file.scene, file.render), 60.0, 0.01, "multipass");
}

// Point-sampled GL with every term (procedural, no term filter) evaluates the same function
// as the reference with one sample per pixel: geometry, layer order, shading and fog must
// agree to float precision. Views keep the horizon out of the frame, where GL antialiases
// the ground edge analytically and the one-sample reference cannot.
RenderSettings pointSampled() {
  RenderSettings s;
  s.texture_evaluation = TextureEvaluation::kProcedural;
  s.term_filter = TermFilter::kNone;
  return s;
}

void expectPointSampledEqual(GlRenderer& renderer, const Scene& scene, const std::string& name);

TEST_F(GlRenderTest, PointSampledEqualsOneSampleReference) {
  for (const char* name : {"cirrus", "stratus", "overcast", "ground_fog"}) {
    SceneFile file = preset(name);
    file.scene.camera.orientation.pitch_deg = 50.0;
    if (file.scene.fog) file.scene.camera.position.z = 0.5 * file.scene.fog->top_m;  // in fog
    expectPointSampledEqual(*renderer_, file.scene, std::string("point_") + name);
  }
  SceneFile fog = preset("ground_fog");
  fog.scene.camera.orientation.pitch_deg = -50.0;  // the ground through the fog
  expectPointSampledEqual(*renderer_, fog.scene, "point_fog_down");
  // Haze (MODEL.md section 5) on a layer above, on the ground below from 3 km, and mixed with
  // the fog.
  SceneFile hazy = preset("stratus");
  hazy.scene.haze = Haze{8000.0, 1500.0};
  hazy.scene.camera.orientation.pitch_deg = 50.0;
  expectPointSampledEqual(*renderer_, hazy.scene, "point_haze_up");
  hazy.scene.camera.position.z = 3000.0;
  hazy.scene.camera.orientation.pitch_deg = -50.0;
  expectPointSampledEqual(*renderer_, hazy.scene, "point_haze_down");
  fog.scene.haze = Haze{5000.0, 800.0};
  expectPointSampledEqual(*renderer_, fog.scene, "point_fog_haze_down");
}

// Largest channel difference 2e-3 in linear RGB (float against double).
void expectPointSampledEqual(GlRenderer& renderer, const Scene& scene, const std::string& name) {
  const FloatImage gl = renderer.renderFloat(scene, pointSampled());
  const FloatImage reference = renderReference(scene, {1, 0});
  float worst = 0.0f;
  for (std::size_t i = 0; i < gl.rgba.size(); ++i)
    worst = std::max(worst, std::abs(gl.rgba[i] - reference.rgba[i]));
  EXPECT_LE(worst, 2e-3f) << name;
}

// Sky planes shadow what lies below them (MODEL.md section 16, "sky planes"): a stratocumulus
// deck and the ground under an altocumulus layer, seen from between the two looking down, so
// that the upper layer shows only by its shadows. Equal to the one-sample reference; without
// the upper layer the view is brighter wherever it differs, and differs.
TEST_F(GlRenderTest, SkyPlanesShadowTheDeckAndTheGroundBelow) {
  SceneFile file = preset("genus_stratocumulus", 160, 90);
  Scene& scene = file.scene;
  for (const CloudLayer& layer : preset("genus_altocumulus", 160, 90).scene.layers)
    scene.layers.push_back(layer);
  scene.camera.position = {0.0, 0.0, 2500.0};
  scene.camera.orientation = {30.0, -40.0, 0.0};
  scene.camera.vfov_deg = 50.0;
  expectPointSampledEqual(*renderer_, scene, "plane_shadows");
  Scene lone = scene;
  std::erase_if(lone.layers, [&](const CloudLayer& l) { return l.altitude_m > 2500.0; });
  ASSERT_LT(lone.layers.size(), scene.layers.size());
  const FloatImage shadowed = renderer_->renderFloat(scene, pointSampled());
  const FloatImage lit = renderer_->renderFloat(lone, pointSampled());
  float darkest = 0.0f, brightest = 0.0f;
  for (std::size_t i = 0; i < lit.rgba.size(); ++i) {
    darkest = std::max(darkest, lit.rgba[i] - shadowed.rgba[i]);
    brightest = std::max(brightest, shadowed.rgba[i] - lit.rgba[i]);
  }
  EXPECT_GT(darkest, 0.05f);
  EXPECT_LE(brightest, 1e-5f);
}

// Lattice breaking (rotated, jittered components; MODEL.md section 2) as the weather mapping
// draws altocumulus: exact against the one-sample reference. The renderer's texture state
// follows the jitter: after the same layer without it, the jittered one is drawn right again.
TEST_F(GlRenderTest, LatticeBreakingEqualsOneSampleReference) {
  SceneFile file = preset("genus_altocumulus");
  ASSERT_FALSE(file.scene.layers.empty());
  ASSERT_GT(file.scene.layers[0].texture.gardner.jitter_octaves, 0.0);
  ASSERT_GT(file.scene.layers[0].texture.gardner.rotation_deg, 0.0);
  file.scene.camera.orientation.pitch_deg = 50.0;
  expectPointSampledEqual(*renderer_, file.scene, "point_lattice_breaking");
  SceneFile plain = file;
  for (CloudLayer& l : plain.scene.layers) l.texture.gardner.jitter_octaves = 0.0;
  expectPointSampledEqual(*renderer_, plain.scene, "point_rotation_only");
  expectPointSampledEqual(*renderer_, file.scene, "point_lattice_breaking_again");
}

// The clipmap of a texture that never repeats (MODEL.md section 2, "Clipmap") against the
// 4x4-supersampled reference, as the per-pixel sines are held to it, and against the sines:
// altocumulus from the ground and stratocumulus from above, at 320x240. The rings hold each
// truncation the term filter keeps, so the two images differ only by the rings' bilinear
// interpolation and, at ring edges, by a coarser ring than the footprint asks.
TEST_F(GlRenderTest, ClipmapMatchesReference) {
  struct Case {
    const char* preset;
    double pitch_deg, z_m;
  };
  for (const Case& c :
       {Case{"genus_altocumulus", 50.0, 2.0}, Case{"genus_stratocumulus", -40.0, 4000.0}}) {
    SceneFile file = preset(c.preset, 320, 240);
    ASSERT_GT(file.scene.layers[0].texture.gardner.rotation_deg, 0.0) << c.preset;
    file.scene.camera.orientation.pitch_deg = c.pitch_deg;
    file.scene.camera.position.z = c.z_m;
    RenderSettings clipmap = file.render, sines = file.render;
    clipmap.texture_evaluation = TextureEvaluation::kBaked;
    sines.texture_evaluation = TextureEvaluation::kProcedural;
    const FloatImage a = renderer_->renderFloat(file.scene, clipmap);
    EXPECT_GT(renderer_->lastFrameStats().layer_texels_baked, 0) << c.preset;
    const FloatImage reference = renderReference(file.scene, file.reference());
    const FloatImage b = renderer_->renderFloat(file.scene, sines);
    const std::string name = std::string("clipmap_") + c.preset;
    std::printf(
        "%s: clipmap %.1f dB, sines %.1f dB against the reference; clipmap against sines %.1f dB\n",
        c.preset, compareImages(a, reference).psnr_db, compareImages(b, reference).psnr_db,
        compareImages(a, b).psnr_db);
    expectClose(a, reference, 36.0, 0.25, name);
    expectClose(a, b, 40.0, 0.2, name + "_sines");
  }
}

// A clipmap carried along a flight by strips (a toroidal update: only the texels the camera
// uncovers are evaluated) holds what a clipmap filled at the end of the flight holds. `auto`:
// a single render notes the clipmap and reads the sines; a second render from the same place
// fills the coarsest ring whole, then a frame's pixels of texels a frame, coarsest first, and
// reads the sines until the clipmap is whole, when it draws what `baked` draws. A continuous
// view fills from its first frame and reads the rings filled so far, compiling no program on
// the way.
TEST_F(GlRenderTest, ClipmapFollowsTheCameraByStrips) {
  SceneFile file = preset("genus_stratocumulus", 160, 120);
  file.scene.camera.orientation = {80.0, 20.0, 0.0};  // ahead, where the strips are filled
  file.scene.camera.position.z = 2.0;
  RenderSettings baked = file.render;
  baked.texture_evaluation = TextureEvaluation::kBaked;
  GlRenderer flyer(*platform_);
  Scene scene = file.scene;
  for (int frame = 0; frame < 40; ++frame) {  // at 30 Hz: west, east at 250 m/s, then faster
    scene.camera.position.x += frame < 10 ? -60.0 : frame < 30 ? 8.3 : 150.0;
    scene.camera.position.y += frame < 10 ? 2.0 : 5.1;
    flyer.renderFloat(scene, baked);
    if (frame > 0) {
      EXPECT_LT(flyer.lastFrameStats().layer_texels_baked, 256 * 160) << frame;
    }
  }
  const FloatImage carried = flyer.renderFloat(scene, baked);
  GlRenderer fresh(*platform_);
  expectClose(carried, fresh.renderFloat(scene, baked), 60.0, 0.01, "clipmap_strips");

  GlRenderer waiting(*platform_);
  RenderSettings automatic = file.render;
  ASSERT_EQ(automatic.texture_evaluation, TextureEvaluation::kAuto);
  waiting.renderFloat(scene, automatic);
  EXPECT_EQ(waiting.lastFrameStats().layer_texels_baked, 0);
  const int ring = LayerClipmaps::sizeFor(120) * LayerClipmaps::sizeFor(120);
  int frames = 1;
  while (frames < 100) {
    waiting.renderFloat(scene, automatic);
    ++frames;
    const FrameStats& stats = waiting.lastFrameStats();
    if (frames > 2 && stats.layer_texels_baked == 0) break;
    EXPECT_LE(stats.layer_texels_baked, frames == 2 ? 2 * ring : 2 * 160 * 120) << frames;
  }
  EXPECT_LT(frames, 100);
  expectClose(waiting.renderFloat(scene, automatic), carried, 60.0, 0.01, "clipmap_auto");
  GlRenderer streaming(*platform_);
  streaming.setContinuousView("flight");
  streaming.renderFloat(scene, automatic);
  EXPECT_GE(streaming.lastFrameStats().layer_texels_baked, ring);
  for (int frame = 0; frame < 6; ++frame) {
    streaming.renderFloat(scene, automatic);
    EXPECT_GT(streaming.lastFrameStats().layer_texels_baked, 0) << frame;
    EXPECT_EQ(streaming.lastFrameStats().programs_compiled, 0) << frame;
  }
}

// A layer bounded by a region (a turned rectangle with an edge band, one side of a front;
// MODEL.md section 11), drifted for ten minutes: exact against the one-sample reference, and
// the region really removes cover (less than half the unbounded layer's).
TEST_F(GlRenderTest, RegionBoundedLayerEqualsOneSampleReference) {
  SceneFile file = preset("stratus");
  file.scene.camera.orientation.pitch_deg = 60.0;
  file.scene.time_s = 600.0;
  CloudLayer& layer = file.scene.layers[0];
  layer.texture.drift_velocity = {12.0, -5.0};
  const FloatImage unbounded = renderer_->renderFloat(file.scene, pointSampled());
  Region& r = layer.region;
  const glm::dvec2 ahead = glm::dvec2(file.scene.camera.position) + glm::dvec2(0.0, 1500.0);
  r.centre = ahead - layer.texture.drift_velocity * file.scene.time_s;  // there at 600 s
  r.half_size = {1800.0, 1200.0};
  r.heading_deg = 30.0;
  r.edge_m = 400.0;
  r.side = 1;
  r.transition_m = 600.0;
  expectPointSampledEqual(*renderer_, file.scene, "point_region");
  const FloatImage bounded = renderer_->renderFloat(file.scene, pointSampled());
  double before = 0.0, after = 0.0;
  for (std::size_t i = 3; i < bounded.rgba.size(); i += 4)
    before += unbounded.rgba[i], after += bounded.rgba[i];
  EXPECT_GT(after, 0.02 * before);
  EXPECT_LT(after, 0.5 * before);
}

// A far deck's hole (CloudLayer::hole_radius_m) confines the deck to a strip along the horizon,
// and the sky passes leave it out of the rest of the screen: exact against the one-sample
// reference with the view rolled, from below and from above, fused and one pass a layer, with
// a layer without a hole on the same side. The views keep the horizon out of the frame (GL
// smooths the ground's edge over a pixel, the one-sample reference does not) and the hole's
// edge at 45 degrees across it. The deck shows beyond its hole.
TEST_F(GlRenderTest, FarDeckBeyondItsHoleEqualsOneSampleReference) {
  SceneFile file = preset("stratus");
  CloudLayer& deck = file.scene.layers[0];
  deck.threshold = 0.2;
  deck.hole_radius_m = 2000.0;  // the deck is 2 km above the ground and below the upper view
  deck.hole_band_m = 500.0;
  CloudLayer high = preset("cirrus").scene.layers[0];
  file.scene.layers.push_back(high);
  struct View {
    double z_m, pitch_deg, roll_deg;
  };
  for (const View& v : {View{2.0, 40.0, 15.0}, View{4000.0, -40.0, -15.0}}) {
    file.scene.camera.position.z = v.z_m;
    file.scene.camera.orientation.pitch_deg = v.pitch_deg;
    file.scene.camera.orientation.roll_deg = v.roll_deg;
    for (SkyPasses passes : {SkyPasses::kFused, SkyPasses::kMultipass}) {
      const std::string name = "far_deck_" + std::to_string(int(v.z_m)) +
                               (passes == SkyPasses::kFused ? "_fused" : "_multipass");
      RenderSettings settings = pointSampled();
      settings.sky_passes = passes;
      const FloatImage gl = renderer_->renderFloat(file.scene, settings);
      const FloatImage reference = renderReference(file.scene, {1, 0});
      float worst = 0.0f;
      for (std::size_t i = 0; i < gl.rgba.size(); ++i)
        worst = std::max(worst, std::abs(gl.rgba[i] - reference.rgba[i]));
      EXPECT_LE(worst, 2e-3f) << name;
      if (worst > 2e-3f) writeFailureImages(gl, reference, name);
    }
  }
  // Without the layer above: the deck covers part of the view.
  file.scene.layers.pop_back();
  const FloatImage level = renderer_->renderFloat(file.scene, pointSampled());
  Scene bare = file.scene;
  bare.layers.clear();
  const FloatImage sky = renderer_->renderFloat(bare, pointSampled());
  EXPECT_GT(compareImages(level, sky).max_abs, 0.05);
}

// The ground's cloud shadows (MODEL.md section 16) under a cumulus field seen from above, low
// and high sun: the GL's shadow map against the reference's exact sunlight per ground point.
// Of the ground either shadows (luminance under 0.65 of the unshadowed ground's), at least
// 90 % is shadowed by both, and the ratio to the unshadowed ground differs by 0.03 on average.
TEST_F(GlRenderTest, CloudShadowsMatchTheReference) {
  SceneFile file = preset("genus_cumulus", 200, 150);
  file.scene.camera.position = {0.0, 0.0, 6000.0};
  file.scene.camera.orientation.pitch_deg = -60.0;
  for (double elevation : {35.0, 70.0}) {
    file.scene.sun.elevation_deg = elevation;
    const std::string name = "cloud_shadows_" + std::to_string(int(elevation));
    const FloatImage gl = renderer_->renderFloat(file.scene, pointSampled());
    RenderSettings none = pointSampled();
    none.shadow_map_size = 0;
    const FloatImage unshadowed = renderer_->renderFloat(file.scene, none);
    const FloatImage reference = renderReference(file.scene, {1, 0});
    const ShadowAgreement forward = shadowAgreement(gl, reference, unshadowed);
    const ShadowAgreement backward = shadowAgreement(reference, gl, unshadowed);
    EXPECT_GT(forward.shadowed, 0.05) << name;  // the view shows shadows at all
    EXPECT_GE(forward.agreement, 0.9) << name;
    EXPECT_GE(backward.agreement, 0.9) << name;
    EXPECT_LE(forward.mean_ratio_difference, 0.03) << name;
    if (forward.agreement < 0.9 || backward.agreement < 0.9 || forward.mean_ratio_difference > 0.03)
      writeFailureImages(gl, reference, name);
  }
}

// Heaps' shadows on a deck below them (MODEL.md section 16, "planes under heaps"): the cumulus
// field over an opaque deck at 600 m, from above, so that every shadow in view falls on the
// deck: the GL's map read where the sun's ray through the deck lands, against the reference's
// exact sunlight there. Over the pixels no heap covers (in a render without the deck), a pixel
// is shadowed where its luminance is under 0.65 of the unshadowed GL's (kShadowedRatio, as
// shadowAgreement counts the ground's): at least 90 % of either's shadowed pixels are the
// other's, and the ratios differ by 0.03 on average.
TEST_F(GlRenderTest, HeapShadowsFallOnADeckBelowThem) {
  SceneFile file = preset("genus_cumulus", 200, 150);
  file.scene.camera.position = {0.0, 0.0, 6000.0};
  file.scene.camera.orientation.pitch_deg = -60.0;
  const FloatImage heaps = renderer_->renderFloat(file.scene, pointSampled());
  CloudLayer deck = preset("genus_stratocumulus").scene.layers.at(0);
  deck.altitude_m = 600.0;
  deck.threshold = -0.5;  // opaque everywhere: the ground is hidden
  deck.transition = 0.1;
  file.scene.layers.push_back(deck);
  const FloatImage gl = renderer_->renderFloat(file.scene, pointSampled());
  RenderSettings none = pointSampled();
  none.shadow_map_size = 0;
  const FloatImage unshadowed = renderer_->renderFloat(file.scene, none);
  const FloatImage reference = renderReference(file.scene, {1, 0});
  auto luminance = [](const FloatImage& image, std::size_t i) {
    const float* p = &image.rgba[4 * i];
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
  };
  int open = 0, gl_shadowed = 0, reference_shadowed = 0, both = 0;
  double difference = 0.0;
  for (std::size_t i = 0; i < std::size_t(gl.width) * gl.height; ++i) {
    if (heaps.rgba[4 * i + 3] > 0.01f) continue;  // a heap in front of the deck
    const double lit = luminance(unshadowed, i);
    const double a = luminance(gl, i) / lit, r = luminance(reference, i) / lit;
    ++open;
    difference += std::abs(a - r);
    gl_shadowed += a < kShadowedRatio;
    reference_shadowed += r < kShadowedRatio;
    both += a < kShadowedRatio && r < kShadowedRatio;
  }
  ASSERT_GT(open, 0);
  EXPECT_GT(double(gl_shadowed) / open, 0.05);  // the deck shows shadows at all
  EXPECT_GE(double(both) / std::max(gl_shadowed, 1), 0.9);
  EXPECT_GE(double(both) / std::max(reference_shadowed, 1), 0.9);
  EXPECT_LE(difference / open, 0.03);
  if (double(both) / std::max(gl_shadowed, 1) < 0.9 ||
      double(both) / std::max(reference_shadowed, 1) < 0.9 || difference / open > 0.03)
    writeFailureImages(gl, reference, "heap_shadows_on_a_deck");
}

// Precipitation (MODEL.md section 17) under a nimbostratus deck, as slabs: rain from the base
// down, snow, and CIGI's dust layer of its own base and top, equal to the one-sample
// reference; without it the view is another.
TEST_F(GlRenderTest, PrecipitationEqualsOneSampleReference) {
  SceneFile file = preset("rain", 160, 90);
  file.scene.targets.clear();  // their edges are the target pass's, tested on their own
  WeatherLayer& deck = file.scene.weather.at({1, std::nullopt});
  const Scene dry = [&] {
    Scene s = file.scene;
    s.weather.at({1, std::nullopt}).precipitation = {};
    return s;
  }();
  WeatherLayer dust;
  dust.base_m = 100.0;
  dust.thickness_m = 400.0;
  dust.precipitation = {PrecipitationKind::kDust, 0.0, 800.0};
  struct Case {
    const char* name;
    Precipitation deck;
    bool dust;
  };
  for (const Case& c : {Case{"rain", deck.precipitation, false},
                        Case{"snow", {PrecipitationKind::kSnow, 1.0, 0.0}, false},
                        Case{"rain_and_dust", deck.precipitation, true}}) {
    Scene scene = file.scene;
    scene.weather.at({1, std::nullopt}).precipitation = c.deck;
    if (c.dust) scene.weather[{9, std::nullopt}] = dust;
    const FloatImage gl = renderer_->renderFloat(scene, pointSampled());
    const FloatImage reference = renderReference(scene, {1, 0});
    float worst = 0.0f;
    for (std::size_t i = 0; i < gl.rgba.size(); ++i)
      worst = std::max(worst, std::abs(gl.rgba[i] - reference.rgba[i]));
    EXPECT_LE(worst, 2e-3f) << c.name;
    if (worst > 2e-3f) writeFailureImages(gl, reference, std::string("precipitation_") + c.name);
    EXPECT_GT(compareImages(gl, renderer_->renderFloat(dry, pointSampled())).max_abs, 0.05)
        << c.name;
  }
}

// Rain shafts (MODEL.md section 17) in front of the camera, one across the view's middle and
// one it stands in, over the ground and against the sky: equal to the one-sample reference,
// and a target behind them less visible by their optical depth in both.
TEST_F(GlRenderTest, RainShaftsEqualOneSampleReference) {
  SceneFile file = preset("rain", 160, 90);
  file.scene.weather.clear();
  file.scene.layers.clear();
  const Scene dry = file.scene;
  const glm::dvec2 eye(file.scene.camera.position);
  file.scene.rain_shafts = {{eye + glm::dvec2(300.0, 2500.0), 700.0, 900.0, 3e-3,
                             precipitationColour(PrecipitationKind::kRain)},
                            {eye + glm::dvec2(-200.0, 100.0), 400.0, 1500.0, 1e-3,
                             precipitationColour(PrecipitationKind::kSnow)}};
  Scene scene = file.scene;
  scene.targets.clear();
  const FloatImage gl = renderer_->renderFloat(scene, pointSampled());
  const FloatImage reference = renderReference(scene, {1, 0});
  // Every pixel but those of the horizon's row, where ground and sky meet inside the pixel.
  const ViewBasis basis = viewBasis(scene.camera);
  float worst = 0.0f;
  for (int y = 0; y < scene.camera.height; ++y) {
    if (rayDirection(basis, scene.camera, 0.5, y).z *
            rayDirection(basis, scene.camera, 0.5, y + 1).z <=
        0.0)
      continue;
    for (std::size_t i = std::size_t(y) * scene.camera.width * 4;
         i < std::size_t(y + 1) * scene.camera.width * 4; ++i)
      worst = std::max(worst, std::abs(gl.rgba[i] - reference.rgba[i]));
  }
  EXPECT_LE(worst, 2e-3f);
  if (worst > 2e-3f) writeFailureImages(gl, reference, "rain_shafts");
  Scene without = dry;
  without.targets.clear();
  EXPECT_GT(compareImages(gl, renderer_->renderFloat(without, pointSampled())).max_abs, 0.05);
  FrameRequest request;
  request.channels = {Channel::kVisibility, Channel::kObjectId, Channel::kDepth};
  const Frame gl_frame = renderer_->renderFrame(file.scene, pointSampled(), request);
  const Frame reference_frame = renderReferenceFrame(file.scene, {1, 0}, request);
  for (const Frame* frame : {&gl_frame, &reference_frame}) {
    int dimmed = 0;
    for (int y = 0; y < file.scene.camera.height; ++y)
      for (int x = 0; x < file.scene.camera.width; ++x) {
        const std::size_t i = std::size_t(y) * file.scene.camera.width + x;
        if (frame->object_id[i] == 0) continue;
        const glm::dvec3 d =
            glm::normalize(rayDirection(basis, file.scene.camera, x + 0.5, y + 0.5));
        double tau = 0.0;
        for (const RainShaft& s : file.scene.rain_shafts)
          tau += shaftOpticalDepth(s, file.scene.camera.position, d, frame->depth[i]);
        EXPECT_NEAR(frame->visibility[i], std::exp(-tau), 2e-3) << "pixel " << i;
        dimmed += tau > 0.1;
      }
    EXPECT_GT(dimmed, 0);
  }
}

// Issue 63, item 1: a frame is planned once whatever channels it draws. The GL's colour passes,
// its visibility's rain and the labels it traces on the CPU read one FramePlan, so labels see
// the clouds, heaps and shafts the colour drew; the reference plans once too.
TEST_F(GlRenderTest, AFrameIsPlannedOnce) {
  for (const char* name : {"storm", "sea_search"}) {
    const SceneFile file = preset(name, 96, 64);
    FrameRequest request;
    request.channels = {Channel::kColour,     Channel::kCoverage, Channel::kVisibility,
                        Channel::kCloudDepth, Channel::kLwir,     Channel::kGlint,
                        Channel::kDepth,      Channel::kObjectId};
    const std::uint64_t before = framePlansMade();
    const Frame gl = renderer_->renderFrame(file.scene, pointSampled(), request);
    EXPECT_EQ(framePlansMade() - before, 1u) << name;
    EXPECT_EQ(gl.cloud_depth.size(), std::size_t(96 * 64)) << name;
    const std::uint64_t between = framePlansMade();
    const Frame reference = renderReferenceFrame(file.scene, {1, 0}, request);
    EXPECT_EQ(framePlansMade() - between, 1u) << name;
    EXPECT_EQ(reference.lwir.size(), std::size_t(96 * 64)) << name;
  }
}

// The visibility channel over a target behind rain (MODEL.md section 17): the rain's
// transmittance to it, exp(-sigma depth), in both renderers; the far boat is less visible.
TEST_F(GlRenderTest, TargetsBehindRainAreLessVisible) {
  const SceneFile file = preset("rain", 320, 180);
  FrameRequest request;
  request.channels = {Channel::kVisibility, Channel::kObjectId, Channel::kDepth};
  const Frame gl = renderer_->renderFrame(file.scene, pointSampled(), request);
  const Frame reference = renderReferenceFrame(file.scene, {1, 0}, request);
  const double sigma =
      precipitationExtinction(file.scene.weather.at({1, std::nullopt}).precipitation);
  for (const Frame* frame : {&gl, &reference}) {
    double mean[3] = {0.0, 0.0, 0.0};
    int pixels[3] = {0, 0, 0};
    for (std::size_t i = 0; i < frame->visibility.size(); ++i) {
      const int id = int(frame->object_id[i]);
      if (id == 0) continue;
      const double expected = std::exp(-sigma * frame->depth[i]);
      EXPECT_NEAR(frame->visibility[i], expected, 2e-3) << "pixel " << i;
      mean[id] += frame->visibility[i];
      ++pixels[id];
    }
    ASSERT_GT(pixels[1], 0);
    ASSERT_GT(pixels[2], 0);
    EXPECT_GT(mean[1] / pixels[1], 4.0 * mean[2] / pixels[2]);  // about 0.27 against 0.03
  }
}

// A deck below the camera and a layer above it, seen from between them: exact against the
// one-sample reference, and filtered against the 4x4 reference. Seen from above at a slant,
// the deck's full plaid is resolved by the 4x4 reference only partly where GL drops its
// high terms (measured 30.8 dB).
TEST_F(GlRenderTest, LayersAboveAndBelowTheCamera) {
  SceneFile file = preset("stratus");
  file.scene.layers[0].texture.gardner.fx1 = 8e-4;
  file.scene.layers[0].texture.gardner.fy1 = 6e-4;
  file.scene.camera.position.z = 5000.0;
  file.scene.camera.orientation.pitch_deg = -26.0;
  CloudLayer high = file.scene.layers[0];
  high.altitude_m = 9000.0;
  high.texture.seed = 5;
  file.scene.layers.push_back(high);
  expectClose(renderer_->renderFloat(file.scene, file.render),
              renderReference(file.scene, file.reference()), 29.0, 0.3, "deck");
  for (double pitch : {-50.0, 50.0}) {
    file.scene.camera.orientation.pitch_deg = pitch;
    expectPointSampledEqual(*renderer_, file.scene, "deck_point");
  }
}

TEST_F(GlRenderTest, NoiseSourcesMatchReference) {
  for (TextureSource source : {TextureSource::kPerlin, TextureSource::kDiamondSquare}) {
    SceneFile file = preset("stratus");
    CloudLayer& layer = file.scene.layers[0];
    layer.texture.source = source;
    layer.texture.table.tile_size_m = {6000.0, 6000.0};
    layer.threshold = 0.4;
    layer.transition = 0.3;
    const FloatImage reference = renderReference(file.scene, file.reference());
    expectClose(renderer_->renderFloat(file.scene, file.render), reference, 38.0, 0.25,
                std::string(textureSourceName(source)));
  }
}

// D = 0: hard cloud edges, one sample per pixel in GL and 16 in the reference, so edge
// pixels differ by up to the cloud-sky contrast (measured 28.3 dB at 160x120).
TEST_F(GlRenderTest, HardThresholdMatchesReference) {
  SceneFile file = preset("cirrus");
  file.scene.layers[0].transition = 0.0;
  const FloatImage reference = renderReference(file.scene, file.reference());
  expectClose(renderer_->renderFloat(file.scene, file.render), reference, 26.0, 0.6, "hard");
}

// The precision rule of MODEL.md section 2: shifted by whole texture periods to about 100 km from
// the origin, a layer must look as it does at the origin.
TEST_F(GlRenderTest, LayerFarFromOriginLooksAsAtOrigin) {
  for (const char* name : {"cirrus", "overcast"}) {
    SceneFile file = preset(name);
    const FloatImage near_origin = renderer_->renderFloat(file.scene, file.render);
    const LayerTexture texture(file.scene.layers[0].texture);
    const glm::dvec2 period = texture.period();
    file.scene.camera.position.x += std::round(1.0e5 / period.x) * period.x;
    file.scene.camera.position.y -= std::round(1.0e5 / period.y) * period.y;
    ASSERT_GT(std::abs(file.scene.camera.position.x), 5.0e4);
    expectClose(renderer_->renderFloat(file.scene, file.render), near_origin, 55.0, 0.02,
                std::string("far_") + name);
    RenderSettings procedural = file.render;
    procedural.texture_evaluation = TextureEvaluation::kProcedural;
    expectClose(renderer_->renderFloat(file.scene, procedural), near_origin, 45.0, 0.05,
                std::string("far_procedural_") + name);
  }
}

// Drift: the layer at time t equals the still layer seen from a camera moved against it.
TEST_F(GlRenderTest, DriftMovesTheLayerWithTheWind) {
  SceneFile file = preset("cirrus");
  const double t = 5400.0;
  const glm::dvec2 v = file.scene.layers[0].texture.drift_velocity;
  file.scene.time_s = t;
  const FloatImage drifted = renderer_->renderFloat(file.scene, file.render);
  file.scene.time_s = 0.0;
  file.scene.camera.position -= glm::dvec3(v * t, 0.0);
  expectClose(drifted, renderer_->renderFloat(file.scene, file.render), 50.0, 0.05, "drift");
}

TEST_F(GlRenderTest, Srgb8TargetMatchesFloatTarget) {
  const SceneFile file = preset("ground_fog");
  const Srgb8Image bytes = renderer_->renderSrgb8(file.scene, file.render);
  const Srgb8Image expected = toSrgb8(renderer_->renderFloat(file.scene, file.render));
  ASSERT_TRUE(bytes.bottom_up);
  int worst = 0;
  for (int y = 0; y < bytes.height; ++y)
    for (int x = 0; x < bytes.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const int a = bytes.rgba[(std::size_t(bytes.height - 1 - y) * bytes.width + x) * 4 + c];
        const int b = expected.rgba[(std::size_t(y) * bytes.width + x) * 4 + c];
        worst = std::max(worst, std::abs(a - b));
      }
  EXPECT_LE(worst, 2);
}

// Stiff and extreme views and parameters: finite pixels, colours in range, coverage in [0, 1].
TEST_F(GlRenderTest, ExtremeCasesStayFinite) {
  struct Case {
    const char* name;
    void (*edit)(Scene&);
  };
  const Case cases[] = {
      {"zenith", [](Scene& s) { s.camera.orientation.pitch_deg = 90.0; }},
      {"nadir", [](Scene& s) { s.camera.orientation.pitch_deg = -90.0; }},
      {"horizon", [](Scene& s) { s.camera.orientation.pitch_deg = 0.0; }},
      {"wide", [](Scene& s) { s.camera.vfov_deg = 179.0; }},
      {"narrow", [](Scene& s) { s.camera.vfov_deg = 0.01; }},
      {"rolled", [](Scene& s) { s.camera.orientation.roll_deg = 180.0; }},
      {"on the ground", [](Scene& s) { s.camera.position.z = 0.0; }},
      {"in the layer", [](Scene& s) { s.camera.position.z = s.layers[0].altitude_m; }},
      {"just under", [](Scene& s) { s.camera.position.z = s.layers[0].altitude_m - 1e-6; }},
      {"far away",
       [](Scene& s) {
         s.camera.position = {9.9e7, -9.9e7, 1.0e5};
       }},
      {"hour drift", [](Scene& s) { s.time_s = 1.0e9; }},
      {"tiny D", [](Scene& s) { s.layers[0].transition = 1e-30; }},
      {"eight terms", [](Scene& s) { s.layers[0].texture.gardner.terms = 8; }},
      {"huge T0", [](Scene& s) { s.layers[0].texture.gardner.t0 = 10.0; }},
      {"high freq", [](Scene& s) { s.layers[0].texture.gardner.fx1 = 10.0; }},
      {"low freq", [](Scene& s) { s.layers[0].texture.gardner.fy1 = 1e-7; }},
      {"dense fog",
       [](Scene& s) {
         s.fog = Fog{1.0e5, 1.0, {0.5, 0.5, 0.5}};
       }},
  };
  SceneFile file = preset("cirrus", 64, 48);
  for (const Case& c : cases) {
    Scene scene = file.scene;
    c.edit(scene);
    for (SkyPasses passes : {SkyPasses::kFused, SkyPasses::kMultipass})
      for (TextureEvaluation evaluation :
           {TextureEvaluation::kBaked, TextureEvaluation::kProcedural}) {
        RenderSettings settings;
        settings.sky_passes = passes;
        settings.texture_evaluation = evaluation;
        const FloatImage image = renderer_->renderFloat(scene, settings);
        for (std::size_t i = 0; i < image.rgba.size(); ++i) {
          ASSERT_TRUE(std::isfinite(image.rgba[i])) << c.name << " at " << i;
          ASSERT_GE(image.rgba[i], 0.0f) << c.name;
          ASSERT_LE(image.rgba[i], i % 4 == 3 ? 1.0f : 100.0f) << c.name;
        }
      }
  }
}

// Both back ends create a 4.5 core context and render the same image.
TEST(GlPlatform, EglAndOsmesaRenderTheSameImage) {
  SceneFile file;
  ASSERT_EQ(loadSceneFile(NEPHELE_SOURCE_DIR "/config/scenes/stratus.toml", file), "");
  file.scene.camera.width = 96;
  file.scene.camera.height = 64;
  FloatImage images[2];
  const GlBackend backends[2] = {GlBackend::kEgl, GlBackend::kOsmesa};
  for (int i = 0; i < 2; ++i) {
    std::string error;
    auto platform = createGlPlatform(backends[i], error);
    ASSERT_NE(platform, nullptr) << error;
    EXPECT_EQ(std::string(platform->backendName()).substr(0, 3), i == 0 ? "egl" : "osm");
    EXPECT_FALSE(platform->renderer().empty());
    EXPECT_NE(platform->version().find("4.5"), std::string::npos) << platform->version();
    GlRenderer renderer(*platform);
    images[i] = renderer.renderFloat(file.scene, file.render);
  }
  const ImageError e = compareImages(images[0], images[1]);
  EXPECT_GE(e.psnr_db, 60.0);
}

// The sea (MODEL.md section 18) under an altocumulus deck, sun ahead: equal to the one-sample
// reference but for what the GL's probe of the mirrored sky resolves (half the view's
// resolution, bilinear), and mirroring the deck in both; its pixels are the sea's class, and
// the glint channel shows the sun's reflection.
TEST_F(GlRenderTest, SeaEqualsOneSampleReference) {
  SceneFile file = preset("sea_search", 160, 90);
  Scene scene = file.scene;
  scene.targets.clear();
  scene.fields.clear();  // the cumulus heaps; the altocumulus deck stays
  scene.haze.reset();
  Scene cleared = scene;  // the same sea, with nothing to mirror but the sky
  cleared.layers.clear();
  const ViewBasis basis = viewBasis(scene.camera);
  // Pixels wholly below the horizon.
  auto sea = [&](int x, int y) { return rayDirection(basis, scene.camera, x + 0.5, y).z < 0.0; };
  const int w = scene.camera.width, h = scene.camera.height;
  auto meanDifference = [&](const FloatImage& a, const FloatImage& b) {
    double sum = 0.0;
    int n = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        if (!sea(x, y)) continue;
        const std::size_t i = (std::size_t(y) * w + x) * 4;
        for (int c = 0; c < 3; ++c)
          sum += std::min(std::abs(a.rgba[i + c] - b.rgba[i + c]), 1.0f);  // glints may exceed 1
        n += 3;
      }
    return sum / n;
  };
  const FloatImage gl = renderer_->renderFloat(scene, pointSampled());
  const FloatImage reference = renderReference(scene, {1, 0});
  EXPECT_EQ(outOfRange(gl), 0);
  const double error = meanDifference(gl, reference);
  const double mirrored = meanDifference(reference, renderReference(cleared, {1, 0}));
  std::printf("sea: GL against reference %.4f; the deck's reflection %.4f\n", error, mirrored);
  EXPECT_LE(error, 0.02);     // 0.007 with a probe twice the view's width
  EXPECT_GE(mirrored, 0.02);  // the deck is seen in the sea, and the bound above resolves it
  if (error > 0.02) writeFailureImages(gl, reference, "sea");

  const FrameRequest request(ChannelSet{Channel::kObjectId, Channel::kGlint});
  const Frame gl_frame = renderer_->renderFrame(scene, pointSampled(), request);
  const Frame ref_frame = renderReferenceFrame(scene, {1, 0}, request);
  int sea_pixels = 0, glinting = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      const float expected = sea(x, y) ? kSeaObjectId : 0.0f;
      if (sea(x, y) && rayDirection(basis, scene.camera, x + 0.5, y + 1.0).z < 0.0) {
        EXPECT_EQ(gl_frame.object_id[i], expected) << x << "," << y;
        EXPECT_EQ(ref_frame.object_id[i], expected) << x << "," << y;
        ++sea_pixels;
      }
      glinting += ref_frame.glint[i] > 0.1f;
      EXPECT_NEAR(gl_frame.glint[i], ref_frame.glint[i], 1e-6f);
    }
  EXPECT_GT(sea_pixels, w * h / 3);
  EXPECT_GT(glinting, 20);
}

// The sea at the extremes: a camera a centimetre above it looking straight down and one at
// 20 km looking level, no wind and the strongest wind allowed, the sun just below the horizon
// and overhead, a host's steepest short wave train: finite, non-negative light in both
// renderers.
TEST_F(GlRenderTest, SeaAtTheExtremesStaysFinite) {
  SceneFile file = preset("sea_search", 64, 36);
  Scene base = file.scene;
  base.fields.clear();
  for (double wind : {0.0, 200.0})
    for (double sun : {-5.0, 89.0})
      for (int view = 0; view < 2; ++view) {
        Scene scene = base;
        scene.sea->wind = {wind, 0.0};
        scene.sea->trains = {{3, 30.0, 1.0, 0.0, 45.0, 0.0}};
        scene.sun.elevation_deg = sun;
        scene.camera.position.z = view == 0 ? 0.01 : 20000.0;
        scene.camera.orientation.pitch_deg = view == 0 ? -90.0 : 0.0;
        const std::string name = "wind " + std::to_string(wind) + ", sun " + std::to_string(sun) +
                                 ", view " + std::to_string(view);
        EXPECT_EQ(outOfRange(renderer_->renderFloat(scene, pointSampled())), 0) << name;
        EXPECT_EQ(outOfRange(renderReference(scene, {1, 0})), 0) << name;
      }
}

}  // namespace
}  // namespace nephele
