// Realism figures (issue 14; method in docs/ACCURACY.md, "Realism"): every genus from the
// weather mapping seen straight down over a square `--span` metres wide, and three figures of
// the drawn field compared with observed clouds:
//   D  perimeter-area dimension of the cloud outlines (observed about 1.35; Lovejoy 1982),
//   s  slope of the transect power spectrum of the radiance (observed close to -5/3 above a
//      few hundred metres; Cahalan and Snider 1989),
//   a  exponent of the cloud size distribution n(A) ~ A^-a, with how many clouds it rests on.
// A benchmark: it prints figures and never fails on them.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench/bench_common.h"
#include "image/cloud_statistics.h"
#include "image/image.h"
#include "world/formations/weather.h"

using namespace nephele;

namespace {

// Clouds smaller than this many pixels have outlines too coarse to measure.
constexpr int kMinCloudPixels = 16;

struct Figures {
  Fitted dimension, slope, sizes;
  double fraction = 0.0;  // drawn cloud fraction
  int clouds = 0;         // whole clouds (not cut by the frame) of kMinCloudPixels or more
  double ms = 0.0;        // render time of the view
};

Figures measure(Renderer& renderer, CloudType type, double coverage, double span_m, int pixels,
                double shortest_m, const ClusterVariation& clusters) {
  Scene scene;
  WeatherLayer w = typicalWeatherLayer(type, coverage);
  if (type == CloudType::kCumulus || type == CloudType::kCumulonimbus) w.clusters = clusters;
  const WeatherClouds clouds = weatherClouds(w, "weather/1", 7);
  scene.layers = clouds.layers;
  scene.fields = clouds.fields;
  scene.camera = nadirCamera({3000.0, -2000.0}, w.base_m, w.thickness_m, span_m, pixels);
  Figures f;
  FloatImage image;
  // The model's texture, its sines per pixel: the clipmap that `auto` fills from the second
  // frame of a place on (MODEL.md section 2) is sized for views near the layer, and over this
  // 50 km map its rings drop the finest terms (nimbostratus at 50 %: s -2.07 against -1.70).
  RenderSettings settings;
  settings.texture_evaluation = TextureEvaluation::kProcedural;
  f.ms = medianMilliseconds(1, [&] { image = renderer.renderFloat(scene, settings); });
  std::vector<double> radiance(std::size_t(pixels) * pixels);
  int covered = 0;
  for (std::size_t i = 0; i < radiance.size(); ++i) {
    const float* p = &image.rgba[4 * i];
    radiance[i] = bench::linearLuminance(p[0], p[1], p[2]);
    covered += p[3] >= 0.5f;
  }
  f.fraction = double(covered) / double(radiance.size());
  const std::vector<CloudRegion> regions = cloudRegions(image, kMinCloudPixels);
  f.clouds = int(regions.size());
  f.dimension = perimeterAreaDimension(regions, kMinCloudPixels);
  f.sizes = sizeDistributionExponent(regions, kMinCloudPixels);
  const double metres_per_pixel = span_m / pixels;
  f.slope = transectSpectrumSlope(radiance, pixels, pixels / 4.0, shortest_m / metres_per_pixel);
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app(
      "Nephele realism benchmark: fractal dimension, spectrum and size distribution of "
      "every genus seen straight down, against observed clouds");
  double span_m = 50000.0, shortest_m = 400.0;
  int pixels = 1024;
  std::vector<double> coverages{0.3, 0.5, 0.7};
  std::vector<std::string> genera;
  app.add_option("--span", span_m, "Width of the square seen, metres")
      ->check(CLI::Range(1000.0, 1.0e6))
      ->capture_default_str();
  app.add_option("--pixels", pixels, "Image side, a power of two")
      ->check(CLI::IsMember({128, 256, 512, 1024, 2048}))
      ->capture_default_str();
  app.add_option("--shortest", shortest_m,
                 "Shortest wavelength in the spectrum fit, metres (the longest is a quarter of "
                 "the span)")
      ->check(CLI::Range(1.0, 1.0e5))
      ->capture_default_str();
  app.add_option("--coverage", coverages, "Cloud fractions asked")
      ->delimiter(',')
      ->check(CLI::Range(0.01, 0.99));
  app.add_option("--genera", genera, "Only these genera (default: all ten)")->delimiter(',');
  ClusterVariation clusters;
  app.add_option("--spacing", clusters.spacing_m,
                 "Heaps: Gardner's cluster grid, metres (MODEL.md section 11; 0 none)")
      ->check(CLI::Range(0.0, 1.0e5));
  app.add_option("--variation", clusters.amount, "Heaps: cluster variation, 0..1")
      ->check(CLI::Range(0.0, 1.0));
  CLI11_PARSE(app, argc, argv);
  std::vector<CloudType> types;
  for (int t = 1; t < kCloudTypeCount; ++t) {
    const std::string name(cloudTypeName(CloudType(t)));
    if (genera.empty() || std::find(genera.begin(), genera.end(), name) != genera.end())
      types.push_back(CloudType(t));
  }
  if (types.empty()) {
    std::fprintf(stderr, "--genera: none of the names is a genus (allowed: altocumulus, ...)\n");
    return 2;
  }
  const std::unique_ptr<Renderer> gl = bench::openRenderer();
  if (!gl) return 1;
  Renderer& renderer = *gl;
  std::printf(
      "Straight down over %.0f km, %d x %d (%.0f m per pixel); clouds of %d pixels or more; "
      "spectrum between %.0f m and %.1f km.\nObserved: D about 1.35 (aim 1.25 to 1.45), "
      "s about -5/3 (aim -1.97 to -1.37).\n",
      span_m / 1000.0, pixels, pixels, span_m / pixels, kMinCloudPixels, shortest_m,
      span_m / 4000.0);
  std::printf("%-14s %6s %6s %7s %7s %7s %7s %8s %8s\n", "genus", "asked", "drawn", "clouds", "D",
              "s", "a", "bins(a)", "ms");
  for (CloudType type : types)
    for (double coverage : coverages) {
      const Figures f = measure(renderer, type, coverage, span_m, pixels, shortest_m, clusters);
      auto value = [](const Fitted& x) { return x.points >= 3 ? x.value : NAN; };
      std::printf("%-14s %6.2f %6.3f %7d %7.3f %7.3f %7.3f %8d %8.0f\n",
                  std::string(cloudTypeName(type)).c_str(), coverage, f.fraction, f.clouds,
                  value(f.dimension), value(f.slope), value(f.sizes), f.sizes.points, f.ms);
      std::fflush(stdout);
    }
  return 0;
}
