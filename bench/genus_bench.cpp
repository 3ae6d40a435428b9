// Genus benchmark (issue 13): the frame time of every genus preset, and of the cloudscape,
// from below, inside and above the layer, still and flying, as multiples of the platform
// floor timed in the same run. A program that prints figures, not a test: these machines
// are shared and noisy, and multiples of the floor move much less than milliseconds.
//
//   genus_bench [--sizes 640x480,1280x1024] [--repeats N] [--presets genus_cumulus,...]
//
// "still" is the median of N frames of one view once the renderer holds it: after a warm-up
// frame and, for layers read from clipmaps (MODEL.md section 2), the frames that fill them,
// whose count and median are printed beneath. "flying" is a view moving east at 250 m/s
// rendered at 30 Hz for N frames, 50 km from the still view, by a renderer that has drawn the
// still view once (programs compiled, textures baked): the median and the slowest frame, so
// the cost of generating new heap tiles and of filling new clipmaps shows. "warm flying" is
// the same flight 2 s on: the median and slowest of the N frames after 60, when the clipmaps
// are whole and follow the camera by strips. A flight is a continuous view, as a daemon's
// subscription is: its heaps reuse the last frame (heap_refresh, --heap-refresh), and the frame
// after the warm flight is compared with the exact frame of its pose. --speed 0 streams the
// still view instead.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <CLI/CLI.hpp>

#include "bench/bench_common.h"
#include "config/scene_file.h"
#include "image/cloud_statistics.h"
#include "image/image.h"
#include "image/image_encoding.h"
#include "image/image_metrics.h"
#include "renderer/reference/reference_renderer.h"
#include "world/formations/cloud_field.h"
#include "world/formations/weather.h"
#include "world/world.h"

namespace {

using namespace nephele;
using Clock = std::chrono::steady_clock;

struct View {
  const char* name;
  Camera camera;
};

// The preset's own view (from the ground), one inside the highest formation and one 1.5 km
// above its top. A formation is a field of heaps or the planes of one weather layer (named
// "weather/N" and "weather/N/k", spread through its thickness); a genus drawn as one plane
// has no inside, and its "inside" view is that plane seen edge on.
std::vector<View> viewsOf(const SceneFile& file) {
  std::vector<View> views{{"below", file.scene.camera}};
  double base = 0.0, top = 0.0;
  std::string top_layer;
  for (const CloudLayer& layer : file.scene.layers)
    if (layer.altitude_m > top) top = base = layer.altitude_m, top_layer = layer.name;
  const std::string group = top_layer.substr(0, top_layer.find('/', top_layer.find('/') + 1));
  for (const CloudLayer& layer : file.scene.layers)
    if (layer.name.starts_with(group)) base = std::min(base, layer.altitude_m);
  for (const CloudField& field : file.scene.fields)
    if (field.base_m + field.thickness_m > top)
      base = field.base_m, top = field.base_m + field.thickness_m;
  if (top <= 0.0) return views;  // no weather layer or field: only the preset's own view
  Camera inside = file.scene.camera;
  inside.position.z = 0.5 * (base + top);
  inside.orientation.pitch_deg = 0.0;
  views.push_back({"inside", inside});
  Camera above = file.scene.camera;
  above.position.z = top + 1500.0;
  above.orientation.pitch_deg = -20.0;
  views.push_back({"above", above});
  return views;
}

// Clouds smaller than this many pixels are left out of the body figures.
constexpr int kMinCloudPixels = 64;

struct BodyFigure {
  int inner = 0, opaque = 0;  // pixels in the inner half, and of those with coverage > 0.95
  double luminance = 0.0;     // mean linear luminance over the inner half
  glm::dvec2 centroid{0.0};   // pixels
};

// The region's inner half is its outline shrunk to half its size about its centroid: pixel p
// is in it when centroid + 2 (p - centroid) lies in the region.
BodyFigure bodyFigure(const FloatImage& image, const std::vector<int>& region) {
  const int w = image.width, h = image.height;
  std::vector<char> in(std::size_t(w) * h, 0);
  BodyFigure f;
  for (int p : region) {
    in[p] = 1;
    f.centroid += glm::dvec2(p % w, p / w);
  }
  f.centroid /= double(region.size());
  for (int p : region) {
    const glm::dvec2 q = f.centroid + 2.0 * (glm::dvec2(p % w, p / w) - f.centroid);
    const int qx = int(std::lround(q.x)), qy = int(std::lround(q.y));
    if (qx < 0 || qy < 0 || qx >= w || qy >= h || !in[qy * w + qx]) continue;
    const float* c = &image.rgba[4 * std::size_t(p)];
    ++f.inner;
    f.opaque += c[3] > 0.95f;
    f.luminance += bench::linearLuminance(c[0], c[1], c[2]);
  }
  f.luminance /= std::max(f.inner, 1);
  return f;
}

// Cumulus body figures (issue 13): the heaps of a few tiles near the origin, each seen
// straight down from far above (near-orthographic) and straight up from the ground under its
// middle; per heap the fraction of its inner half that is opaque (coverage > 0.95), and the
// luminance of its underside against that of its sunlit top.
void printBodyFigures(Renderer& renderer, const SceneFile& file) {
  if (file.scene.fields.empty()) return;
  const CloudField& field = file.scene.fields.front();
  const double tile = fieldTileSize(field);
  int inner = 0, opaque = 0, heaps = 0;
  double top_sum = 0.0, under_sum = 0.0, worst = 1.0;
  for (std::int64_t i = -1; i <= 1; ++i)
    for (std::int64_t j = -1; j <= 1; ++j) {
      Scene scene = file.scene;
      scene.haze.reset();  // the figures are of the clouds' own light, not of the air
      scene.fields.clear();
      scene.layers.clear();
      scene.clouds = tileClouds(field, i, j);
      if (scene.clouds.empty()) continue;
      // Straight down onto the tile and a margin around it.
      const double span = 2.0 * tile;
      const glm::dvec2 middle = (glm::dvec2(i, j) + 0.5) * tile;
      Camera& c = scene.camera;
      c = nadirCamera(middle, field.base_m, field.thickness_m, span, 384);
      const FloatImage top = renderer.renderFloat(scene, file.render);
      for (const CloudRegion& region : cloudRegions(top, kMinCloudPixels)) {
        const BodyFigure above = bodyFigure(top, region.pixels);
        // Image x runs east, rows run south from the top.
        const glm::dvec2 xy = middle + span * glm::dvec2((above.centroid.x + 0.5) / c.width - 0.5,
                                                         0.5 - (above.centroid.y + 0.5) / c.height);
        Scene up = scene;
        up.camera.position = glm::dvec3(xy, 2.0);
        up.camera.orientation = {0.0, 90.0, 0.0};
        up.camera.vfov_deg = 120.0;
        up.camera.width = up.camera.height = 256;
        const FloatImage below = renderer.renderFloat(up, file.render);
        // The heap overhead: the region holding the image centre.
        const std::vector<CloudRegion> regions = cloudRegions(below, kMinCloudPixels);
        const int centre = (up.camera.height / 2) * up.camera.width + up.camera.width / 2;
        const auto hit = std::find_if(regions.begin(), regions.end(), [&](const CloudRegion& r) {
          return std::find(r.pixels.begin(), r.pixels.end(), centre) != r.pixels.end();
        });
        if (hit == regions.end()) continue;
        const BodyFigure under = bodyFigure(below, hit->pixels);
        ++heaps;
        inner += above.inner + under.inner;
        opaque += above.opaque + under.opaque;
        worst = std::min({worst, double(above.opaque) / std::max(above.inner, 1),
                          double(under.opaque) / std::max(under.inner, 1)});
        top_sum += above.luminance;
        under_sum += under.luminance;
      }
    }
  if (heaps == 0) return;
  std::printf(
      "  body: %d heaps; inner half opaque (coverage > 0.95): %.3f of pixels (worst heap view "
      "%.3f); luminance underside %.3f, sunlit top %.3f, ratio %.2f\n",
      heaps, double(opaque) / std::max(inner, 1), worst, under_sum / heaps, top_sum / heaps,
      under_sum / std::max(top_sum, 1e-9));
}

// A cloud's own light per unit opacity at pixel p: the frame is alpha C + (1 - alpha) sky, so
// C = (frame - (1 - alpha) sky) / alpha, as linear luminance.
double ownLuminance(const FloatImage& frame, const FloatImage& sky, int p) {
  const float* c = &frame.rgba[4 * std::size_t(p)];
  const float* s = &sky.rgba[4 * std::size_t(p)];
  const double alpha = c[3];
  auto own = [&](int k) { return (c[k] - (1.0 - alpha) * s[k]) / alpha; };
  return bench::linearLuminance(own(0), own(1), own(2));
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

// The heap's view of printLightFigures side-lit at the benchmark's frame sizes: the outline's
// detail the texture draws at 640x480 and 1280x1024 (issue 47 item 5).
void printOutlinesAtFrameSizes(Renderer& renderer, const Scene& scene,
                               const RenderSettings& render) {
  for (const glm::ivec2 size : {glm::ivec2(640, 480), glm::ivec2(1280, 1024)}) {
    Scene sized = scene;
    sized.sun.azimuth_deg = 90.0, sized.sun.elevation_deg = 10.0;
    sized.camera.width = size.x, sized.camera.height = size.y;
    std::vector<int> silhouette;
    for (const CloudRegion& region :
         cloudRegions(renderer.renderFloat(sized, render), kMinCloudPixels))
      if (region.pixels.size() > silhouette.size()) silhouette = region.pixels;
    const OutlineFigures f = outlineFigures(silhouette, size.x, size.y);
    std::printf("  outline at %dx%d: %zu px, dimension %.3f, %.2f within a pixel of its ellipse\n",
                size.x, size.y, silhouette.size(), f.dimension, f.near_ellipse);
  }
}

// Light figures of a heap (issue 27, MODEL.md section 14): the field's typical heap
// (typicalHeap) alone, seen level from 8 km or three times its size, whichever is further. (b) With
// the sun 90 degrees to the right at 10 degrees up, the median luminance of the right (sunlit) half
// of its largest connected silhouette (coverage > 0.5) over its left half, split at the
// silhouette's centroid column. (c) With the sun 12 degrees above the line to the heap's middle,
// behind it, the median light per unit opacity of its thin edge (coverage 0.05 to 0.5) over its
// body's (coverage > 0.95): a silver lining is > 1. (a) On the side-lit view's silhouette, its
// outline's dimension and the fraction of it within a pixel of its moment ellipse
// (outlineFigures, image/cloud_statistics.h).
void printLightFigures(Renderer& renderer, const SceneFile& file, const std::string& name,
                       const std::string& images) {
  if (file.scene.fields.empty()) return;
  const CloudField& field = file.scene.fields.front();
  const EllipsoidCloud heap = typicalHeap(field, {0.0, 0.0, field.base_m});
  if (heap.ellipsoids.empty()) return;
  const BoundingBox box = boundingBox(heap);
  const glm::dvec3 middle = 0.5 * (box.lo + box.hi);
  const double widest = box.hi.x - box.lo.x;
  const double size = std::max(box.hi.z - box.lo.z, widest);
  const double distance = std::max(8000.0, 3.0 * size);
  Scene scene = file.scene;
  scene.haze.reset();  // the figures are of the clouds' own light, not of the air
  scene.fields.clear();
  scene.layers.clear();
  scene.clouds = {heap};
  Camera& c = scene.camera;
  c.width = 480, c.height = 360;
  c.position = middle - glm::dvec3(0.0, distance, 0.0);  // looking north at it
  c.orientation = {0.0, 0.0, 0.0};
  c.vfov_deg = 2.0 * glm::degrees(std::atan(0.7 * size / distance));
  Scene clear = scene;
  clear.clouds.clear();

  scene.sun.azimuth_deg = 90.0, scene.sun.elevation_deg = 10.0;  // to the right (east)
  const FloatImage side = renderer.renderFloat(scene, file.render);
  const FloatImage side_sky = renderer.renderFloat(Scene(clear), file.render);
  // The figure is taken on the largest connected silhouette, so that a stray fragment of the
  // heap's edge does not move the split between its two sides.
  std::vector<int> covered;
  for (const CloudRegion& region : cloudRegions(side, kMinCloudPixels))
    if (region.pixels.size() > covered.size()) covered = region.pixels;
  double centroid = 0.0;
  for (int p : covered) centroid += p % c.width;
  centroid /= std::max<std::size_t>(covered.size(), 1);
  std::vector<double> lit, away;
  for (int p : covered)
    (p % c.width >= centroid ? lit : away).push_back(ownLuminance(side, side_sky, p));

  scene.sun.azimuth_deg = 0.0;  // behind it, 12 degrees above the line to its middle
  scene.sun.elevation_deg = 12.0;
  clear.sun = scene.sun;
  const FloatImage back = renderer.renderFloat(scene, file.render);
  const FloatImage back_sky = renderer.renderFloat(clear, file.render);
  if (!images.empty()) {  // the two views the figures are measured on, to look at
    std::filesystem::create_directories(images);
    for (const auto& [view, image] : {std::pair{"side_lit", &side}, {"back_lit", &back}})
      if (const std::string error =
              writeImageFile(images + "/" + name + "_" + view + ".png", *image);
          !error.empty())
        std::fprintf(stderr, "%s\n", error.c_str());
  }
  std::vector<double> edge, body;
  for (int p = 0; p < c.width * c.height; ++p) {
    const float alpha = back.rgba[4 * std::size_t(p) + 3];
    if (alpha > 0.05f && alpha < 0.5f) edge.push_back(ownLuminance(back, back_sky, p));
    if (alpha > 0.95f) body.push_back(ownLuminance(back, back_sky, p));
  }
  const OutlineFigures outline = outlineFigures(covered, c.width, c.height);
  std::printf(
      "  outline: heap seen level from %.1f km, %zu px: dimension %.3f (ellipse 1.0, cumulus "
      "1.3 to 1.4), %.2f of the outline within a pixel of its moment ellipse\n",
      distance / 1000.0, covered.size(), outline.dimension, outline.near_ellipse);
  printOutlinesAtFrameSizes(renderer, scene, file.render);
  std::printf(
      "  light: heap of %zu ellipsoids, %.0f m wide; sun 90 deg to the side: sunlit half / "
      "shadowed half %.2f (%zu, %zu px); sun 12 deg behind: thin edge / body per unit opacity "
      "%.2f (%zu, %zu px)\n",
      heap.ellipsoids.size(), widest, median(lit) / std::max(median(away), 1e-9), lit.size(),
      away.size(), median(edge) / std::max(median(body), 1e-9), edge.size(), body.size());
}

// Where a cumulonimbus's tower lies in its view across the shear (printCumulonimbusFigures):
// its covered rows in the column through the base's middle, and its run at 0.45 of its height.
struct TowerInView {
  int top = -1, bottom = -1, mid_row = 0, lo = 0, hi = -1;
};

// The shape across the shear: coverage > 0.5 in the column `axis` (through the base's middle)
// from the lowest to the highest covered row (a continuous tower has no uncovered row in it);
// the tower's width at 0.45 of that height; the widest run of the top fifth (the anvil), its
// width over the tower's and how far its middle lies downwind of the base. None: the column
// is clear.
std::optional<TowerInView> printCumulonimbusShape(const FloatImage& image, int axis,
                                                  double metres_per_px, double speed) {
  const int width = image.width, height = image.height;
  auto covered = [&](int x, int y) { return image.pixel(x, y)[3] > 0.5f; };
  TowerInView t;
  for (int y = 0; y < height; ++y)
    if (covered(axis, y)) t.bottom = y, t.top = t.top < 0 ? y : t.top;
  if (t.top < 0) return std::nullopt;
  int gaps = 0;
  for (int y = t.top; y <= t.bottom; ++y) gaps += !covered(axis, y);
  // The covered run through column x of row y, or through its widest part when x is clear.
  auto run = [&](int y, int x) {
    int lo = x, hi = x;
    while (lo > 0 && covered(lo - 1, y)) --lo;
    while (hi + 1 < width && covered(hi + 1, y)) ++hi;
    return std::pair{lo, hi};
  };
  t.mid_row = t.bottom - int(0.45 * (t.bottom - t.top));
  std::tie(t.lo, t.hi) = run(t.mid_row, axis);
  int anvil_lo = 0, anvil_hi = -1;
  for (int y = t.top; y <= t.top + (t.bottom - t.top) / 5; ++y)
    for (int x = 0; x < width; ++x)
      if (covered(x, y)) {
        const auto [lo, hi] = run(y, x);
        if (hi - lo > anvil_hi - anvil_lo) anvil_lo = lo, anvil_hi = hi;
        x = hi;
      }
  const double tower = (t.hi - t.lo + 1) * metres_per_px;
  const double anvil = (anvil_hi - anvil_lo + 1) * metres_per_px;
  std::printf(
      "  cumulonimbus alone across the shear (%.1f m/s): column through the base, %d of %d rows "
      "uncovered; tower %.0f m wide at 0.45 of its height, anvil %.0f m wide (%.1f times), its "
      "middle %.0f m downwind of the base\n",
      speed, gaps, t.bottom - t.top + 1, tower, anvil, anvil / std::max(tower, 1.0),
      (0.5 * (anvil_lo + anvil_hi) - axis) * metres_per_px);
  return t;
}

// The cloud's own luminance (ownLuminance) in `view`, without the haze, over the opaque pixels
// (x, y) for which `inside` holds: their median and how many.
template <class Inside>
std::pair<double, std::size_t> ownMedian(Renderer& renderer, Scene view, Inside inside,
                                         const RenderSettings& settings) {
  view.haze.reset();
  const FloatImage frame = renderer.renderFloat(view, settings);
  view.clouds.clear();
  const FloatImage sky = renderer.renderFloat(view, settings);
  std::vector<double> own;
  for (int y = 0; y < view.camera.height; ++y)
    for (int x = 0; x < view.camera.width; ++x)
      if (inside(x, y) && frame.pixel(x, y)[3] > 0.95f)
        own.push_back(ownLuminance(frame, sky, y * view.camera.width + x));
  return std::pair{median(own), own.size()};
}

// The base against the sunlit tower (issue 47 item 5): the cloud's own luminance straight up
// from the ground under the base's middle in a 20 degree view, and on the tower's face in the
// view across the shear (`scene`, looking along `forward`) with the sun behind the camera (the
// tower's rows from its foot to 0.45 of its height, within its width there); medians over
// opaque pixels, without the haze (120 km of it would stand for the cloud's own light).
void printCumulonimbusBase(Renderer& renderer, const SceneFile& file, const Scene& scene,
                           glm::dvec3 base, glm::dvec3 forward, const TowerInView& tower) {
  Scene lit = scene;
  lit.sun.azimuth_deg = glm::degrees(std::atan2(-forward.x, -forward.y));
  auto onFace = [&](int x, int y) {
    return y >= tower.mid_row && y <= tower.bottom && x >= tower.lo && x <= tower.hi;
  };
  const auto [face, face_px] = ownMedian(renderer, lit, onFace, file.render);
  // The same without the heaps' shadows (shadow_map_size 0): the tower's own light alone, where
  // the anvil's upwind overhang does not shadow its face.
  RenderSettings unshadowed = file.render;
  unshadowed.shadow_map_size = 0;
  const double own_face = ownMedian(renderer, lit, onFace, unshadowed).first;
  Scene up = scene;
  up.camera.position = base + glm::dvec3(0.0, 0.0, 2.0 - base.z);
  up.camera.orientation = {0.0, 90.0, 0.0};
  up.camera.vfov_deg = 20.0;
  up.camera.width = up.camera.height = 64;
  const auto [under, under_px] = ownMedian(
      renderer, up, [](int, int) { return true; }, file.render);
  std::printf(
      "  cumulonimbus base from below %.3f (%zu px), sunlit tower %.3f (%zu px, sun behind the "
      "camera): ratio %.2f (aim at most 0.3); without the heaps' shadows on the tower %.3f, "
      "ratio %.2f\n",
      under, under_px, face, face_px, under / std::max(face, 1e-9), own_face,
      under / std::max(own_face, 1e-9));
}

// Cumulonimbus figures (issue 27 item 5d): the field's typical heap alone (with the shear the
// world's wind gives it), seen level across the shear from 120 km, downwind to the right, with
// the preset's sun: its shape (printCumulonimbusShape), then its base against its sunlit tower
// (printCumulonimbusBase).
void printCumulonimbusFigures(Renderer& renderer, const SceneFile& file, const std::string& name,
                              const std::string& images) {
  const Scene world = World(file.scene, file.dynamics).scene();
  if (world.fields.empty() || world.fields.front().type != CloudType::kCumulonimbus) return;
  const CloudField& field = world.fields.front();
  const glm::dvec3 base(0.0, 0.0, field.base_m);
  Scene scene = file.scene;
  scene.fields.clear();
  scene.layers.clear();
  scene.clouds = {typicalHeap(field, base)};
  const double speed = glm::length(field.shear);
  const glm::dvec2 downwind = speed > 0.0 ? field.shear / speed : glm::dvec2(1.0, 0.0);
  // Aimed a thickness downwind of the base, so that an anvil reaching three thicknesses
  // downwind and one upwind fits the 4:3 frame.
  constexpr double kDistance = 120000.0;
  const double aside = field.thickness_m;
  Camera& c = scene.camera;
  c.width = 480, c.height = 360;
  c.orientation = {glm::degrees(std::atan2(-downwind.y, downwind.x)), 0.0, 0.0};  // right: downwind
  const glm::dvec3 forward(-downwind.y, downwind.x, 0.0);
  c.position = base + glm::dvec3(aside * downwind, 0.55 * field.thickness_m) - kDistance * forward;
  c.vfov_deg = 2.0 * glm::degrees(std::atan(1.6 * field.thickness_m / kDistance));
  const FloatImage image = renderer.renderFloat(scene, file.render);
  if (!images.empty()) {
    std::filesystem::create_directories(images);
    if (const std::string error = writeImageFile(images + "/" + name + "_across_shear.png", image);
        !error.empty())
      std::fprintf(stderr, "%s\n", error.c_str());
  }
  const double tan_half = std::tan(glm::radians(c.vfov_deg) / 2.0);
  const double metres_per_px = 2.0 * kDistance * tan_half / c.height;
  const int axis = int(c.width / 2 - aside / metres_per_px);  // the base's middle
  const std::optional<TowerInView> tower =
      printCumulonimbusShape(image, axis, metres_per_px, speed);
  if (tower) printCumulonimbusBase(renderer, file, scene, base, forward, *tower);
}

// Rain shafts (issue 47 item 5; MODEL.md section 17): the field's typical heap raining at 1, 4
// and 25 mm/h, and a boat 40 m long on the ground behind its shaft's axis, seen level from 50 m
// up 6 km before the axis on the other side. The boat's mean value in the visibility channel
// (the GL's), against exp(-tau) on the ray through the boat's middle with tau the shaft's exact
// optical depth; and the equivalent path tau / sigma against the Koschmieder range 3.912 /
// sigma of the rate, the visibility the same rain would leave filling the air.
void printRainFigures(Renderer& renderer, const SceneFile& file) {
  const Scene world = World(file.scene, file.dynamics).scene();
  if (world.fields.empty()) return;
  CloudField field = world.fields.front();
  const glm::dvec3 base(0.0, 0.0, field.base_m);
  for (double rate : {1.0, 4.0, 25.0}) {
    field.precipitation = {PrecipitationKind::kRain, rate, 0.0};
    Scene scene = file.scene;
    scene.weather.clear();
    scene.fields.clear();
    scene.layers.clear();
    scene.haze.reset();
    scene.clouds = {typicalHeap(field, base)};
    const RainShaft shaft = heapRainShaft(field, base);
    scene.rain_shafts = {shaft};
    const glm::dvec3 boat(shaft.centre + glm::dvec2(0.0, shaft.radius_m + 500.0), 4.0);
    Target target;
    target.name = "boat";
    target.centre = boat;
    target.size = {20.0, 8.0, 4.0};
    scene.targets = {target};
    Camera& c = scene.camera;
    c.width = 320, c.height = 240;
    c.position = glm::dvec3(shaft.centre - glm::dvec2(0.0, 6000.0), 50.0);
    c.orientation = {0.0, 0.0, 0.0};
    c.vfov_deg = 2.0;
    FrameRequest request;
    request.channels = {Channel::kVisibility, Channel::kObjectId};
    const Frame frame = renderer.render(scene, file.render, request);
    double sum = 0.0;
    int pixels = 0;
    for (std::size_t i = 0; i < frame.visibility.size(); ++i)
      if (frame.object_id[i] != 0) sum += frame.visibility[i], ++pixels;
    const glm::dvec3 ray = boat - c.position;
    const double tau = shaftOpticalDepth(shaft, c.position, glm::normalize(ray), glm::length(ray));
    std::printf(
        "  rain shaft at %.0f mm/h (radius %.0f m, sigma %.2e per m): boat behind it visibility "
        "%.4f over %d px, exp(-tau) %.4f on its middle ray; path %.0f m in the shaft's core "
        "equivalent, Koschmieder range %.0f m\n",
        rate, shaft.radius_m, shaft.sigma, pixels > 0 ? sum / pixels : 0.0, pixels, std::exp(-tau),
        tau / shaft.sigma, visibilityForExtinction(shaft.sigma));
  }
}

// Fraction of the sky hemisphere seen from the ground whose coverage exceeds one half, from
// the five upper faces of a cube map (each pixel weighted by its solid angle, proportional to
// (1 + u^2 + v^2)^-3/2 on a face at unit distance), averaged over four places 20 km apart.
// The ground's cloud shadows (MODEL.md section 16) under the preset's first field, seen from
// 4 km above its top at 60 degrees down with the preset's sun: how far the GL's shadow map
// agrees with the reference's exact sunlight (shadowAgreement, image/cloud_statistics.h, at
// 320x240 with one sample a pixel) and what the shadows cost at 640x480: the frame whose map
// is drawn anew (every frame of a world that ticks, or whose sun moves), the frame that reuses
// it (the other views of one eye at one tick), against the frame without shadows.
void printShadowFigures(const Renderer& base, const SceneFile& file, const std::string& name,
                        int repeats, const std::string& images) {
  if (file.scene.fields.empty()) return;
  const CloudField& field = file.scene.fields.front();
  Scene scene = World(file.scene, file.dynamics).scene();
  Camera& c = scene.camera;
  c.position = {0.0, 0.0, fieldTop(field) + 4000.0};
  c.orientation = {file.scene.camera.orientation.heading_deg, -60.0, 0.0};
  c.width = 320, c.height = 240;
  const std::unique_ptr<Renderer> fresh = base.another();
  Renderer& renderer = *fresh;
  RenderSettings none = file.render;
  none.shadow_map_size = 0;
  RenderSettings exact = file.render;
  exact.heap_shading_rate = 1;
  const FloatImage gl = renderer.renderFloat(scene, exact);
  const FloatImage unshadowed = renderer.renderFloat(scene, none);
  const FloatImage reference = renderReference(scene, {1, 0, file.render.heaps});
  const ShadowAgreement forward = shadowAgreement(gl, reference, unshadowed);
  const ShadowAgreement backward = shadowAgreement(reference, gl, unshadowed);
  if (!images.empty()) {
    std::filesystem::create_directories(images);
    for (const auto& [what, image] : {std::pair{"gl", &gl}, {"reference", &reference}})
      if (const std::string e =
              writeImageFile(images + "/" + name + "_shadows_" + what + ".png", *image);
          !e.empty())
        std::fprintf(stderr, "%s\n", e.c_str());
  }
  c.width = 640, c.height = 480;
  renderer.renderSrgb8(scene, file.render);
  const double without = medianMilliseconds(repeats, [&] { renderer.renderSrgb8(scene, none); });
  const double reused =
      medianMilliseconds(repeats, [&] { renderer.renderSrgb8(scene, file.render); });
  int step = 0;
  double map_ms = 0.0;
  const double redrawn = medianMilliseconds(repeats, [&] {
    scene.sun.azimuth_deg += 0.01 * (++step % 2 ? 1.0 : -1.0);  // the map is drawn anew
    renderer.renderSrgb8(scene, file.render);
    map_ms = renderer.lastFrameStats().times.gpu(GpuPass::kShadows);
  });
  std::printf(
      "  shadows from above (%s, sun at %.0f degrees): of the ground the GL shadows, %.3f is "
      "shadowed by the reference too (of the reference's, %.3f by the GL); ratio to the "
      "unshadowed ground %.4f apart on average; %.2f of the ground in shadow\n"
      "  shadows' cost at 640x480: map drawn anew %.2f ms (%.2f x the frame without shadows, "
      "%.2f ms; the map's pass %.2f ms), map reused %.2f ms (%.2f x)\n",
      name.c_str(), file.scene.sun.elevation_deg, forward.agreement, backward.agreement,
      forward.mean_ratio_difference, forward.shadowed, redrawn, redrawn / without, without, map_ms,
      reused, reused / without);
}

double hemisphereFraction(Renderer& renderer, const Scene& weather, const RenderSettings& render) {
  constexpr int kFace = 128;
  double cloudy = 0.0, total = 0.0;
  for (int place = 0; place < 4; ++place) {
    Scene scene = weather;
    scene.camera.position = {20000.0 * (place % 2), 20000.0 * (place / 2), 2.0};
    scene.camera.vfov_deg = 90.0;
    scene.camera.width = scene.camera.height = kFace;
    for (int face = 0; face < 5; ++face) {
      scene.camera.orientation =
          face == 4 ? Orientation{0.0, 90.0, 0.0} : Orientation{90.0 * face, 0.0, 0.0};
      const FloatImage image = renderer.renderFloat(scene, render);
      for (int y = 0; y < kFace; ++y) {
        const double v = 1.0 - 2.0 * (y + 0.5) / kFace;
        if (face < 4 && v <= 0.0) continue;  // below the horizon
        for (int x = 0; x < kFace; ++x) {
          const double u = 2.0 * (x + 0.5) / kFace - 1.0;
          const double w = std::pow(1.0 + u * u + v * v, -1.5);
          total += w;
          cloudy += image.pixel(x, y)[3] > 0.5f ? w : 0.0;
        }
      }
    }
  }
  return cloudy / total;
}

// Automaton clouds' underside against their sunlit top (MODEL.md section 6, sky light): each
// automaton of the harbour preset seen straight up from the ground under its middle and
// straight down from 2 km above it; mean luminance over the inner half of its outline.
void printAutomatonFigures(Renderer& renderer) {
  SceneFile file;
  if (!bench::loadPreset(NEPHELE_SOURCE_DIR "/config/scenes/harbour.toml", file)) return;
  file.scene.fog.reset();  // the sea fog lies below the clouds; it would grey the view down
  const Scene world = World(file.scene, file.dynamics).scene();
  double under_sum = 0.0, top_sum = 0.0;
  int clouds = 0;
  for (const AutomatonCloudView& cloud : world.automata) {
    const glm::dvec3 middle = 0.5 * (cloud.lowerBound() + cloud.upperBound());
    Scene only = world;
    only.automata = {cloud};
    double luminance[2] = {0.0, 0.0};
    bool seen = true;
    for (int side = 0; side < 2 && seen; ++side) {
      only.camera.position = glm::dvec3(glm::dvec2(middle), side == 0 ? 2.0 : middle.z + 2000.0);
      only.camera.orientation = {0.0, side == 0 ? 90.0 : -90.0, 0.0};
      only.camera.vfov_deg = 60.0;
      only.camera.width = only.camera.height = 128;
      const FloatImage image = renderer.renderFloat(only, file.render);
      const std::vector<CloudRegion> regions = cloudRegions(image, kMinCloudPixels);
      const int centre = 64 * 128 + 64;
      const auto hit = std::find_if(regions.begin(), regions.end(), [&](const CloudRegion& r) {
        return std::find(r.pixels.begin(), r.pixels.end(), centre) != r.pixels.end();
      });
      seen = hit != regions.end();
      if (seen) luminance[side] = bodyFigure(image, hit->pixels).luminance;
    }
    if (!seen) continue;
    ++clouds;
    under_sum += luminance[0];
    top_sum += luminance[1];
  }
  if (clouds == 0) return;
  std::printf(
      "automaton clouds (harbour, %d whole): luminance underside %.3f, sunlit top %.3f, "
      "ratio %.2f\n",
      clouds, under_sum / clouds, top_sum / clouds, under_sum / std::max(top_sum, 1e-9));
}

// The process's resident and peak resident memory, MiB (Linux /proc/self/status).
std::pair<double, double> residentMiB() {
  std::ifstream status("/proc/self/status");
  double rss = 0.0, peak = 0.0;
  for (std::string line; std::getline(status, line);) {
    if (line.rfind("VmRSS:", 0) == 0) rss = std::stod(line.substr(6)) / 1024.0;
    if (line.rfind("VmHWM:", 0) == 0) peak = std::stod(line.substr(6)) / 1024.0;
  }
  return {rss, peak};
}

// The ellipsoids a view of `scene` draws: its clouds' and its fields' heaps around the camera.
std::size_t drawnEllipsoids(const Scene& scene) {
  return ellipsoidCount(withFieldClouds(scene));
}

// Every genus at its typical altitude (weather.h), seen from the ground: the fraction of the
// sky dome covered for each cloud fraction asked.
void printHemisphereFigures(Renderer& renderer) {
  std::printf(
      "hemisphere fraction from the ground (cloud fraction asked -> fraction of the sky "
      "dome with coverage > 0.5)\n%-14s",
      "genus");
  const double asked[] = {0.1, 0.3, 0.5, 0.7, 0.9};
  for (double c : asked) std::printf(" %7.1f", c);
  std::printf("\n");
  for (int type = 1; type < kCloudTypeCount; ++type) {
    std::printf("%-14s", std::string(cloudTypeName(CloudType(type))).c_str());
    for (double c : asked) {
      Scene scene;
      const WeatherClouds add =
          weatherClouds(typicalWeatherLayer(CloudType(type), c), "weather/1", 7);
      scene.layers = add.layers;
      scene.fields = add.fields;
      std::printf(" %7.3f", hemisphereFraction(renderer, scene, RenderSettings{}));
      std::fflush(stdout);
    }
    std::printf("\n");
  }
}

struct GenusBenchOptions {
  std::string presets_dir = NEPHELE_SOURCE_DIR "/config/scenes";
  int repeats = 9;
  std::vector<std::string> sizes{"640x480", "1280x1024"}, names;
  std::string images;
  double coverage = -1.0;
  bool still_only = false;
  int shading_rate = 0;
  int refresh = 0;
  double speed = 250.0;
  bool hemisphere = false;
};

void addOptions(CLI::App& app, GenusBenchOptions& o) {
  app.add_option("--repeats", o.repeats, "Frames per still median and per flight")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--sizes", o.sizes, "Image sizes WxH")->delimiter(',');
  app.add_option("--dir", o.presets_dir, "Directory of scene files")->capture_default_str();
  app.add_option("--presets", o.names,
                 "Only these presets (default: genus_* and cloudscape; harbour adds the "
                 "automaton figures)")
      ->delimiter(',');
  app.add_option("--images", o.images,
                 "Also write the heap views the light figures are measured on to this directory");
  app.add_option("--coverage", o.coverage,
                 "Draw every [[weather]] layer of the presets at this cover, percent (issue 28's "
                 "30, 50, 70 and 100), instead of the preset's own")
      ->check(CLI::Range(0.0, 100.0));
  app.add_flag("--still", o.still_only,
               "Only the still frames and their budgets: no flights, look or body figures");
  app.add_option("--speed", o.speed,
                 "Flights: the camera's speed east, m/s (0: a still view streamed)")
      ->check(CLI::Range(0.0, 1000.0));
  app.add_option("--heap-refresh", o.refresh,
                 "Flights: walk one heap pixel in N anew a frame and reuse the last frame for "
                 "the rest (1, 4 or 16) instead of the preset's own");
  app.add_option("--heap-shading-rate", o.shading_rate,
                 "Draw the heaps of every preset at this shading rate (1, 2 or 4) instead of its "
                 "own");
  app.add_flag("--hemisphere", o.hemisphere,
               "Instead: the fraction of the sky dome covered, seen from the ground, for every "
               "genus at coverage 0.1 to 0.9");
}

// A preset as the options draw it (its cover, heap shading rate and refresh replaced when
// asked): 0, or the exit code with the error printed.
int loadGenusPreset(const std::filesystem::path& path, const GenusBenchOptions& o,
                    SceneFile& file) {
  if (o.coverage < 0.0) {
    if (!bench::loadPreset(path.string(), file)) return 1;
  } else {  // the preset's text with every `coverage = ...` line replaced
    std::ifstream in(path);
    std::string text, line;
    while (std::getline(in, line))
      text += (line.starts_with("coverage =") ? "coverage = " + std::to_string(o.coverage) : line) +
              "\n";
    if (const std::string e = parseSceneText(text, path.string(), file); !e.empty()) {
      std::fprintf(stderr, "%s\n", e.c_str());
      return 1;
    }
  }
  if (o.shading_rate > 0) {
    file.render.heap_shading_rate = o.shading_rate;
    if (const std::string e = validateRenderSettings(file.render); !e.empty()) {
      std::fprintf(stderr, "--heap-shading-rate: %s\n", e.c_str());
      return 2;
    }
  }
  if (o.refresh > 0) {
    file.render.heap_refresh = o.refresh;
    if (const std::string e = validateRenderSettings(file.render); !e.empty()) {
      std::fprintf(stderr, "--heap-refresh: %s\n", e.c_str());
      return 2;
    }
  }
  return 0;
}

// A still view's frame times: the floor, the clear sky, the frames that filled clipmaps, and
// the view itself (medians), with the still and clear frames' budgets.
struct StillFigures {
  double floor = 0.0, clear_ms = 0.0, still = 0.0;
  std::vector<double> fill;  // frames that filled clipmaps
  FrameTimes still_budget, clear_budget;
};

StillFigures measureStill(Renderer& renderer, const Scene& scene, const RenderSettings& render,
                          int repeats) {
  StillFigures s;
  const int width = scene.camera.width, height = scene.camera.height;
  s.floor = medianMilliseconds(repeats, [&] { renderer.renderFloor(width, height); });
  Scene clear = scene;
  clear.layers.clear(), clear.clouds.clear(), clear.fields.clear(), clear.automata.clear();
  s.clear_ms = medianMilliseconds(repeats, [&] { renderer.renderSrgb8(clear, render); });
  for (int frame = 0; frame < 100; ++frame) {
    const auto start = Clock::now();
    renderer.renderSrgb8(scene, render);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    if (renderer.lastFrameStats().layer_texels_baked == 0 && frame > 0) break;
    if (frame > 0) s.fill.push_back(ms);
  }
  s.still = medianMilliseconds(repeats, [&] { renderer.renderSrgb8(scene, render); });
  s.still_budget = renderer.lastFrameStats().times;
  renderer.renderSrgb8(clear, render);
  s.clear_budget = renderer.lastFrameStats().times;
  return s;
}

// A flight east from the still view: its frame times (the first `repeats`, then `repeats` warm
// ones after 60), its last frame against the exact one, and the first frame after a weather
// change.
struct FlightFigures {
  std::vector<double> ms, warm;
  double strip_texels = 0.0;  // clipmap texels evaluated per warm frame
  FrameTimes budget;
  std::string stats;
  FloatImage reused, exact;
  double change_ms = 0.0;
};

FlightFigures measureFlight(const Renderer& base, const Scene& scene, const RenderSettings& render,
                            int repeats, double speed) {
  FlightFigures f;
  // The flight's renderer has drawn the still view once, as a running daemon has drawn
  // frames before: its programs are compiled and its textures baked (one-off costs of
  // hundreds of milliseconds), while the heaps along the flight are new to it.
  const std::unique_ptr<Renderer> fresh = base.another();
  Renderer& flyer = *fresh;
  flyer.renderSrgb8(scene, render);
  // A flight is a continuous view, as a daemon's subscription is (heap_refresh).
  flyer.setContinuousView("flight");
  Scene moving = scene;
  // Frame k of the flight: east at `speed` at 30 Hz, from 50 km east of the still view,
  // where the heaps are new to the renderer; a still view streamed (speed 0) is the
  // still view itself.
  const double start_x = speed > 0.0 ? 50000.0 : 0.0;
  auto flyTo = [&](int frame) {
    moving.camera.position.x = scene.camera.position.x + speed / 30.0 * frame + start_x;
  };
  for (int frame = 0; frame < repeats; ++frame) {
    flyTo(frame);
    const auto start = Clock::now();
    flyer.renderSrgb8(moving, render);
    f.ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
  }
  for (int frame = repeats; frame < 60 + repeats; ++frame) {
    flyTo(frame);
    const auto start = Clock::now();
    flyer.renderSrgb8(moving, render);
    if (frame < 60) continue;
    f.warm.push_back(std::chrono::duration<double, std::milli>(Clock::now() - start).count());
    f.strip_texels += flyer.lastFrameStats().layer_texels_baked / double(repeats);
  }
  f.budget = flyer.lastFrameStats().times;
  f.stats = flyer.lastFrameStats().line();
  // The next frame of the flight against the exact frame of its pose.
  flyTo(60 + repeats);
  f.reused = flyer.renderFloat(moving, render);
  flyer.setContinuousView("");
  f.exact = flyer.renderFloat(moving, render);
  // The first frame after a weather change, as a subscription draws it: the world's
  // edit makes a new continuous view, whose first frame is exact, with the heaps of the
  // new cover generated. The cover is 5 points more (less above 90 %).
  Scene changed = moving;
  for (CloudField& field : changed.fields)
    field.coverage = field.coverage > 0.9 ? field.coverage - 0.05 : field.coverage + 0.05;
  flyer.setContinuousView("flight after the change");
  const auto change_start = Clock::now();
  flyer.renderSrgb8(changed, render);
  f.change_ms = std::chrono::duration<double, std::milli>(Clock::now() - change_start).count();
  flyer.setContinuousView("");
  return f;
}

// One view's row of the table and its budget lines, flight figures included unless --still.
void benchView(const Renderer& base, const std::filesystem::path& path, const SceneFile& file,
               const View& view, const Scene& scene, const std::string& size,
               const GenusBenchOptions& o) {
  // A fresh renderer per case: heap tiles and bakes left by the previous case would
  // make the first frames of this one look cheaper than a new view's are.
  const std::unique_ptr<Renderer> fresh = base.another();
  Renderer& renderer = *fresh;
  StillFigures s = measureStill(renderer, scene, file.render, o.repeats);
  auto printBudgets = [&] {
    std::printf("  budget, still: %s\n  budget, clear: %s\n",
                bench::frameBudgetLine(s.still_budget).c_str(),
                bench::frameBudgetLine(s.clear_budget).c_str());
  };
  if (o.still_only) {
    std::printf("%-22s %-7s %-10s %8.2f %8.2f %9.2f %7.1f %7.1f\n", path.stem().c_str(), view.name,
                size.c_str(), s.floor, s.clear_ms, s.still, s.still / s.floor,
                s.still / s.clear_ms);
    printBudgets();
    std::fflush(stdout);
    return;
  }
  FlightFigures f = measureFlight(base, scene, file.render, o.repeats, o.speed);
  const ImageError reuse_error = compareImages(f.reused, f.exact);
  if (!o.images.empty()) {  // the flight's last frame and the exact one, to look at
    std::filesystem::create_directories(o.images);
    const std::string stem = o.images + "/" + path.stem().string() + "_" + view.name + "_";
    for (const auto& [what, image] : {std::pair{"flight", &f.reused}, {"exact", &f.exact}})
      if (const std::string error = writeImageFile(stem + what + ".png", *image); !error.empty())
        std::fprintf(stderr, "%s\n", error.c_str());
  }
  const double clear_ms = s.clear_ms;
  const double slowest = *std::max_element(f.ms.begin(), f.ms.end());
  const double warm_slowest = *std::max_element(f.warm.begin(), f.warm.end());
  std::sort(f.ms.begin(), f.ms.end());
  std::sort(f.warm.begin(), f.warm.end());
  const double flying = f.ms[f.ms.size() / 2], warm_flying = f.warm[f.warm.size() / 2];
  std::printf(
      "%-22s %-7s %-10s %8.2f %8.2f %9.2f %7.1f %7.1f %10.2f %7.1f %10.2f %7.1f %10.2f "
      "%7.1f %10.2f %7.1f %10zu\n",
      path.stem().c_str(), view.name, size.c_str(), s.floor, clear_ms, s.still, s.still / s.floor,
      s.still / clear_ms, flying, flying / clear_ms, slowest, slowest / clear_ms, warm_flying,
      warm_flying / clear_ms, warm_slowest, warm_slowest / clear_ms, drawnEllipsoids(scene));
  printBudgets();
  std::printf(
      "  budget, warm flight: %s\n"
      "  flight at heap_refresh %d: last frame against the exact one %.1f dB, largest "
      "difference %.3f\n"
      "  first frame after a weather change (%s): %.2f ms, %.1f x clear\n"
      "  %s\n",
      bench::frameBudgetLine(f.budget).c_str(), file.render.heap_refresh, reuse_error.psnr_db,
      reuse_error.max_abs,
      scene.fields.empty() ? "no field: the same sky" : "every field's cover 5 points on",
      f.change_ms, f.change_ms / clear_ms, f.stats.c_str());
  if (!s.fill.empty()) {
    std::sort(s.fill.begin(), s.fill.end());
    std::printf(
        "  clipmaps filled over %zu frames after the first, median %.2f ms (%.1f x clear); "
        "warm flight: %.0f texels a frame\n",
        s.fill.size(), s.fill[s.fill.size() / 2], s.fill[s.fill.size() / 2] / clear_ms,
        f.strip_texels);
  }
  std::fflush(stdout);
}

// One preset: every view at every size, then (unless --still) its look, light, cumulonimbus,
// rain and shadow figures. 0, or the exit code.
int benchPreset(const Renderer& base, const std::filesystem::path& path,
                const GenusBenchOptions& o) {
  SceneFile file;
  if (const int code = loadGenusPreset(path, o, file); code != 0) return code;
  for (const std::string& size : o.sizes) {
    Camera sized;
    if (!bench::parseSize(size, sized)) return 2;
    // The world at the preset's time: automaton clouds are grown by the World.
    const Scene at_time = World(file.scene, file.dynamics).scene();
    for (const View& view : viewsOf(file)) {
      Scene scene = at_time;
      scene.camera = view.camera;
      scene.camera.width = sized.width, scene.camera.height = sized.height;
      benchView(base, path, file, view, scene, size, o);
    }
    const auto [rss, peak] = residentMiB();
    std::printf(
        "  memory after %s at %s: resident %.0f MiB, peak %.0f MiB (the process, GL "
        "included)\n",
        path.stem().c_str(), size.c_str(), rss, peak);
  }
  if (o.still_only) return 0;
  const std::unique_ptr<Renderer> fresh = base.another();
  Renderer& renderer = *fresh;
  printBodyFigures(renderer, file);
  printLightFigures(renderer, file, path.stem().string(), o.images);
  printCumulonimbusFigures(renderer, file, path.stem().string(), o.images);
  if (path.stem() == "genus_cumulonimbus") printRainFigures(renderer, file);
  printShadowFigures(base, file, path.stem().string(), o.repeats, o.images);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("Nephele genus benchmark: frame times of the genus presets in floor multiples");
  GenusBenchOptions o;
  addOptions(app, o);
  CLI11_PARSE(app, argc, argv);

  std::vector<std::filesystem::path> files;
  for (const auto& path : bench::presetFiles(o.presets_dir)) {
    const std::string stem = path.stem().string();
    const bool wanted = o.names.empty()
                            ? stem.starts_with("genus_") || stem == "cloudscape"
                            : std::find(o.names.begin(), o.names.end(), stem) != o.names.end();
    if (wanted) files.push_back(path);
  }
  // Every case draws on a renderer of its own, made from this one (Renderer::another);
  // the hemisphere and automaton figures, drawn alone, on this one.
  const std::unique_ptr<Renderer> gl = bench::openRenderer();
  if (!gl) return 1;
  if (o.hemisphere) {
    printHemisphereFigures(*gl);
    return 0;
  }
  const RendererPlatform platform = gl->platform();
  std::printf("GL: %s, %s; render + readback into an 8-bit target\n", platform.backend.c_str(),
              platform.device.c_str());
  std::printf(
      "still and flying are also given as multiples of the clear frame: the same view "
      "with no cloud, timed in the same run\n");
  std::printf("%-22s %-7s %-10s %8s %8s %9s %7s %7s %10s %7s %10s %7s %10s %7s %10s %7s %10s\n",
              "preset", "view", "size", "floor ms", "clear ms", "still ms", "xfloor", "xclear",
              "flying ms", "xclear", "slowest ms", "xclear", "warm ms", "xclear", "slowest ms",
              "xclear", "ellipsoids");
  for (const auto& path : files)
    if (const int code = benchPreset(*gl, path, o); code != 0) return code;
  if (!o.still_only &&
      (o.names.empty() || std::find(o.names.begin(), o.names.end(), "harbour") != o.names.end())) {
    printAutomatonFigures(*gl);
  }
  return 0;
}
