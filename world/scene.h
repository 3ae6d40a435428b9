#pragma once
// A scene: everything one rendered image depends on.
#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "world/automaton/automaton_cloud.h"
#include "world/camera.h"
#include "world/formations/cloud_field.h"
#include "world/formations/ellipsoid_cloud.h"
#include "world/formations/region.h"
#include "world/geodesy.h"
#include "world/sea.h"
#include "world/shading.h"
#include "world/sky.h"
#include "world/target.h"
#include "world/textures/layer_texture.h"

namespace nephele {

// A textured sky plane Z = altitude (MODEL.md section 5), seen from below or above.
struct CloudLayer {
  std::string name;
  double altitude_m = 3000.0;
  glm::dvec3 colour{1.0, 1.0, 1.0};  // linear RGB
  double threshold = 0.3;            // T1
  double transition = 0.3;           // D, >= 0
  ShadingParams shading;
  LayerTextureSpec texture;
  Region region;  // where the layer lies (MODEL.md section 11); it drifts with the texture
  // A far deck standing for heaps (withFieldClouds) is absent within this horizontal distance
  // of the camera, where the heaps themselves are drawn, and fades in over the next band.
  double hole_radius_m = 0.0, hole_band_m = 0.0;
  FarCover far;  // a far deck's cover against view elevation (region.h)
  // The base plane of a stratiform weather layer carries its slab (MODEL.md section 5): up to
  // top_m, thinning over band_m beyond it, visibility_m inside; none while visibility_m is 0.
  struct InLayer {
    double top_m = 0.0, band_m = 0.0, visibility_m = 0.0;
    bool operator==(const InLayer&) const = default;
  } in_layer;
};

// The layer's weight at world point `xy` at time t seen from `eye` (MODEL.md section 11): its
// region's, which moves with the layer's drift (unwrapped: the texture's own offset may be
// reduced modulo its period), times its hole's.
inline double layerRegionWeight(const CloudLayer& layer, glm::dvec2 xy, double time_s,
                                glm::dvec2 eye) {
  double w = 1.0;
  if (!layer.region.everywhere()) {
    const LayerTextureSpec& t = layer.texture;
    w = regionWeight(layer.region, xy - t.drift_offset_m - t.drift_velocity * time_s);
  }
  if (layer.hole_radius_m > 0.0)
    w *= bandRamp(glm::length(xy - eye) - layer.hole_radius_m, layer.hole_band_m);
  return w;
}
// The layer's T1 at world point xy seen along `view` from `eye` at time t: a far deck's cover
// for the view's elevation, raised by its region's weight there (MODEL.md section 11).
inline double layerThreshold(const CloudLayer& layer, glm::dvec2 xy, glm::dvec3 view, double time_s,
                             glm::dvec2 eye) {
  const double base = layer.far.side_ratio > 0.0 ? farThreshold(layer.far, view) : layer.threshold;
  return regionThreshold(base, layerRegionWeight(layer, xy, time_s, eye));
}
inline bool layerHasRegion(const CloudLayer& layer) {
  return !layer.region.everywhere() || layer.hole_radius_m > 0.0 || layer.far.side_ratio > 0.0;
}

// Which weather layer: its number (a host's 1 to 3, a scene file's [[weather]] tables in
// order) and, for a CIGI region's own layers, the region.
struct WeatherKey {
  int layer = 1;
  std::optional<std::uint16_t> region;
  auto operator<=>(const WeatherKey&) const = default;
};

struct Scene {
  std::uint64_t seed = 1;
  double time_s = 0.0;
  Camera camera;
  Sun sun;
  Sky sky;
  std::optional<Fog> fog;
  std::optional<Haze> haze;
  std::vector<CloudLayer> layers;
  std::vector<EllipsoidCloud> clouds;
  // Fields of heaps that exist everywhere; a render sees the heaps around its camera
  // (withFieldClouds).
  std::vector<CloudField> fields;
  std::vector<Target> targets;
  // Automaton clouds as the World hands them to a render (scene files alone hold none).
  std::vector<AutomatonCloudView> automata;
  // The weather layers as set (set_weather, Modbus, CIGI, [[weather]]), held here alone: their
  // clouds are the layers and fields named under weatherPrefix(key) (world.h placeWeather).
  std::map<WeatherKey, WeatherLayer> weather;
  // The rain shafts under its fields' heaps near the camera (MODEL.md section 17), drawn out of
  // the fields with their heaps (withFieldClouds); a scene with fields has none yet.
  std::vector<RainShaft> rain_shafts;
  // The sea in place of the ground (MODEL.md section 18); none: the ground plane.
  std::optional<Sea> sea;
  // Where the database lies on the Earth; none: a flat world placed nowhere (scene files, a
  // socket host). And where the database's origin lies in the frame the world's procedural
  // content was laid out in: the sum of its re-centrings' shifts (MODEL.md section 13), where
  // weather and a sea set later are laid out too, so that they land where they would have.
  std::optional<Site> site;
  glm::dvec2 content_origin{0.0};
};

// `scene` with `clouds` in place of its own: everything else copied, its clouds' lobes not
// (a world's millions of lobes, where a caller keeps a few; withinEllipsoidBudget).
inline Scene withClouds(const Scene& scene, std::vector<EllipsoidCloud> clouds) {
  // Every member by name: this stops compiling when Scene gains one, which belongs here too.
  const auto& [seed, time_s, camera, sun, sky, fog, haze, layers, own_clouds, fields, targets,
               automata, weather, rain_shafts, sea, site, content_origin] = scene;
  static_cast<void>(own_clouds);
  return Scene{
      seed,   time_s,  camera,   sun,     sky,         fog, haze, layers,        std::move(clouds),
      fields, targets, automata, weather, rain_shafts, sea, site, content_origin};
}

// Ellipsoids the scene's clouds hold (its fields' heaps are made per view and not counted).
inline std::size_t ellipsoidCount(const Scene& scene) {
  std::size_t n = 0;
  for (const EllipsoidCloud& cloud : scene.clouds) n += cloud.ellipsoids.size();
  return n;
}

// The medium of the stratiform layer the camera is in, or in the transition band of (MODEL.md
// section 5, "the in-layer veil"): the layer's slab, its in-layer visibility divided by the
// cover of its base plane over the eye and by the slab's density at the eye's height, in the
// colour the layer's texture and sun give it there; none elsewhere (where layers overlap, the
// densest).
std::optional<Fog> inLayerVeil(const Scene& scene);
// Whether the camera is in a layer's slab or band (where inLayerVeil may give a veil).
bool eyeInLayer(const Scene& scene);

// The media in the air between the eye and a surface (MODEL.md sections 5 and 17), a bit each:
// a GL pass compiles only those its scene holds (renderer/gl/sky_shaders.h, airDefines).
enum AirMedium : unsigned {
  kAirFog = 1,
  kAirVeil = 2,  // the in-layer veil (inLayerVeil)
  kAirHaze = 4,
  kAirSlabs = 8,    // precipitation slabs under stratiform layers
  kAirShafts = 16,  // rain shafts under heaps
};
inline constexpr unsigned kEveryAirMedium = kAirFog | kAirVeil | kAirHaze | kAirSlabs | kAirShafts;
inline unsigned airMedia(const Scene& scene) {
  return (scene.fog ? kAirFog : 0u) | (eyeInLayer(scene) ? kAirVeil : 0u) |
         (scene.haze ? kAirHaze : 0u) | (hasPrecipitationSlabs(scene) ? kAirSlabs : 0u) |
         (hasPrecipitationShafts(scene) ? kAirShafts : 0u);
}
// Whether anything lies in the air between the eye and a surface.
inline bool sceneHasAir(const Scene& scene) {
  return airMedia(scene) != 0;
}

// What a scene's fields make for its camera (MODEL.md sections 10, 11 and 17): their heaps within
// heapRange(drawing.range_m) of it, where the view reaches beyond that a far deck standing for
// the rest, and the rain shafts in view (rainShaftsInView).
struct FieldContent {
  std::vector<EllipsoidCloud> heaps;
  std::vector<CloudLayer> far_decks;
  std::vector<RainShaft> rain_shafts;
};
FieldContent fieldContent(const Scene& scene, const HeapDrawing& drawing = {});
// `scene` with its fields' content in their place: the heaps after its clouds, the far decks
// after its layers (renderer/frame_plan.h borrows the scene instead of copying it).
Scene withFieldClouds(const Scene& scene, const HeapDrawing& drawing = {});

// A frame's work budget (issue 31; MODEL.md section 15), in two parts, both counted in
// geometry, never in time, so that equal frames stay equal (0 turns a part off):
// - `budget`: at most this many ellipsoids;
// - `overdraw`: their footprints (each one's projected bounding square, clipped to the view;
//   the whole view for one that reaches the eye) cover at most this many views, the cost of the
//   per-pixel pass, which tests every ellipsoid listed over a pixel.
// Ellipsoids are taken in order of projected size (largest radius over distance along the
// view; ties by cloud and lobe order; behind the camera, none) while both hold, the rest
// dropped, and the clouds thinned share one texture seed. Nothing when the scene is within both.
std::optional<Scene> withinEllipsoidBudget(const Scene& scene, double budget,
                                           double overdraw = 0.0);
// The same for a list of clouds seen by `camera`: the clouds the budget leaves (copies, in the
// list's order, empty ones dropped), or nothing when the list is within it.
std::optional<std::vector<EllipsoidCloud>> cloudsWithinBudget(
    std::span<const EllipsoidCloud* const> clouds, const Camera& camera, double budget,
    double overdraw = 0.0);
// The footprint of `e` in views of `camera` (the projected bounding square of its largest
// radius, clipped to the view; 1 when it reaches the eye's plane; 0 behind or outside).
double ellipsoidFootprint(const Ellipsoid& e, const Camera& camera, const ViewBasis& basis);

}  // namespace nephele
