// Cost against what is visible (issue 14, item 2): a world of about 100,000 ellipsoids (a grid
// of 25-lobe cumuli over 100 km x 100 km) seen straight down from a height where about 500 of
// them are in view, against a world holding only the clouds that view can see. Prints both
// frame times, their ratio (the target is at most 1.2), the platform floor and multiples of
// it, and the memory the large world takes. A benchmark: it never fails on its figures.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench/bench_common.h"
#include "renderer/gl/gl_renderer.h"
#include "world/formations/ellipsoid_cloud.h"
#include "world/frames.h"

using namespace nephele;

namespace {

// Resident memory of this process, MiB (Linux /proc).
double residentMiB() {
  std::ifstream statm("/proc/self/statm");
  double pages = 0.0, resident = 0.0;
  statm >> pages >> resident;
  return resident * 4096.0 / (1024.0 * 1024.0);
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
  CLI11_PARSE(app, argc, argv);

  const auto platform = bench::openPlatform();
  if (!platform) return 1;
  const double before_mib = residentMiB();
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
  std::size_t total = 0;
  for (const EllipsoidCloud& c : world.clouds) total += c.ellipsoids.size();
  const double world_mib = residentMiB() - before_mib;
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
    // The world of the clouds this view can see (the same test the renderer culls with).
    Scene seen = world;
    const ViewBasis basis = viewBasis(camera);
    std::erase_if(seen.clouds, [&](const EllipsoidCloud& c) {
      const BoundingBox box = boundingBox(c);
      return !boxMayBeInView(basis, camera.position, box.lo, box.hi);
    });
    GlRenderer renderer(*platform);
    const RenderSettings settings;
    const double floor =
        medianMilliseconds(repeats, [&] { renderer.renderFloor(camera.width, camera.height); });
    const double whole =
        medianMilliseconds(repeats, [&] { renderer.renderSrgb8(world, settings); });
    const FrameStats stats = renderer.lastFrameStats();
    const double part = medianMilliseconds(repeats, [&] { renderer.renderSrgb8(seen, settings); });
    std::printf("%-10s %9d %9.2f %9.1f %8.1f %9.1f %9.1f %7.2f %9d\n", size.c_str(),
                stats.ellipsoids_drawn, floor, whole, whole / floor, part, part / floor,
                whole / part, stats.ellipsoids_culled);
    std::fflush(stdout);
  }
  return 0;
}
