// Cost against what is visible (issue 14, item 2), in two parts. World: about 100,000
// ellipsoids (a grid of 25-lobe cumuli over 100 km x 100 km) seen straight down from a height
// where about 500 of them are in view, against a world holding only the clouds that view can
// see; prints both frame times, their ratio (the target is at most 1.2), the platform floor
// and multiples of it, and the memory the large world takes. Horizon: a 300 km macrocluster
// of cumulus seen from 10 km up looking at the horizon, for each heap range (heaps as
// ellipsoids that far, a far deck beyond; MODEL.md section 11): frame time as a multiple of
// the floor (the target is 3 at 1280x1024), heaps drawn, and the error against the CPU
// reference with the automatic range. A benchmark: it never fails on its figures.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench/bench_common.h"
#include "image/image_metrics.h"
#include "renderer/reference/reference_renderer.h"
#include "world/camera.h"
#include "world/formations/ellipsoid_cloud.h"
#include "world/formations/weather.h"

using namespace nephele;

namespace {

// The horizon part: see the file comment.
void horizon(const Renderer& gl, const std::vector<std::string>& sizes, int repeats,
             const std::vector<double>& ranges_km) {
  WeatherLayer w = typicalWeatherLayer(CloudType::kCumulus, 0.4);
  w.region.half_size = {150000.0, 150000.0};
  w.region.edge_m = 15000.0;
  w.clusters = {25000.0, 0.6};
  Scene scene;
  const WeatherClouds add = weatherClouds(w, "front", 3);
  scene.layers = add.layers;
  scene.fields = add.fields;
  scene.sun.elevation_deg = 35.0;
  scene.sun.azimuth_deg = 160.0;
  Camera camera;
  camera.position = {-100000.0, -100000.0, 10000.0};
  camera.orientation = {45.0, -4.0, 0.0};
  camera.vfov_deg = 60.0;
  std::printf(
      "\nhorizon: 300 km cumulus macrocluster (coverage 0.4, clusters 25 km, variation "
      "0.6) from 10 km, pitch -4 degrees\n");
  // The reference: the CPU renderer with the automatic heap range, at a size it can afford.
  Camera small = camera;
  small.width = 256, small.height = 192;
  scene.camera = small;
  const double before = bench::residentMiB();
  const FloatImage reference = renderReference(scene, {});
  std::printf("reference 256x192 4x4, automatic range (%.0f km)\n",
              heapRange(scene.fields[0], small) / 1000.0);
  std::printf("%-10s %9s %9s %9s %8s %10s %8s %10s %10s\n", "size", "range km", "floor ms",
              "frame ms", "xfloor", "ellipsoids", "PSNR dB", "row cover", "row lum");
  const std::unique_ptr<Renderer> fresh = gl.another();
  Renderer& renderer = *fresh;
  for (double km : ranges_km) {
    RenderSettings settings;
    settings.heaps.range_m = km * 1000.0;
    scene.camera = small;
    const FloatImage image = renderer.renderFloat(scene, settings);
    const ImageError error = compareImages(image, reference);
    const ProfileError profile = rowProfileError(image, reference);
    for (const std::string& size : sizes) {
      if (!bench::parseSize(size, camera)) return;
      scene.camera = camera;
      const double floor =
          medianMilliseconds(repeats, [&] { renderer.renderFloor(camera.width, camera.height); });
      const double ms = medianMilliseconds(repeats, [&] { renderer.renderSrgb8(scene, settings); });
      std::printf("%-10s %9s %9.2f %9.1f %8.1f %10d %8.1f %10.3f %10.3f\n", size.c_str(),
                  km > 0.0 ? std::to_string(int(km)).c_str() : "auto", floor, ms, ms / floor,
                  renderer.lastFrameStats().ellipsoids_drawn, error.psnr_db, profile.cover,
                  profile.luminance);
      std::fflush(stdout);
    }
  }
  std::printf("resident memory grew %.1f MiB over the horizon runs\n",
              bench::residentMiB() - before);
}

// A square world `side_km` across of cumulus clouds of 25 ellipsoids, `spacing_m` apart.
Scene gridWorld(double side_km, double spacing_m) {
  Scene world;
  world.sun.elevation_deg = 50.0;
  const int per_side = int(side_km * 1000.0 / spacing_m);
  for (int j = 0; j < per_side; ++j)
    for (int i = 0; i < per_side; ++i) {
      EllipsoidCloud cloud;
      cloud.name = "c";
      cloud.name += std::to_string(j * per_side + i);
      cloud.texture.gardner.fx1 = cloud.texture.gardner.fy1 = 2.0e-3;
      const glm::dvec3 base((i - 0.5 * (per_side - 1)) * spacing_m,
                            (j - 0.5 * (per_side - 1)) * spacing_m, 1000.0);
      cloud.ellipsoids = cumulusEllipsoids(25, base, 0.6 * spacing_m, std::uint64_t(j * 7919 + i));
      world.clouds.push_back(std::move(cloud));
    }
  return world;
}

// The whole world's frame against that of the clouds its camera can see (the same test the
// renderer culls with), both as multiples of the floor: one row of the table.
void benchWorldView(const Renderer& gl, const Scene& world, const std::string& size, int repeats) {
  const Camera& camera = world.camera;
  Scene seen = world;
  const ViewBasis basis = viewBasis(camera);
  std::erase_if(seen.clouds, [&](const EllipsoidCloud& c) {
    const BoundingBox box = boundingBox(c);
    return !boxMayBeInView(basis, camera.position, box.lo, box.hi);
  });
  const std::unique_ptr<Renderer> fresh = gl.another();
  Renderer& renderer = *fresh;
  const RenderSettings settings;
  const double floor =
      medianMilliseconds(repeats, [&] { renderer.renderFloor(camera.width, camera.height); });
  const double whole = medianMilliseconds(repeats, [&] { renderer.renderSrgb8(world, settings); });
  const FrameStats stats = renderer.lastFrameStats();
  const double part = medianMilliseconds(repeats, [&] { renderer.renderSrgb8(seen, settings); });
  std::printf("%-10s %9d %9.2f %9.1f %8.1f %9.1f %9.1f %7.2f %9d\n", size.c_str(),
              stats.ellipsoids_drawn, floor, whole, whole / floor, part, part / floor, whole / part,
              stats.ellipsoids_culled);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Nephele scale benchmark: a 100,000-ellipsoid world against the part in view");
  double side_km = 100.0, spacing_m = 1600.0, height_m = 6500.0;
  int repeats = 7;
  std::vector<std::string> sizes{"640x480", "1280x1024"};
  app.add_option("--side", side_km, "Side of the square world, km")
      ->check(CLI::Range(1.0, 1000.0))
      ->capture_default_str();
  app.add_option("--spacing", spacing_m, "Distance between cloud centres, metres")
      ->check(CLI::Range(500.0, 1.0e5))
      ->capture_default_str();
  app.add_option("--height", height_m, "Camera altitude, metres (looking straight down)")
      ->check(CLI::Range(2500.0, 1.0e5))
      ->capture_default_str();
  app.add_option("--repeats", repeats, "Frames per median")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  app.add_option("--sizes", sizes, "Image sizes WxH")->delimiter(',');
  std::vector<double> ranges_km{0.0, 20.0, 10.0, 5.0};
  app.add_option("--ranges", ranges_km, "Horizon part: heap ranges, km (0 automatic)")
      ->delimiter(',');
  bool world_part = true, horizon_part = true;
  app.add_flag("!--no-world", world_part, "Skip the 100,000-ellipsoid part");
  app.add_flag("!--no-horizon", horizon_part, "Skip the horizon part");
  CLI11_PARSE(app, argc, argv);

  const std::unique_ptr<Renderer> gl = bench::openRenderer();
  if (!gl) return 1;
  if (!world_part) {
    if (horizon_part) horizon(*gl, sizes, repeats, ranges_km);
    return 0;
  }
  const double before_mib = bench::residentMiB();
  Scene world = gridWorld(side_km, spacing_m);
  const std::size_t total = ellipsoidCount(world);
  const double world_mib = bench::residentMiB() - before_mib;
  std::printf("world: %zu clouds, %zu ellipsoids over %.0f km x %.0f km; %.1f MiB resident\n",
              world.clouds.size(), total, side_km, side_km, world_mib);
  std::printf("%-10s %9s %9s %9s %8s %9s %9s %7s %9s\n", "size", "in view", "floor ms", "world ms",
              "xfloor", "view ms", "xfloor", "ratio", "culled");
  for (const std::string& size : sizes) {
    Camera camera;
    if (!bench::parseSize(size, camera)) return 2;
    camera.position = {0.0, 0.0, height_m};
    camera.orientation = {0.0, -90.0, 0.0};
    camera.vfov_deg = 60.0;
    world.camera = camera;
    benchWorldView(*gl, world, size, repeats);
  }
  if (horizon_part) horizon(*gl, sizes, repeats, ranges_km);
  return 0;
}
