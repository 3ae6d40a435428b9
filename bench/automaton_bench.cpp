// Automaton-cloud benchmark: automaton steps on Dobashi's 256x128x20 grid (cell updates per
// second, one core and more), keyframe and light update times, and frames per second for
// Shen's two scenes with error against the CPU reference. A program that prints figures.
//
//   automaton_bench [--steps N] [--repeats N] [--threads 1,2] [--size 1280x1024] [--no-render]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench/bench_common.h"
#include "config/scene_file.h"
#include "image/image_metrics.h"
#include "renderer/reference/reference_renderer.h"
#include "world/world.h"

namespace {

using namespace nephele;

// Dobashi's grid with one shaping ellipsoid filling it: a field of cloud that keeps growing
// and dying. Steps of the automaton alone (no keyframes), in its steady state.
void automatonSteps(int steps, const std::vector<int>& thread_counts) {
  AutomatonCloudSpec spec;
  spec.cells = {256, 128, 20};
  spec.warmup_steps = 30;
  const AutomatonCloud cloud(spec, {}, {0, 0, 1});
  std::printf("automaton steps, %dx%dx%d cells (%lld)\n", spec.cells.nx, spec.cells.ny,
              spec.cells.nz, static_cast<long long>(spec.cells.cells()));
  std::printf("%-8s %12s %18s %10s\n", "threads", "ms/step", "cell updates/s", "cloud %");
  for (int threads : thread_counts) {
    CellularAutomaton automaton = cloud.automaton();
    const double ms =
        medianMilliseconds(steps, [&] { automaton.step(cloud.probabilities(), threads); });
    std::printf("%-8d %12.3f %18.3g %10.1f\n", threads, ms, double(spec.cells.cells()) / ms * 1e3,
                100.0 * double(automaton.count(CellBit::kCld)) / double(spec.cells.cells()));
  }
}

// Keyframe (cell means, density lattice, sweep) and relight (sweep alone) times.
void lightUpdates(int repeats) {
  std::printf("\nkeyframe and light updates (one cloud, 2 samples per cell)\n");
  std::printf("%-12s %10s %14s %14s %12s\n", "cells", "samples", "keyframe ms", "relight ms",
              "step ms");
  for (const GridSize cells : {GridSize{20, 20, 20}, GridSize{20, 18, 15}, GridSize{40, 40, 30}}) {
    AutomatonCloudSpec spec;
    spec.cells = cells;
    World world(Scene{}, WorldDynamics{{}, {}, {}, {spec}});
    Sun sun = world.base().sun;
    double elevation = 30.0;
    const double relight_ms = medianMilliseconds(repeats, [&] {
      sun.elevation_deg = (elevation += 1.0);
      world.setSun(sun);
    });
    // Each advance by one interval runs one step and builds one keyframe.
    const double keyframe_ms =
        medianMilliseconds(repeats, [&] { world.advance(spec.step_interval_s); });
    CellularAutomaton automaton = world.automata()[0].automaton();
    const AutomatonProbabilities& fields = world.automata()[0].probabilities();
    const double step_ms = medianMilliseconds(repeats, [&] { automaton.step(fields); });
    const glm::ivec3 dims = world.scene().automata[0].to->lattice.dims;
    char name[32], samples[32];
    std::snprintf(name, sizeof name, "%dx%dx%d", cells.nx, cells.ny, cells.nz);
    std::snprintf(samples, sizeof samples, "%d", dims.x * dims.y * dims.z);
    std::printf("%-12s %10s %14.3f %14.3f %12.4f\n", name, samples, keyframe_ms, relight_ms,
                step_ms);
  }
}

// Frames per second at `size` (median frame: render + readback into an 8-bit target) and
// error against the CPU reference at a quarter of the size, for the march-step knob and the
// lattice resolution.
void renderTable(const std::string& presets, const std::string& size, int repeats) {
  const std::unique_ptr<Renderer> gl = bench::openRenderer();
  if (!gl) return;
  Renderer& renderer = *gl;
  std::printf(
      "\nframes (%s, %s; error: sRGB RGB against the reference at a quarter size, 1 sample "
      "per pixel)\n",
      size.c_str(), renderer.platform().device.c_str());
  std::printf("%-16s %-22s %9s %8s %9s %9s\n", "preset", "knob", "ms/frame", "fps", "PSNR dB",
              "max err");
  struct Case {
    const char* name;
    int samples_per_cell;
    double volume_step;
  };
  const Case cases[] = {{"default (2, 1.0)", 2, 1.0},
                        {"step 2.0", 2, 2.0},
                        {"step 0.5", 2, 0.5},
                        {"1 sample per cell", 1, 1.0},
                        {"3 samples per cell", 3, 1.0}};
  for (const char* name : {"automaton_cloud", "harbour"}) {
    SceneFile file;
    if (!bench::loadPreset(presets + "/" + name + ".toml", file)) return;
    if (!bench::parseSize(size, file.scene.camera)) return;
    FloatImage reference;
    for (const Case& c : cases) {
      SceneFile edited = file;
      for (AutomatonCloudSpec& a : edited.dynamics.automata)
        a.samples_per_cell = c.samples_per_cell;
      const Scene scene = World(edited.scene, edited.dynamics).scene();
      RenderSettings settings;
      settings.volume_step = c.volume_step;
      const double ms = bench::medianFrameMilliseconds(renderer, scene, settings, repeats, false);
      Scene small = scene;
      small.camera.width /= 4;
      small.camera.height /= 4;
      if (reference.rgba.empty()) reference = renderReference(small, {1, 0});
      const ImageError err = compareImages(renderer.renderFloat(small, settings), reference);
      std::printf("%-16s %-22s %9.1f %8.1f %9.2f %9.4f\n", name, c.name, ms, 1000.0 / ms,
                  err.psnr_db, err.max_abs);
      std::fflush(stdout);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Nephele automaton-cloud benchmark");
  int steps = 50, repeats = 15;
  std::vector<int> threads{1, 2};
  app.add_option("--steps", steps, "Timed automaton steps (median reported)")
      ->check(CLI::Range(1, 100000));
  app.add_option("--repeats", repeats, "Timed repeats for light updates and frames")
      ->check(CLI::Range(1, 1000));
  app.add_option("--threads", threads, "Thread counts for the automaton table")->delimiter(',');
  std::string presets = NEPHELE_SOURCE_DIR "/config/scenes", size = "1280x1024";
  bool no_render = false;
  app.add_option("--presets", presets, "Directory of scene files")->capture_default_str();
  app.add_option("--size", size, "Image size WxH for the frame table")->capture_default_str();
  app.add_flag("--no-render", no_render, "Skip the frame table");
  CLI11_PARSE(app, argc, argv);
  automatonSteps(steps, threads);
  lightUpdates(repeats);
  if (!no_render) renderTable(presets, size, repeats);
  return 0;
}
