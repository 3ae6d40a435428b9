// A long flight (issue 14, item 4): a view flying level at 250 m/s for two hours through a
// 2,000 km macrocluster of cumulus (clusters that vary, drifting with a 12 m/s wind) under an
// altocumulus layer, starting 1,000 km from the origin. Every `interval` simulated seconds it
// renders two frames 1/30 s apart and prints the time of the first (which builds every tile
// in view: the camera has jumped) and of the second (tiles cached, as in a flight at 30 Hz),
// the second's multiple of the platform floor, heaps drawn, the largest change between the two
// frames of the mean coverage and mean luminance (popping: tiles, lobe merging and the far deck
// switching in), the largest pixel change, and resident memory. Precision: at the start and the
// end, the view rendered where it is and with the whole world moved so that the camera is at the
// origin (the field's offset, the layers' drift and the camera shifted together: the same sky), GL
// against GL and each against the one-sample CPU reference, which computes in double. A benchmark:
// it never fails on its figures.
#include <cmath>
#include <cstdio>
#include <string>

#include <CLI/CLI.hpp>

#include "bench/bench_common.h"
#include "image/image_metrics.h"
#include "renderer/reference/reference_renderer.h"
#include "world/formations/weather.h"

using namespace nephele;

namespace {

struct Means {
  double cover = 0.0, luminance = 0.0;
};
Means means(const FloatImage& image) {
  Means m;
  const double n = double(image.width) * image.height;
  for (std::size_t i = 0; i < image.rgba.size(); i += 4) {
    m.cover += image.rgba[i + 3] / n;
    m.luminance += (image.rgba[i] + image.rgba[i + 1] + image.rgba[i + 2]) / (3.0 * n);
  }
  return m;
}

struct FlightOptions {
  double hours = 2.0, speed = 250.0, interval = 60.0, start_x = 1.0e6;
  std::string size = "320x240";
  double heap_range = 0.0;
};

// The weather system along the route, and the view flying through it.
struct Flight {
  Scene scene;
  Camera camera;
  glm::dvec2 wind{12.0, 4.0};
  double start_x = 0.0, speed = 0.0;

  // The world and the view `t` seconds into the flight.
  Scene at(double t) const {
    Scene s = scene;
    s.time_s = t;
    for (CloudField& f : s.fields) f.drift_m = wind * t;
    s.camera = camera;
    s.camera.position = {start_x + speed * t, 0.0, 3200.0};
    return s;
  }
};

// One macrocluster along the route, an altocumulus layer everywhere, drifting with the wind.
Flight flightOf(const FlightOptions& o, const Camera& camera) {
  Flight flight;
  flight.camera = camera;
  flight.start_x = o.start_x;
  flight.speed = o.speed;
  WeatherLayer cumulus = typicalWeatherLayer(CloudType::kCumulus, 0.35);
  cumulus.region.centre = {o.start_x + 0.5 * o.speed * o.hours * 3600.0, 0.0};
  cumulus.region.half_size = {0.5 * o.speed * o.hours * 3600.0 + 200000.0, 150000.0};
  cumulus.region.heading_deg = 90.0;  // its long axis east
  std::swap(cumulus.region.half_size.x, cumulus.region.half_size.y);
  cumulus.region.edge_m = 20000.0;
  cumulus.clusters = {20000.0, 0.6};
  const WeatherClouds heaps = weatherClouds(cumulus, "cu", 5);
  const WeatherClouds cells =
      weatherClouds(typicalWeatherLayer(CloudType::kAltocumulus, 0.3), "ac", 6);
  Scene& scene = flight.scene;
  scene.sun.elevation_deg = 40.0;
  scene.sun.azimuth_deg = 200.0;
  scene.layers = cells.layers;
  scene.fields = heaps.fields;
  for (CloudLayer& l : scene.layers) l.texture.drift_velocity = flight.wind;
  return flight;
}

// Every `interval` simulated seconds two frames 1/30 s apart: a row every tenth sample, and
// the flight's summary.
void flyAndPrint(Renderer& renderer, const Flight& flight, const RenderSettings& settings,
                 const FlightOptions& o, double floor, double start_mib) {
  std::printf("%8s %10s %9s %8s %7s %10s %9s %9s %9s %9s\n", "time s", "x km", "first ms", "ms",
              "xfloor", "ellipsoids", "d cover", "d lum", "d pixel", "RSS MiB");
  double worst_cover = 0.0, worst_luminance = 0.0, worst_pixel = 0.0, total_ms = 0.0;
  double total_first_ms = 0.0, worst_at = 0.0;
  double peak_mib = start_mib;
  int samples = 0;
  for (double t = 0.0; t <= o.hours * 3600.0; t += o.interval, ++samples) {
    const Scene a = flight.at(t), b = flight.at(t + 1.0 / 30.0);
    auto begin = std::chrono::steady_clock::now();
    auto since = [&] {
      return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin)
          .count();
    };
    const FloatImage fa = renderer.renderFloat(a, settings);
    const double first_ms = since();
    begin = std::chrono::steady_clock::now();
    const FloatImage fb = renderer.renderFloat(b, settings);
    const double ms = since();
    const int drawn = renderer.lastFrameStats().ellipsoids_drawn;
    const Means ma = means(fa), mb = means(fb);
    const ImageError e = compareImages(fb, fa);
    const double d_cover = std::abs(ma.cover - mb.cover),
                 d_lum = std::abs(ma.luminance - mb.luminance);
    if (d_cover > worst_cover) worst_at = t;
    worst_cover = std::max(worst_cover, d_cover);
    total_first_ms += first_ms;
    worst_luminance = std::max(worst_luminance, d_lum);
    worst_pixel = std::max(worst_pixel, e.max_abs);
    total_ms += ms;
    peak_mib = std::max(peak_mib, bench::residentMiB());
    if (samples % 10 == 0)
      std::printf("%8.0f %10.1f %9.1f %8.1f %7.1f %10d %9.4f %9.4f %9.3f %9.1f\n", t,
                  a.camera.position.x / 1000.0, first_ms, ms, ms / floor, drawn, d_cover, d_lum,
                  e.max_abs, bench::residentMiB());
    std::fflush(stdout);
  }
  std::printf(
      "%d samples: mean frame %.1f ms (%.1f x floor), %.1f ms on arriving; between frames "
      "1/30 s apart the mean coverage changed by at most %.4f (at %.0f s), the mean "
      "luminance by %.4f, one pixel by %.3f (sRGB); memory %.1f MiB after the first "
      "frame, peak %.1f, end %.1f\n",
      samples, total_ms / samples, total_ms / samples / floor, total_first_ms / samples,
      worst_cover, worst_at, worst_luminance, worst_pixel, start_mib, peak_mib,
      bench::residentMiB());
}

// Precision: GL against the double-precision reference, near the origin and far from it.
void printPrecision(Renderer& renderer, Flight flight, const RenderSettings& settings,
                    const FlightOptions& o) {
  flight.camera.width = 160, flight.camera.height = 120;
  RenderSettings point = settings;
  point.texture_evaluation = TextureEvaluation::kProcedural;
  point.term_filter = TermFilter::kNone;
  ReferenceSettings reference{1, 0, o.heap_range};
  std::printf("precision, 160x120 point-sampled (PSNR dB / largest difference):\n");
  std::printf("%10s %22s %22s %22s\n", "x km", "GL far vs GL origin", "GL far vs reference",
              "GL origin vs reference");
  for (double t : {0.0, o.hours * 3600.0}) {
    const Scene far = flight.at(t);
    Scene near = far;
    const glm::dvec2 shift(-far.camera.position.x, 0.0);
    near.camera.position.x = 0.0;
    for (CloudField& f : near.fields) f.drift_m += shift;
    for (CloudLayer& l : near.layers) l.texture.drift_offset_m += shift;
    const FloatImage gl_far = renderer.renderFloat(far, point);
    const FloatImage gl_near = renderer.renderFloat(near, point);
    const ImageError moved = compareImages(gl_far, gl_near);
    const ImageError e_far = compareImages(gl_far, renderReference(far, reference));
    const ImageError e_near = compareImages(gl_near, renderReference(near, reference));
    std::printf("%10.1f %13.1f / %6.4f %13.1f / %6.4f %13.1f / %6.4f\n",
                far.camera.position.x / 1000.0, moved.psnr_db, moved.max_abs, e_far.psnr_db,
                e_far.max_abs, e_near.psnr_db, e_near.max_abs);
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Nephele long-flight benchmark: two hours at 250 m/s through a macrocluster");
  FlightOptions o;
  app.add_option("--heap-range", o.heap_range, "Heaps as ellipsoids this far, m (0 automatic)")
      ->check(CLI::Range(0.0, 1.0e6))
      ->capture_default_str();
  app.add_option("--hours", o.hours, "Flight time, hours")
      ->check(CLI::Range(0.01, 24.0))
      ->capture_default_str();
  app.add_option("--speed", o.speed, "Ground speed, m/s")
      ->check(CLI::Range(1.0, 1000.0))
      ->capture_default_str();
  app.add_option("--interval", o.interval, "Simulated seconds between samples")
      ->check(CLI::Range(1.0, 3600.0))
      ->capture_default_str();
  app.add_option("--start", o.start_x, "Start, metres east of the origin")
      ->check(CLI::Range(-5.0e7, 5.0e7))
      ->capture_default_str();
  app.add_option("--size", o.size, "Image size WxH")->capture_default_str();
  CLI11_PARSE(app, argc, argv);

  const std::unique_ptr<Renderer> gl = bench::openRenderer();
  if (!gl) return 1;
  Renderer& renderer = *gl;
  Camera camera;
  if (!bench::parseSize(o.size, camera)) return 2;
  camera.orientation = {90.0, -8.0, 0.0};  // east, a little down
  camera.vfov_deg = 60.0;
  const Flight flight = flightOf(o, camera);
  RenderSettings settings;
  settings.heaps.range_m = o.heap_range;
  const double floor =
      medianMilliseconds(5, [&] { renderer.renderFloor(camera.width, camera.height); });
  renderer.renderFloat(flight.at(0.0), settings);  // shaders, textures, the heaps' footprints
  const double start_mib = bench::residentMiB();
  std::printf("flight: %.1f h at %.0f m/s from x = %.0f km, %s, floor %.2f ms\n", o.hours, o.speed,
              o.start_x / 1000.0, o.size.c_str(), floor);
  flyAndPrint(renderer, flight, settings, o, floor, start_mib);
  printPrecision(renderer, flight, settings, o);
  return 0;
}
