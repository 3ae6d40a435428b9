// Frame channels (renderer/frame.h) from both back ends against independent computations:
// depth of a box target and of the ground by ray-slab and ray-plane intersection; cloud depth
// of one opaque sphere against its analytic entry distance; visibility of a target behind a
// layer against the layer's translucence at the ray's crossing; GL against the reference for
// every channel.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <utility>

#include "renderer/renderer.h"
#include "world/shading.h"
#include "world/textures/layer_texture.h"

namespace nephele {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

struct ChannelsTestScenes {
  // Looking north, level, from 100 m up.
  static Scene level(int width = 96, int height = 72) {
    Scene scene;
    scene.camera.position = {0.0, 0.0, 100.0};
    scene.camera.vfov_deg = 40.0;
    scene.camera.width = width;
    scene.camera.height = height;
    return scene;
  }
};

class ChannelsTest : public ::testing::TestWithParam<RendererKind>, public ChannelsTestScenes {
 protected:
  static std::unique_ptr<Renderer> makeRenderer(RendererKind kind) {
    RendererOptions options;
    options.kind = kind;
    options.render.reference_samples = 1;  // labels and colour from the centre ray
    std::string error;
    auto renderer = createRenderer(options, error);
    EXPECT_NE(renderer, nullptr) << error;
    return renderer;
  }

  static glm::dvec3 centreRay(const Scene& scene, int x, int y) {
    return glm::normalize(rayDirection(viewBasis(scene.camera), scene.camera, x + 0.5, y + 0.5));
  }
};

// Ray and axis-aligned box, written out again here (slabs): entry distance or infinity.
double boxEntry(glm::dvec3 lo, glm::dvec3 hi, glm::dvec3 o, glm::dvec3 d) {
  double enter = 0.0, leave = kInf;
  for (int a = 0; a < 3; ++a) {
    const double t0 = (lo[a] - o[a]) / d[a], t1 = (hi[a] - o[a]) / d[a];
    enter = std::max(enter, std::min(t0, t1));
    leave = std::min(leave, std::max(t0, t1));
  }
  return enter < leave ? enter : kInf;
}

TEST_P(ChannelsTest, DepthAndObjectIdOfABoxAndTheGround) {
  Scene scene = level();
  Target box;
  box.shape = TargetShape::kBox;
  box.centre = {10.0, 400.0, 95.0};
  box.size = {20.0, 15.0, 12.0};
  scene.targets.push_back(box);
  const auto renderer = makeRenderer(GetParam());
  const Frame frame = renderer->render(
      scene, {ChannelSet{Channel::kDepth, Channel::kObjectId, Channel::kCloudDepth}});
  ASSERT_EQ(frame.depth.size(), std::size_t(96 * 72));
  int box_pixels = 0, id_mismatch = 0, depth_mismatch = 0;
  for (int y = 0; y < 72; ++y)
    for (int x = 0; x < 96; ++x) {
      const glm::dvec3 d = centreRay(scene, x, y);
      const double ground = d.z < 0.0 ? 100.0 / -d.z : kInf;
      const double target =
          boxEntry(box.centre - box.size, box.centre + box.size, scene.camera.position, d);
      const double expected = std::min(ground, target);
      const std::size_t i = std::size_t(y) * 96 + x;
      const int expected_id = target < ground ? 1 : 0;
      box_pixels += expected_id;
      id_mismatch += int(frame.object_id[i]) != expected_id;
      if (std::isinf(expected))
        depth_mismatch += !std::isinf(frame.depth[i]);
      else
        depth_mismatch += !(std::abs(frame.depth[i] - expected) <= 1e-4 * expected + 1e-3);
      EXPECT_TRUE(std::isinf(frame.cloud_depth[i])) << "no clouds, yet a cloud depth";
    }
  EXPECT_GT(box_pixels, 50);
  // A rasteriser and a ray may disagree on pixels whose centre grazes an edge.
  EXPECT_LE(id_mismatch, 4) << "of " << box_pixels << " box pixels";
  EXPECT_LE(depth_mismatch, 4);
}

TEST_P(ChannelsTest, CloudDepthOfAnOpaqueSphereIsItsEntryDistance) {
  Scene scene = level();
  scene.camera.position.z = 400.0;  // the ground hides no part of the sphere
  EllipsoidCloud cloud;
  cloud.threshold_centre = cloud.threshold_limb = -2.0;  // opaque everywhere
  cloud.transition = 0.0;
  const glm::dvec3 centre{0.0, 2000.0, 400.0};
  const double radius = 300.0;
  cloud.ellipsoids.push_back({{radius, radius, radius}, centre, {}});
  scene.clouds.push_back(cloud);
  const auto renderer = makeRenderer(GetParam());
  const Frame frame = renderer->render(
      scene, {ChannelSet{Channel::kCloudDepth, Channel::kCoverage, Channel::kVisibility}});
  int inside = 0, wrong = 0;
  for (int y = 0; y < 72; ++y)
    for (int x = 0; x < 96; ++x) {
      const glm::dvec3 d = centreRay(scene, x, y);
      const glm::dvec3 oc = scene.camera.position - centre;
      const double b = glm::dot(oc, d), c = glm::dot(oc, oc) - radius * radius;
      const double disc = b * b - c;
      const double entry = disc > 0.0 ? -b - std::sqrt(disc) : kInf;
      const std::size_t i = std::size_t(y) * 96 + x;
      const float got = frame.cloud_depth[i];
      // Pixels whose centre ray grazes the limb (within a metre of it) may go either way.
      if (disc > 0.0 && disc < 2.0 * radius) continue;
      inside += std::isfinite(entry);
      wrong += std::isfinite(entry) ? !(std::abs(got - entry) <= 1e-3 * entry) : !std::isinf(got);
      if (std::isfinite(entry)) {
        EXPECT_NEAR(frame.visibility[i], 0.0f, 1e-3f);
        EXPECT_NEAR(frame.plane(Channel::kCoverage)[i], 1.0f, 1e-3f);
      }
    }
  EXPECT_GT(inside, 200);
  EXPECT_EQ(wrong, 0);
}

// A wide box target behind a translucent layer at 250 m, seen from below.
Scene targetBehindLayer() {
  Scene scene = ChannelsTestScenes::level();
  scene.camera.orientation.pitch_deg = 20.0;
  Target box;
  box.centre = {0.0, 600.0, 330.0};
  box.size = {150.0, 10.0, 120.0};
  scene.targets.push_back(box);
  CloudLayer layer;
  layer.altitude_m = 250.0;
  layer.threshold = 0.2;
  layer.transition = 0.8;  // translucent throughout
  layer.texture.gardner.fx1 = layer.texture.gardner.fy1 = 0.01;
  scene.layers.push_back(layer);
  return scene;
}

TEST_P(ChannelsTest, VisibilityBehindALayerIsItsTranslucence) {
  const Scene scene = targetBehindLayer();
  const Target& box = scene.targets[0];
  const CloudLayer& layer = scene.layers[0];
  const LayerTexture texture(layer.texture);
  const auto renderer = makeRenderer(GetParam());
  const Frame frame =
      renderer->render(scene, {ChannelSet{Channel::kVisibility, Channel::kObjectId}});
  int target_pixels = 0, behind = 0;
  double worst = 0.0, sum = 0.0;
  for (int y = 0; y < 72; ++y)
    for (int x = 0; x < 96; ++x) {
      const std::size_t i = std::size_t(y) * 96 + x;
      if (frame.object_id[i] != 1.0f) continue;
      ++target_pixels;
      const glm::dvec3 d = centreRay(scene, x, y);
      const double s = (layer.altitude_m - 100.0) / d.z;
      const double hit =
          boxEntry(box.centre - box.size, box.centre + box.size, scene.camera.position, d);
      double expected = 1.0;
      if (s > 0.0 && s < hit) {
        ++behind;
        const glm::dvec3 p = scene.camera.position + s * d;
        expected =
            skyPlaneTranslucence(texture.value({p.x, p.y}, 0.0), layer.threshold, layer.transition);
      }
      worst = std::max(worst, std::abs(frame.visibility[i] - expected));
      sum += std::abs(frame.visibility[i] - expected);
    }
  EXPECT_GT(target_pixels, 300);
  EXPECT_GT(behind, 100);
  // GL bakes the texture and fades the terms finer than a pixel (ACCURACY.md, term_filter):
  // a mean error of about 0.01 and a few pixels up to 0.07 here.
  const bool gl = GetParam() == RendererKind::kGl;
  EXPECT_LE(worst, gl ? 0.1 : 1e-5);
  EXPECT_LE(sum / target_pixels, gl ? 0.015 : 1e-6);
}

// The infrared band (MODEL.md section 12): a target behind a translucent layer shows
// alpha B(T_layer) + (1 - alpha) B(T_target), with alpha the layer's opacity at the crossing
// and T_layer the ISA temperature of its altitude; the clear sky is colder at the zenith.
TEST_P(ChannelsTest, LwirBehindALayerMixesTheLayerAndTheTarget) {
  const Scene scene = targetBehindLayer();
  const Target& box = scene.targets[0];
  const CloudLayer& layer = scene.layers[0];
  const LayerTexture texture(layer.texture);
  FrameRequest request(ChannelSet{Channel::kLwir, Channel::kObjectId});
  request.infrared.target_temperatures = {330.0};
  const InfraredModel& ir = request.infrared;
  const auto renderer = makeRenderer(GetParam());
  const Frame frame = renderer->render(scene, request);
  const double target = bandRadiance(ir, 330.0);
  const double cloud = bandRadiance(ir, airTemperature(ir, 250.0));
  EXPECT_NEAR(airTemperature(ir, 250.0), 288.15 - 1.625, 1e-9);
  int checked = 0;
  for (int y = 0; y < 72; ++y)
    for (int x = 0; x < 96; ++x) {
      const std::size_t i = std::size_t(y) * 96 + x;
      if (frame.object_id[i] != 1.0f) continue;
      const glm::dvec3 d = centreRay(scene, x, y);
      const double s = (layer.altitude_m - 100.0) / d.z;
      const glm::dvec3 p = scene.camera.position + s * d;
      const double alpha =
          s < boxEntry(box.centre - box.size, box.centre + box.size, scene.camera.position, d)
              ? 1.0 - skyPlaneTranslucence(texture.value({p.x, p.y}, 0.0), layer.threshold,
                                           layer.transition)
              : 0.0;
      EXPECT_NEAR(frame.lwir[i], alpha * cloud + (1.0 - alpha) * target, 1e-4 * target);
      ++checked;
    }
  EXPECT_GT(checked, 300);
  // Sky: the top row looks 56 degrees up, the row at the horizon 0; each pixel is at most the
  // air's radiance at the camera and the zenith is coldest.
  Scene clear = level();
  clear.camera.orientation.pitch_deg = 60.0;
  const Frame sky = renderer->render(clear, FrameRequest(ChannelSet{Channel::kLwir}));
  const double air = bandRadiance(ir, airTemperature(ir, 100.0));
  for (int y = 1; y < 72; ++y) {
    EXPECT_LT(sky.lwir[std::size_t(y - 1) * 96 + 48], sky.lwir[std::size_t(y) * 96 + 48]);
    EXPECT_LT(sky.lwir[std::size_t(y) * 96 + 48], air);
  }
}

INSTANTIATE_TEST_SUITE_P(BothBackEnds, ChannelsTest,
                         ::testing::Values(RendererKind::kGl, RendererKind::kReference),
                         [](const auto& info) {
                           return info.param == RendererKind::kGl ? "Gl" : "Reference";
                         });

// Every channel of a scene with clouds, a mesh-free target pair and a layer: GL against the
// reference (one sample per pixel), per channel.
TEST(ChannelsCompare, GlMatchesReferenceOnEveryChannel) {
  Scene scene;
  scene.camera.position = {0.0, -1500.0, 900.0};
  scene.camera.orientation.pitch_deg = -5.0;
  scene.camera.vfov_deg = 30.0;
  scene.camera.width = 120;
  scene.camera.height = 90;
  EllipsoidCloud cloud;
  cloud.texture.seed = 5;
  cloud.ellipsoids.push_back({{300.0, 250.0, 200.0}, {0.0, 0.0, 900.0}, {}});
  cloud.ellipsoids.push_back({{200.0, 200.0, 150.0}, {250.0, 100.0, 1000.0}, {}});
  scene.clouds.push_back(cloud);
  Target a, b;
  a.centre = {-150.0, -400.0, 880.0};
  a.size = {30.0, 10.0, 8.0};
  b.shape = TargetShape::kEllipsoid;
  b.centre = {120.0, 500.0, 850.0};
  b.size = {40.0, 40.0, 20.0};
  scene.targets = {a, b};
  const FrameRequest all{ChannelSet::all()};
  RendererOptions options;
  options.render.reference_samples = 1;
  std::string error;
  const auto gl = createRenderer(options, error);
  ASSERT_NE(gl, nullptr) << error;
  options.kind = RendererKind::kReference;
  const auto reference = createRenderer(options, error);
  const Frame g = gl->render(scene, all), r = reference->render(scene, all);
  for (const ChannelInfo& info : kChannels) {
    // Colour is compared as its three planes in a row.
    auto planeOf = [&](const Frame& f) {
      if (info.channel != Channel::kColour) return f.plane(info.channel);
      std::vector<float> rgb;
      for (std::size_t i = 0; i < f.colour.rgba.size(); ++i)
        if (i % 4 != 3) rgb.push_back(f.colour.rgba[i]);
      return rgb;
    };
    const std::vector<float> pg = planeOf(g), pr = planeOf(r);
    ASSERT_FALSE(pg.empty()) << info.name;
    ASSERT_EQ(pg.size(), pr.size()) << info.name;
    int differing = 0;
    for (std::size_t i = 0; i < pg.size(); ++i) {
      const float u = pg[i], v = pr[i];
      const bool same = std::isinf(u) ? std::isinf(v)
                        : info.channel == Channel::kDepth || info.channel == Channel::kCloudDepth
                            ? std::abs(u - v) <= 1e-3f * std::abs(v) + 0.01f
                            : std::abs(u - v) <= 0.02f;
      differing += !same;
    }
    // Edge pixels: a rasteriser covers a pixel by its centre like the ray, but coverage of
    // cloud limbs and thresholds in half floats differ by a few hundredths there.
    std::printf("%-12s %4d of %zu pixels differ\n", info.name, differing, pg.size());
    EXPECT_LE(differing, int(pg.size() / 50)) << info.name;
  }
}

// The reference through the interface: a flag raised while it draws stops it between rows. One
// thread, and `alive` (called before each row's check) raising the flag before row 10: rows 0
// to 9 are drawn, the rest left empty, and the frame says it was cancelled; with the flag
// lowered the next frame is whole.
TEST(RendererInterface, ReferenceStopsBetweenRowsWhenCancelled) {
  RendererOptions options;
  options.kind = RendererKind::kReference;
  options.render.reference_samples = 1;
  options.reference_threads = 1;
  std::string error;
  const auto reference = createRenderer(options, error);
  ASSERT_NE(reference, nullptr) << error;
  std::atomic<bool> cancel{false};
  int rows_checked = 0;
  reference->setCancel(&cancel, [&] { cancel = ++rows_checked > 10; });
  const Scene scene = ChannelsTestScenes::level(32, 24);
  const FloatImage stopped = reference->renderFloat(scene, {});
  EXPECT_TRUE(reference->lastFrameCancelled());
  EXPECT_EQ(rows_checked, 11);
  auto rowDrawn = [](const FloatImage& image, int y) {
    for (int x = 0; x < image.width; ++x)
      if (image.pixel(x, y)[2] > 0.0f) return true;  // the sky is blue everywhere
    return false;
  };
  for (int y = 0; y < scene.camera.height; ++y) EXPECT_EQ(rowDrawn(stopped, y), y < 10) << y;

  reference->setCancel(nullptr);
  const FloatImage whole = reference->renderFloat(scene, {});
  EXPECT_FALSE(reference->lastFrameCancelled());
  for (int y = 0; y < scene.camera.height; ++y) EXPECT_TRUE(rowDrawn(whole, y)) << y;
}

// The reference takes what both back ends draw alike from each call's settings: depth at
// channel_divisor 4 is one centre ray per 4 x 4 block, while the renderer's own settings
// (divisor 1) trace every pixel, whose ground depth changes from row to row.
TEST(RendererInterface, ReferenceDrawsEachCallsSettings) {
  RendererOptions options;
  options.kind = RendererKind::kReference;
  options.render.reference_samples = 1;
  std::string error;
  const auto reference = createRenderer(options, error);
  ASSERT_NE(reference, nullptr) << error;
  const Scene scene = ChannelsTestScenes::level(32, 24);
  const FrameRequest depth(ChannelSet{Channel::kDepth});
  RenderSettings blocks;
  blocks.channel_divisor = 4;
  const Frame coarse = reference->render(scene, blocks, depth);
  const Frame fine = reference->render(scene, depth);
  const int w = scene.camera.width;
  int ground = 0, fine_steps = 0;
  for (int y = 16; y < scene.camera.height; ++y)  // below the horizon: the ground
    for (int x = 0; x < w; ++x) {
      const std::size_t i = std::size_t(y) * w + x;
      ASSERT_TRUE(std::isfinite(fine.depth[i])) << x << "," << y;
      ++ground;
      EXPECT_EQ(coarse.depth[i], coarse.depth[std::size_t(y - y % 4) * w + (x - x % 4)]);
      fine_steps += fine.depth[i] != fine.depth[i - w];
    }
  EXPECT_EQ(fine_steps, ground);
}

// Both back ends draw the platform floor at the size asked, and a renderer made by
// another() (GL: on the same context) too.
TEST(RendererInterface, FloorHasTheSizeAsked) {
  for (RendererKind kind : {RendererKind::kGl, RendererKind::kReference}) {
    RendererOptions options;
    options.kind = kind;
    std::string error;
    const auto renderer = createRenderer(options, error);
    ASSERT_NE(renderer, nullptr) << error;
    const std::unique_ptr<Renderer> other = renderer->another();
    for (Renderer* r : {renderer.get(), other.get()})
      for (auto [width, height] : {std::pair{37, 23}, std::pair{8, 61}}) {
        const Srgb8Image floor = r->renderFloor(width, height);
        EXPECT_EQ(floor.width, width) << r->description();
        EXPECT_EQ(floor.height, height) << r->description();
        EXPECT_EQ(floor.rgba.size(), std::size_t(width) * height * 4) << r->description();
      }
  }
}

// The band integral against Stefan-Boltzmann (sigma T^4 / pi over all wavelengths), and the
// brightness temperature as its inverse.
TEST(Infrared, BandRadianceIsPlanckIntegrated) {
  InfraredModel wide;
  wide.band_lo_um = 0.5;
  wide.band_hi_um = 2000.0;
  wide.band_steps = 200000;
  const double sigma = 5.670374419e-8;
  for (double t : {220.0, 288.15, 330.0})
    EXPECT_NEAR(bandRadiance(wide, t), sigma * std::pow(t, 4) / M_PI,
                2e-3 * sigma * std::pow(t, 4) / M_PI)
        << t;
  const InfraredModel band;
  const BandTable table(band);
  for (double t : {180.0, 250.0, 300.0, 350.0}) {
    EXPECT_NEAR(brightnessTemperature(band, bandRadiance(band, t)), t, 1e-6);
    EXPECT_NEAR(table.temperature(bandRadiance(band, t)), t, 1e-3);
  }
}

}  // namespace
}  // namespace nephele
