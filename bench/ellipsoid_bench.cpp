// Ellipsoid-cloud benchmark: milliseconds per frame (median, render + readback into an 8-bit
// target) against the number of ellipsoids, and error against the CPU reference for every
// quality knob on the cloud presets. A program that prints figures, not a test.
//
//   ellipsoid_bench [--presets DIR] [--repeats N] [--samples N] [--counts 1,6,27,100,500]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench/bench_common.h"
#include "config/scene_file.h"
#include "image/image_metrics.h"
#include "renderer/reference/reference_renderer.h"

namespace {

using namespace nephele;
using bench::Knob;
using bench::knob;

std::vector<Knob> knobs() {
  auto multipass = [](RenderSettings& s) { s.ellipsoid_passes = EllipsoidPasses::kMultipass; };
  return {
      knob("fused per-pixel (default)", [](RenderSettings&) {}),
      knob("fused centre order",
           [](RenderSettings& s) { s.ellipsoid_order = EllipsoidOrder::kCentre; }),
      knob("fused procedural",
           [](RenderSettings& s) { s.texture_evaluation = TextureEvaluation::kProcedural; }),
      knob("fused spotlight limb", [](RenderSettings& s) { s.limb = LimbEvaluation::kSpotlight; }),
      knob("multipass adaptive", multipass),
      knob("multipass rgba8 tiles",
           [&](RenderSettings& s) {
             multipass(s);
             s.tile_format = TileFormat::kRgba8;
           }),
      knob("multipass 10x10 mesh",
           [&](RenderSettings& s) {
             multipass(s);
             s.tessellation = 10;
           }),
      knob("multipass tiles 64",
           [&](RenderSettings& s) {
             multipass(s);
             s.tile_resolution = 64;
           }),
      knob("multipass tiles 256",
           [&](RenderSettings& s) {
             multipass(s);
             s.tile_resolution = 256;
           }),
      knob("multipass spotlight",
           [&](RenderSettings& s) {
             multipass(s);
             s.limb = LimbEvaluation::kSpotlight;
           }),
      knob("multipass procedural",
           [&](RenderSettings& s) {
             multipass(s);
             s.texture_evaluation = TextureEvaluation::kProcedural;
           }),
      knob("impostors 0.5 px", [](RenderSettings& s) { s.impostor_tolerance_px = 0.5; }),
  };
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Nephele ellipsoid-cloud benchmark");
  std::string presets = NEPHELE_SOURCE_DIR "/config/scenes";
  int repeats = 9, samples = 4;
  std::vector<int> counts{1, 6, 27, 100, 500};
  std::vector<std::string> sizes{"640x480", "1280x1024"};
  bool skip_knobs = false;
  app.add_option("--presets", presets, "Directory of scene files")->capture_default_str();
  app.add_option("--repeats", repeats, "Timed frames per case (median reported)")
      ->check(CLI::Range(1, 1000));
  app.add_option("--samples", samples, "Reference supersampling per axis")
      ->check(CLI::Range(1, 16));
  app.add_option("--counts", counts, "Ellipsoid counts for the scaling table")->delimiter(',');
  app.add_option("--sizes", sizes, "Image sizes WxH for the scaling table")->delimiter(',');
  app.add_flag("--no-knobs", skip_knobs, "Print only the scaling table");
  CLI11_PARSE(app, argc, argv);

  const std::unique_ptr<Renderer> gl = bench::openRenderer();
  if (!gl) return 1;
  Renderer& renderer = *gl;
  const RendererPlatform platform = renderer.platform();
  std::printf("GL: %s, %s; timed: render + readback, 8-bit sRGB target\n", platform.backend.c_str(),
              platform.device.c_str());

  SceneFile cumulus;
  if (!bench::loadPreset(presets + "/cumulus.toml", cumulus)) return 1;
  // Scaling: the cumulus preset's cloud rebuilt with N lobes (the same 2 km heap, denser).
  std::printf("\nscaling (cumulus preset, default knobs; multipass beside it)\n");
  std::printf("%-10s %-10s %12s %14s\n", "ellipsoids", "size", "fused ms", "multipass ms");
  for (int count : counts)
    for (const std::string& size : sizes) {
      Scene scene = cumulus.scene;
      EllipsoidCloud& cloud = scene.clouds.at(0);
      cloud.ellipsoids = cumulusEllipsoids(count, {0.0, 0.0, 800.0}, 2000.0, 27);
      if (!bench::parseSize(size, scene.camera)) return 2;
      RenderSettings multipass;
      multipass.ellipsoid_passes = EllipsoidPasses::kMultipass;
      const double fused_ms = bench::medianFrameMilliseconds(renderer, scene, {}, repeats, false);
      const double multipass_ms =
          bench::medianFrameMilliseconds(renderer, scene, multipass, repeats, false);
      std::printf("%-10d %-10s %12.2f %14.2f\n", count, size.c_str(), fused_ms, multipass_ms);
      std::fflush(stdout);
    }
  if (skip_knobs) return 0;

  std::printf("\nknobs (error: sRGB RGB against the CPU reference, %dx%d samples, every term)\n",
              samples, samples);
  std::printf("%-18s %-26s %9s %9s %9s\n", "preset", "knob", "ms/frame", "PSNR dB", "max err");
  const std::vector<std::filesystem::path> files = bench::presetFiles(presets);
  for (const auto& path : files) {
    SceneFile file;
    if (!bench::loadPreset(path.string(), file)) return 1;
    if (file.scene.clouds.empty()) continue;
    const Scene& scene = file.scene;
    const FloatImage reference = renderReference(scene, {samples, 0});
    for (const Knob& knob : knobs()) {
      const double ms =
          bench::medianFrameMilliseconds(renderer, scene, knob.settings, repeats, false);
      const ImageError err = compareImages(renderer.renderFloat(scene, knob.settings), reference);
      std::printf("%-18s %-26s %9.2f %9.2f %9.4f%s\n", path.stem().c_str(), knob.name, ms,
                  err.psnr_db, err.max_abs, err.non_finite ? "  NON-FINITE PIXELS" : "");
      std::fflush(stdout);
    }
  }
  return 0;
}
