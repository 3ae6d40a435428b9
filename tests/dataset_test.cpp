// Dataset descriptions, sample draws and labels (dataset/dataset.h): draws are pure functions
// of (seed, index); boxes of targets without clouds equal their projected geometry; the
// visibility label is the transmittance of the cloud in front; RLE decodes to the mask; bad
// descriptions name file, line and key.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "dataset/dataset_file.h"
#include "renderer/renderer.h"
#include "world/shading.h"

namespace nephele {
namespace {

using ::testing::HasSubstr;

const char* kSmall = R"(
[dataset]
seed = 11
samples = 6
width = 96
height = 72

[sky]
genera = ["stratocumulus", "altostratus"]
layers = [0, 2]

[camera]
altitude = [500.0, 2500.0]

[[target]]
name = "crate"
shape = "box"
size = [6.0, 4.0, 3.0]
count = [1, 3]
distance = [150.0, 600.0]
)";

DatasetSpec parse(const std::string& text) {
  DatasetSpec spec;
  EXPECT_EQ(parseDatasetText(text, "d.toml", spec), "");
  return spec;
}

std::string parseError(const std::string& text) {
  DatasetSpec spec;
  spec.samples = -7;  // must stay untouched
  const std::string e = parseDatasetText(text, "d.toml", spec);
  EXPECT_EQ(spec.samples, -7) << "a refused description changed the output";
  return e;
}

TEST(Dataset, SampleDrawsArePureFunctionsOfSeedAndIndex) {
  const DatasetSpec spec = parse(kSmall);
  for (int i : {0, 3, 5}) {
    const SampleScene a = drawSample(spec, i), b = drawSample(spec, i);
    EXPECT_EQ(a.record.dump(), b.record.dump()) << i;
    EXPECT_EQ(a.scene.targets.size(), b.scene.targets.size());
  }
  // Different indices and seeds draw different skies.
  EXPECT_NE(drawSample(spec, 0).record.dump(), drawSample(spec, 1).record.dump());
  DatasetSpec other = spec;
  other.seed = 12;
  EXPECT_NE(drawSample(spec, 0).record["seed"], drawSample(other, 0).record["seed"]);
  // Adding a target category leaves the sky of every sample as it was.
  DatasetSpec more = spec;
  more.targets.push_back(more.targets[0]);
  more.targets.back().name = "crate2";
  EXPECT_EQ(drawSample(spec, 2).record["layers"], drawSample(more, 2).record["layers"]);
  EXPECT_EQ(drawSample(spec, 2).record["camera"], drawSample(more, 2).record["camera"]);
  // The infrared band places the same targets.
  DatasetSpec infrared = spec;
  infrared.band = Band::kLwir;
  EXPECT_EQ(drawSample(spec, 4).record["targets"], drawSample(infrared, 4).record["targets"]);
}

TEST(Dataset, BadDescriptionsNameFileLineAndKey) {
  EXPECT_THAT(parseError("[dataset]\nsamples = 0\n"),
              HasSubstr("d.toml:2: dataset.samples: 0 is out of range (allowed: 1 to 100000000)"));
  EXPECT_THAT(parseError("[sky]\ngenera = [\"cumulus\", \"cumulonimbulus\"]\n"),
              HasSubstr("d.toml:2: sky.genera: \"cumulonimbulus\" is not a genus (allowed: "));
  EXPECT_THAT(parseError("[sky]\ncoverage = [0.8, 0.2]\n"),
              HasSubstr("d.toml:2: sky.coverage: the low end 0.8 is above the high end 0.2"));
  EXPECT_THAT(parseError("[camera]\nvfov = [10, 200]\n"),
              HasSubstr("d.toml:2: camera.vfov: 200 is out of range (allowed: 0.01 to 179)"));
  EXPECT_THAT(parseError("[dataset]\nband = \"radar\"\n"),
              HasSubstr("dataset.band: \"radar\" is not allowed (one of: visible, lwir)"));
  EXPECT_THAT(parseError("[[target]]\nshape = \"box\"\n"), HasSubstr("name is missing"));
  EXPECT_THAT(parseError("[[target]]\nname = \"a\"\nshape = \"mesh\"\n"),
              HasSubstr("needs a mesh = \"file.obj\" key"));
  EXPECT_THAT(parseError("[[target]]\nname = \"a\"\n[[target]]\nname = \"a\"\n"),
              HasSubstr("two [[target]] categories are named \"a\""));
  EXPECT_THAT(parseError("[infrared]\ndisplay = [300, 300]\n"),
              HasSubstr("d.toml:2: infrared.display: must be [black, white] kelvin"));
  EXPECT_THAT(parseError("[[target]]\nname = \"a\"\ntemperature = [0, 300]\n"),
              HasSubstr("target[0].temperature: 0 is out of range (allowed: 1 to 5000)"));
  EXPECT_THAT(parseError("[dataset]\nsampels = 3\n"),
              HasSubstr("d.toml:2: dataset.sampels: unknown key (allowed here: seed, samples"));
}

// With no clouds, the full and visible boxes of a box target are the pixels whose centre ray
// meets the box: computed here from the geometry, not from the renderer.
TEST(Dataset, BoxesWithoutCloudsAreTheProjectedGeometry) {
  DatasetSpec spec = parse(kSmall);
  spec.genera.clear();
  spec.layers = {0.0, 0.0};
  RendererOptions options;
  std::string error;
  const auto renderer = createRenderer(options, error);
  ASSERT_NE(renderer, nullptr) << error;
  int checked = 0;
  for (int index = 0; index < 3; ++index) {
    const SampleScene sample = drawSample(spec, index);
    const Frame frame = renderer->render(
        sample.scene, {ChannelSet{Channel::kColour, Channel::kObjectId, Channel::kVisibility}});
    const std::vector<TargetLabel> labels = labelTargets(frame, sample.target_class);
    ASSERT_EQ(labels.size(), sample.scene.targets.size());
    const Camera& camera = sample.scene.camera;
    const ViewBasis basis = viewBasis(camera);
    for (std::size_t k = 0; k < labels.size(); ++k) {
      // The nearest hit of each pixel's centre ray among all targets and the ground.
      int x0 = 1 << 30, y0 = 1 << 30, x1 = -1, y1 = -1;
      for (int y = 0; y < camera.height; ++y)
        for (int x = 0; x < camera.width; ++x) {
          const glm::dvec3 d = glm::normalize(rayDirection(basis, camera, x + 0.5, y + 0.5));
          double best = d.z < 0.0 ? camera.position.z / -d.z : INFINITY;
          int id = 0;
          for (std::size_t t = 0; t < sample.scene.targets.size(); ++t)
            if (auto hit = intersectTarget(sample.scene.targets[t], camera.position, d);
                hit && hit->distance < best)
              best = hit->distance, id = int(t) + 1;
          if (id != int(k) + 1) continue;
          x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
        }
      const TargetLabel& l = labels[k];
      if (x1 < 0) {
        EXPECT_EQ(l.silhouette_px, 0);
        continue;
      }
      // A rasteriser and the ray may differ on a pixel whose centre grazes an edge.
      for (int c = 0; c < 4; ++c) {
        const double expected[4] = {double(x0), double(y0), double(x1 - x0 + 1),
                                    double(y1 - y0 + 1)};
        EXPECT_NEAR(l.box_full[c], expected[c], 1.0) << "sample " << index << " target " << k;
        EXPECT_NEAR(l.box[c], expected[c], 1.0);
      }
      EXPECT_DOUBLE_EQ(l.visibility, 1.0);
      EXPECT_EQ(l.visible_px, l.silhouette_px);
      ++checked;
    }
  }
  EXPECT_GE(checked, 3);
}

// Labels from a frame built by hand: visibility is the mean transmittance over the
// silhouette, the visible part is where it is at least 1/2, and the RLE decodes to it.
TEST(Dataset, LabelsOfAHandMadeFrame) {
  Frame frame;
  frame.info.width = 5, frame.info.height = 4;
  frame.object_id.assign(20, 0.0f);
  frame.visibility.assign(20, 1.0f);
  // Target 1 covers columns 1-3 of rows 1-2; the cloud hides column 3 (T = 0.2).
  for (int y = 1; y <= 2; ++y)
    for (int x = 1; x <= 3; ++x) {
      frame.object_id[y * 5 + x] = 1.0f;
      if (x == 3) frame.visibility[y * 5 + x] = 0.2f;
    }
  const std::vector<TargetLabel> labels = labelTargets(frame, {0, 0});
  ASSERT_EQ(labels.size(), 2u);
  const TargetLabel& l = labels[0];
  EXPECT_EQ(l.silhouette_px, 6);
  EXPECT_EQ(l.visible_px, 4);
  EXPECT_NEAR(l.visibility, (4 * 1.0 + 2 * 0.2) / 6, 1e-6);
  EXPECT_EQ(std::vector<double>(l.box_full, l.box_full + 4), (std::vector<double>{1, 1, 3, 2}));
  EXPECT_EQ(std::vector<double>(l.box, l.box + 4), (std::vector<double>{1, 1, 2, 2}));
  // Column-major: zeros down column 0 and the top of column 1, then two ones, ...
  std::vector<int> decoded;
  bool on = false;
  for (std::uint32_t run : l.rle) {
    decoded.insert(decoded.end(), run, on);
    on = !on;
  }
  ASSERT_EQ(decoded.size(), 20u);
  for (int x = 0; x < 5; ++x)
    for (int y = 0; y < 4; ++y)
      EXPECT_EQ(decoded[x * 4 + y], (x == 1 || x == 2) && (y == 1 || y == 2)) << x << "," << y;
  EXPECT_EQ(labels[1].silhouette_px, 0);
  EXPECT_EQ(yoloText(labels, 5, 4), "0 0.400000 0.500000 0.400000 0.500000\n");
  const std::vector<float> mask = instanceMask(frame);
  EXPECT_EQ(mask[1 * 5 + 1], 1);
  EXPECT_EQ(mask[1 * 5 + 3], 0);
}

// At sea: every sample has the sea as drawn (its wind within the spans), afloat targets float
// on it, the draws without a sea are those of the same description without one, and the glint
// mask and per-label glint count follow the glint channel.
TEST(Dataset, SamplesAtSeaFloatTheirTargetsAndMaskTheGlint) {
  const std::string afloat = std::string(kSmall) + "afloat = true\n";
  const DatasetSpec dry = parse(kSmall);
  const DatasetSpec wet = parse(afloat + R"(
[sea]
probability = 1.0
wind = [4.0, 12.0]
clarity = [0.2, 0.4]
)");
  for (int i = 0; i < 6; ++i) {
    const SampleScene sample = drawSample(wet, i);
    ASSERT_TRUE(sample.scene.sea) << i;
    const double speed = glm::length(sample.scene.sea->wind);
    EXPECT_GE(speed, 4.0);
    EXPECT_LE(speed, 12.0);
    EXPECT_GE(sample.scene.sea->clarity, 0.2);
    EXPECT_LE(sample.scene.sea->clarity, 0.4);
    for (const Target& t : sample.scene.targets) EXPECT_NEAR(t.centre.z, 0.3 * 3.0, 1e-9) << i;
    // The sky, sun and camera draws are those of the same description without a sea.
    const SampleScene plain = drawSample(dry, i);
    EXPECT_EQ(plain.record["layers"].dump(), sample.record["layers"].dump());
    EXPECT_EQ(plain.record["camera"].dump(), sample.record["camera"].dump());
    EXPECT_FALSE(plain.scene.sea);
  }
  Frame frame;
  frame.info.width = 4, frame.info.height = 2;
  frame.object_id = {kSeaObjectId, 1, 1, kSeaObjectId, kSeaObjectId, 1, 1, kSeaObjectId};
  frame.visibility.assign(8, 1.0f);
  frame.glint = {0.0f, 0.3f, 0.1f, 2.0f, 0.0f, 0.0f, 0.25f, 0.0f};
  const std::vector<float> mask = glintMask(frame, 0.25);
  EXPECT_EQ(mask, (std::vector<float>{0, 65535, 0, 65535, 0, 0, 65535, 0}));
  const std::vector<TargetLabel> labels = labelTargets(frame, {0}, 0.25);
  EXPECT_EQ(labels[0].glint_px, 2);  // columns 1-2 of both rows
  frame.glint.clear();
  EXPECT_EQ(labelTargets(frame, {0}, 0.25)[0].glint_px, -1);
}

}  // namespace
}  // namespace nephele
