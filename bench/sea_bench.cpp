// The sea's figures (MODEL.md section 18; issue 48): for sea states 1, 3, 5 and 7 its drawn
// surface against Pierson-Moskowitz (the frequency spectrum's slope), its repetition (the
// largest autocorrelation from three peak wavelengths to 10 km), its mean glint against Cox
// and Munk's and its foam against Monahan's; and the GL frame's cost with the sea as a
// multiple of the same view over the flat ground, with the platform floor timed in the same
// run. With --board DIR, the pictures of every sea state from 300 m and 3 km, sun high and
// low, with and without clouds. A program that prints figures, not a test.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <filesystem>
#include <string>

#include "bench/bench_common.h"
#include "bench/sea_measures.h"
#include "image/image_encoding.h"
#include "world/limits.h"

using namespace nephele;
using namespace nephele::sea_measures;

namespace {

// Sea states by the WMO's code (Douglas), each drawn as the fully developed sea of a wind
// whose significant height, 0.21 U^2 / g, lies in its band.
struct SeaState {
  int code;
  const char* name;
  double wind;  // m/s
};
constexpr SeaState kStates[] = {
    {1, "calm (rippled), 0-0.1 m", 2.0},
    {3, "slight, 0.5-1.25 m", 6.0},
    {5, "rough, 2.5-4 m", 12.0},
    {7, "high, 6-9 m", 18.0},
};

Scene withSea(Scene scene, double wind) {
  scene.sea.emplace();
  scene.sea->wind = {-0.6 * wind, 0.8 * wind};
  scene.sea->clarity = 0.7;
  return scene;
}

// Every sea state's drawn surface against Pierson-Moskowitz, Monahan, and its repetition.
void printSurfaceFigures(const RenderSettings& settings) {
  std::printf("Surface (fully developed; heights from the drawn sines, 0.7 w_p up):\n");
  std::printf("%-4s %-26s %6s %6s %8s %9s %14s %14s %11s %11s\n", "sea", "state", "wind", "Hs m",
              "foam", "(Monahan)", "spectrum slope", "(Pierson-M.)", "repetition", "across");
  for (const SeaState& state : kStates) {
    const Sea sea = withSea(Scene{}, state.wind).sea.value();
    const SeaSurface surface(sea, settings.sea_waves);
    const SpectrumFit fit = measureSpectrum(surface, state.wind);
    const glm::dvec2 along = glm::normalize(sea.wind);
    std::printf("%-4d %-26s %6.1f %6.2f %8.4f %9.4f %14.2f %14.2f %11.3f %11.3f\n", state.code,
                state.name, state.wind, surface.significantHeight(), meanFoam(surface),
                surface.whitecapFraction(), fit.measured_slope, fit.expected_slope,
                repetition(surface, along), repetition(surface, {-along.y, along.x}));
  }
}

// The drawn surface's mean glint over the sun's reflection against Cox-Munk's.
void printGlintFigures(const RenderSettings& settings) {
  std::printf(
      "\nGlint over the sun's reflection against Cox-Munk, the drawn surface's mean "
      "(sun 37 deg up; tan beta in units of Cox-Munk's sigma):\n");
  std::printf("%6s %10s %10s %10s\n", "wind", "0", "0.5", "0.9");
  const glm::dvec3 sun = glm::normalize(glm::dvec3(0.0, 0.8, 0.6));
  for (double wind : {2.0, 7.0, 15.0}) {
    const SeaSurface surface(withSea(Scene{}, wind).sea.value(), settings.sea_waves);
    const double sigma = std::sqrt(0.003 + 5.12e-3 * wind);
    std::printf("%6.1f", wind);
    for (double t : {0.0, 0.5, 0.9})
      std::printf(" %10.3f", glintRatio(surface, wind, t * sigma, sun));
    std::printf("\n");
  }
}

// The GL frame's cost with each sea state, as a multiple of the flat ground's, with and
// without the preset's clouds.
void printFrameCosts(Renderer& renderer, const Scene& clouded, const Scene& clear,
                     const RenderSettings& settings, int repeats) {
  std::printf("%-4s %10s %10s %8s %12s %12s %8s\n", "sea", "ground ms", "sea ms", "x ground",
              "clouds+grd", "clouds+sea", "x ground");
  const double ground = bench::medianFrameMilliseconds(renderer, clear, settings, repeats, false);
  const double ground_clouds =
      bench::medianFrameMilliseconds(renderer, clouded, settings, repeats, false);
  for (const SeaState& state : kStates) {
    const double sea = bench::medianFrameMilliseconds(renderer, withSea(clear, state.wind),
                                                      settings, repeats, false);
    const double sea_clouds = bench::medianFrameMilliseconds(renderer, withSea(clouded, state.wind),
                                                             settings, repeats, false);
    std::printf("%-4d %10.2f %10.2f %8.2f %12.2f %12.2f %8.2f\n", state.code, ground, sea,
                sea / ground, ground_clouds, sea_clouds, sea_clouds / ground_clouds);
  }
}

// The picture board: every sea state from 300 m and 3 km, sun high and low, with and without
// clouds, into `board`.
void writeBoard(Renderer& renderer, const SceneFile& file, const Scene& clear,
                const RenderSettings& settings, const std::string& board) {
  std::filesystem::create_directories(board);
  for (const SeaState& state : kStates)
    for (double altitude : {300.0, 3000.0})
      for (double elevation : {60.0, 12.0})
        for (bool clouds : {false, true}) {
          Scene scene = withSea(clouds ? file.scene : clear, state.wind);
          scene.targets = file.scene.targets;
          scene.camera = file.scene.camera;
          scene.camera.width = 480;
          scene.camera.height = 270;
          scene.camera.position.z = altitude;
          scene.camera.orientation.pitch_deg = altitude > 1000.0 ? -35.0 : -8.0;
          scene.sun.elevation_deg = elevation;
          char name[128];
          std::snprintf(name, sizeof name, "%s/ss%d_%04.0fm_sun%02.0f_%s.png", board.c_str(),
                        state.code, altitude, elevation, clouds ? "clouds" : "clear");
          writeImageFile(name, renderer.renderFloat(scene, settings));
          std::printf("wrote %s\n", name);
        }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Nephele sea benchmark: the sea's surface figures and its frame cost");
  std::string size = "640x360", board;
  int repeats = 5;
  app.add_option("--size", size, "Image size WxH for the timed frames (default 640x360)");
  app.add_option("--repeats", repeats, "Timed frames per view (default 5)")
      ->check(CLI::Range(1, 100));
  app.add_option("--board", board, "Write the picture board's images into this directory");
  RenderSettings settings;
  app.add_option("--sea-waves", settings.sea_waves, "The knob sea_waves (default 64)")
      ->check(CLI::Range(int(Limits::kSeaWaves.lo), int(Limits::kSeaWaves.hi)));
  app.add_option("--sea-probe-scale", settings.sea_probe_scale,
                 "The knob sea_probe_scale (default 0.5)")
      ->check(CLI::Range(Limits::kSeaProbeScale.lo, Limits::kSeaProbeScale.hi));
  CLI11_PARSE(app, argc, argv);

  printSurfaceFigures(settings);
  printGlintFigures(settings);
  SceneFile file;
  if (std::string e = loadSceneFile(NEPHELE_SOURCE_DIR "/config/scenes/sea_search.toml", file);
      !e.empty()) {
    std::fprintf(stderr, "%s\n", e.c_str());
    return 1;
  }
  Camera camera = file.scene.camera;
  if (!bench::parseSize(size, camera)) return 2;
  const std::unique_ptr<Renderer> gl = bench::openRenderer();
  if (!gl) return 1;
  Renderer& renderer = *gl;
  Scene clouded = file.scene;
  clouded.targets.clear();
  clouded.sea.reset();
  clouded.camera = camera;
  Scene clear = clouded;
  clear.layers.clear();
  clear.fields.clear();
  clear.weather.clear();
  const double floor =
      medianMilliseconds(repeats, [&] { renderer.renderFloor(camera.width, camera.height); });
  std::printf(
      "\nGL frame at %dx%d from 300 m, 10 deg down, sun 30 deg up ahead (%s): ms and "
      "multiples of the flat ground's frame; floor %.2f ms\n",
      camera.width, camera.height, renderer.platform().device.c_str(), floor);
  printFrameCosts(renderer, clouded, clear, settings, repeats);
  if (!board.empty()) writeBoard(renderer, file, clear, settings, board);
  return 0;
}
