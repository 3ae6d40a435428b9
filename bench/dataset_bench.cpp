// Dataset throughput and where the time goes (issue: 20 samples per second at 640x480 with
// PNG, labels and masks, for layers and cumulus with two targets, on 2 cores with software
// GL). Per sample of a description: drawing the sky and placing the targets (CPU), rendering
// colour, object ids and visibility (GL), labelling, sRGB conversion and PNG encoding of the
// image, and the 16-bit mask's PNG; every stage timed alone, in memory (no disk), plus the
// platform floor at the same size. `nephele dataset` runs the three groups (drawing,
// rendering, labelling with encoding) on three threads: its rate is bounded by the slowest.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench_common.h"
#include "dataset/dataset_file.h"
#include "image/image_encoding.h"
#include "image/image_metrics.h"
#include "renderer/encode.h"
#include "world/infrared.h"

using namespace nephele;
using namespace nephele::bench;

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

// Milliseconds per stage, summed over samples, and what the labels found.
struct StageTimes {
  double draw = 0, heaps = 0, render = 0, label = 0, srgb = 0, png = 0, mask = 0;
  FrameTimes budget;  // the mean over the samples
  int targets = 0, visible = 0;
};

// Sample i of `spec` through every stage, each timed alone.
void timeSample(Renderer& gl, const DatasetSpec& spec, const RenderSettings& settings,
                const FrameRequest& request, int i, int samples, bool per_sample,
                StageTimes& times) {
  auto t = Clock::now();
  const SampleScene sample = drawSample(spec, i);
  times.draw += msSince(t);
  t = Clock::now();
  // The heaps around the camera, which the render builds first (tiles of ellipsoids).
  const Scene with_heaps = withFieldClouds(sample.scene, spec.heaps);
  times.heaps += msSince(t);
  t = Clock::now();
  Frame frame = gl.render(with_heaps, settings, request);
  const double render_ms = msSince(t);
  times.render += render_ms;
  times.budget.accumulate(gl.lastFrameStats().times, 1.0 / samples);
  if (per_sample) {
    const Camera& c = sample.scene.camera;
    std::printf("  sample %d: camera at %.0f m, pitch %.1f deg, vfov %.1f deg: render %.1f ms\n", i,
                c.position.z, c.orientation.pitch_deg, c.vfov_deg, render_ms);
  }
  t = Clock::now();
  const std::vector<TargetLabel> labels = labelTargets(frame, sample.target_class);
  const std::string json = sampleLabelsJson(labels, spec.width, spec.height).dump() +
                           yoloText(labels, spec.width, spec.height);
  frame.derived.push_back({"instance_mask", instanceMask(frame)});
  times.label += msSince(t);
  t = Clock::now();
  const Srgb8Image bytes = toSrgb8(frame.colour);
  times.srgb += msSince(t);
  t = Clock::now();
  std::vector<std::uint8_t> encoded;
  encodeImage(ImageFileFormat::kPng, bytes, true, false, EncodeOptions{1}, encoded);
  times.png += msSince(t);
  t = Clock::now();
  encode(frame, ImageFileFormat::kPng, {{}, Channels::Pixels::kGrey16, {"instance_mask"}},
         EncodeOptions{1});
  times.mask += msSince(t);
  times.targets += int(labels.size());
  for (const TargetLabel& l : labels) times.visible += l.visible_px > 0;
}

// One description's samples per second, serial and pipelined, and its time per stage: 0, or
// the exit code.
int benchDescription(Renderer& gl, const std::string& path, int samples, bool per_sample) {
  DatasetSpec spec;
  if (std::string e = loadDatasetFile(path, spec); !e.empty()) {
    std::fprintf(stderr, "%s\n", e.c_str());
    return 1;
  }
  const double floor_ms = medianMilliseconds(7, [&] { gl.renderFloor(spec.width, spec.height); });
  RenderSettings settings;
  settings.heaps = spec.heaps;
  const FrameRequest request{{Channel::kColour, Channel::kObjectId, Channel::kVisibility}};
  gl.render(drawSample(spec, 0).scene, settings, request);  // warm-up: shaders, tables
  StageTimes s;
  for (int i = 0; i < samples; ++i)
    timeSample(gl, spec, settings, request, i, samples, per_sample, s);
  const double n = samples;
  const double serial = (s.draw + s.heaps + s.render + s.label + s.srgb + s.png + s.mask) / n;
  const double pipelined =
      std::max({s.draw / n, (s.heaps + s.render) / n, (s.label + s.srgb + s.png + s.mask) / n});
  std::printf("%s: %dx%d, %d samples, %.1f targets per sample (%.0f %% visible)\n", path.c_str(),
              spec.width, spec.height, samples, s.targets / n,
              s.targets ? 100.0 * s.visible / s.targets : 0.0);
  std::printf("  floor (one constant pass + readback): %.2f ms\n", floor_ms);
  std::printf(
      "  per sample: draw %.1f ms, heaps %.1f ms, GL render %.1f ms (%.0f x floor), "
      "labels %.1f ms, sRGB %.1f ms, PNG %.1f ms, mask PNG %.1f ms\n",
      s.draw / n, s.heaps / n, s.render / n, s.render / n / floor_ms, s.label / n, s.srgb / n,
      s.png / n, s.mask / n);
  std::printf("  GL render's budget, mean per sample: %s\n", frameBudgetLine(s.budget).c_str());
  std::printf(
      "  one thread: %.1f samples/s; three overlapped stages on 2 cores: at most %.1f "
      "samples/s (bounded by the slowest stage)\n",
      1e3 / serial, 1e3 / pipelined);
  return 0;
}

// The label knob: cloud depth traced once per N x N pixels, against every pixel traced, on
// the first samples of a description (error: pixels whose cloud depth changes between finite
// and infinite, and the mean relative change where both are finite).
void printDivisorFigures(Renderer& gl, const std::string& path, int samples) {
  DatasetSpec spec;
  loadDatasetFile(path, spec);
  std::printf("cloud_depth channel_divisor (%s, %d samples):\n", path.c_str(),
              std::min(samples, 4));
  std::vector<std::vector<float>> exact;
  for (int divisor : {1, 2, 4, 8}) {
    RenderSettings settings;
    settings.heaps = spec.heaps;
    settings.channel_divisor = divisor;
    double ms = 0.0, flipped = 0.0, relative = 0.0;
    const int n = std::min(samples, 4);
    for (int i = 0; i < n; ++i) {
      const Scene scene = drawSample(spec, i).scene;
      const auto t = Clock::now();
      const Frame frame = gl.render(scene, settings, {ChannelSet{Channel::kCloudDepth}});
      ms += msSince(t);
      if (divisor == 1) exact.push_back(frame.cloud_depth);
      const PlaneError e = comparePlanes(frame.cloud_depth, exact[std::size_t(i)]);
      flipped += e.flipped / n;
      relative += e.mean_relative / n;
    }
    std::printf(
        "  %d: %.1f ms per frame, %.2f %% of pixels cloud/clear flipped, mean relative "
        "depth error %.4f\n",
        divisor, ms / n, 100.0 * flipped, relative);
  }
}

// The infrared knob: band_steps (midpoint rule over 8-12 um) against 4096 steps, as the
// brightness temperature error of the radiance it gives, 200 K to 340 K.
void printBandStepsFigures() {
  std::printf("lwir band_steps (8-12 um; error in brightness temperature, 200 to 340 K):\n");
  InfraredModel fine;
  fine.band_steps = 4096;
  for (int steps : {1, 2, 4, 8, 16, 64}) {
    InfraredModel model;
    model.band_steps = steps;
    double worst = 0.0;
    for (double t = 200.0; t <= 340.0; t += 5.0)
      worst = std::max(worst, std::abs(brightnessTemperature(fine, bandRadiance(model, t)) - t));
    const auto t0 = Clock::now();
    double sink = 0.0;
    for (int i = 0; i < 20000; ++i) sink += bandRadiance(model, 250.0 + i * 0.001);
    const double us = msSince(t0) * 1e3 / 20000;
    std::printf("  %3d: %.4f K worst, %.2f us per radiance%s\n", steps, worst, us,
                sink > 0 ? "" : " ");
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Dataset throughput: samples per second and time per stage");
  std::vector<std::string> specs{NEPHELE_SOURCE_DIR "/bench/datasets/layers_and_cumulus.toml",
                                 NEPHELE_SOURCE_DIR "/bench/datasets/layers.toml"};
  int samples = 12;
  bool per_sample = false;
  app.add_option("specs", specs, "Dataset descriptions")->capture_default_str();
  app.add_option("--samples", samples, "Samples timed per description")->check(CLI::Range(1, 1000));
  app.add_flag("--per-sample", per_sample, "Print each sample's camera and render time");
  CLI11_PARSE(app, argc, argv);

  const std::unique_ptr<Renderer> renderer = openRenderer();
  if (!renderer) return 1;
  Renderer& gl = *renderer;
  for (const std::string& path : specs)
    if (const int code = benchDescription(gl, path, samples, per_sample); code != 0) return code;
  printDivisorFigures(gl, specs.front(), samples);
  printBandStepsFigures();
  return 0;
}
