// Sky-layer renderer benchmark: milliseconds per frame (median) and error against the CPU
// reference for every preset, size and quality knob. A program that prints figures, not a
// test: these machines are shared and noisy.
//
//   render_bench [--presets DIR] [--repeats N] [--samples N] [--sizes 640x480,1280x1024]
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
using Clock = std::chrono::steady_clock;

std::vector<Knob> knobs() {
  return {
      knob("baked/fade (default)", [](RenderSettings&) {}),
      knob("baked/cut", [](RenderSettings& s) { s.term_filter = TermFilter::kCut; }),
      knob("baked/fade tpc=4", [](RenderSettings& s) { s.bake_texels_per_cycle = 4; }),
      knob("baked/fade tpc=16", [](RenderSettings& s) { s.bake_texels_per_cycle = 16; }),
      knob("baked/fade tpc=2", [](RenderSettings& s) { s.bake_texels_per_cycle = 2; }),
      knob("baked/fade tpc=32", [](RenderSettings& s) { s.bake_texels_per_cycle = 32; }),
      knob("baked/fade multipass", [](RenderSettings& s) { s.sky_passes = SkyPasses::kMultipass; }),
      knob("procedural/fade",
           [](RenderSettings& s) { s.texture_evaluation = TextureEvaluation::kProcedural; }),
      knob("procedural/none",
           [](RenderSettings& s) {
             s.texture_evaluation = TextureEvaluation::kProcedural;
             s.term_filter = TermFilter::kNone;
           }),
  };
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Nephele sky-layer benchmark");
  std::string presets = NEPHELE_SOURCE_DIR "/config/scenes";
  int repeats = 9, samples = 4;
  std::string target = "srgb8";
  std::vector<std::string> sizes{"640x480", "1280x1024"};
  app.add_option("--presets", presets, "Directory of scene files")->capture_default_str();
  app.add_option("--repeats", repeats, "Timed frames per case (median reported)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--samples", samples, "Reference supersampling per axis")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  app.add_option("--sizes", sizes, "Image sizes WxH")->delimiter(',');
  app.add_option("--target", target, "Render target timed: srgb8 (PNG/JPEG/TIFF) or float (EXR)")
      ->check(CLI::IsMember({"srgb8", "float"}))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const std::unique_ptr<Renderer> renderer = bench::openRenderer();
  if (!renderer) return 1;
  const RendererPlatform platform = renderer->platform();
  std::printf("GL: %s, %s\n", platform.backend.c_str(), platform.device.c_str());
  std::printf("timed: %s target, render + readback\n", target.c_str());
  std::printf("error: sRGB RGB against the CPU reference (%dx%d samples, every term)\n\n", samples,
              samples);
  std::printf("%-12s %-10s %-22s %9s %9s %9s\n", "preset", "size", "knob", "ms/frame", "PSNR dB",
              "max err");

  const std::vector<std::filesystem::path> files = bench::presetFiles(presets);

  for (const auto& path : files) {
    SceneFile file;
    if (!bench::loadPreset(path.string(), file)) return 1;
    for (const std::string& size : sizes) {
      Scene scene = file.scene;
      if (!bench::parseSize(size, scene.camera)) return 2;
      const auto ref_start = Clock::now();
      const FloatImage reference = renderReference(scene, {samples, 0});
      const double ref_ms =
          std::chrono::duration<double, std::milli>(Clock::now() - ref_start).count();
      for (const Knob& knob : knobs()) {
        const double ms = bench::medianFrameMilliseconds(*renderer, scene, knob.settings, repeats,
                                                         target == "float");
        const ImageError err =
            compareImages(renderer->renderFloat(scene, knob.settings), reference);
        std::printf("%-12s %-10s %-22s %9.2f %9.2f %9.4f%s\n", path.stem().c_str(), size.c_str(),
                    knob.name, ms, err.psnr_db, err.max_abs,
                    err.non_finite ? "  NON-FINITE PIXELS" : "");
        std::fflush(stdout);
      }
      std::printf("%-12s %-10s %-22s %9.0f\n", path.stem().c_str(), size.c_str(), "(CPU reference)",
                  ref_ms);
    }
  }
  return 0;
}
