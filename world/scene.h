#pragma once
// A scene: everything one rendered image depends on.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "world/automaton/automaton_cloud.h"
#include "world/formations/cloud_field.h"
#include "world/formations/ellipsoid_cloud.h"
#include "world/formations/region.h"
#include "world/frames.h"
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
};

// The layer's region weight at world point `xy` at time t: the region moves with the layer's
// drift, unwrapped (the texture's own offset may be reduced modulo its period).
inline double layerRegionWeight(const CloudLayer& layer, glm::dvec2 xy, double time_s) {
  if (layer.region.everywhere()) return 1.0;
  const LayerTextureSpec& t = layer.texture;
  return regionWeight(layer.region, xy - t.drift_offset_m - t.drift_velocity * time_s);
}

struct Scene {
  std::uint64_t seed = 1;
  double time_s = 0.0;
  Camera camera;
  Sun sun;
  Sky sky;
  std::optional<Fog> fog;
  std::vector<CloudLayer> layers;
  std::vector<EllipsoidCloud> clouds;
  // Fields of heaps that exist everywhere; a render sees the heaps around its camera
  // (withFieldClouds).
  std::vector<CloudField> fields;
  std::vector<Target> targets;
  // Automaton clouds as the World hands them to a render (scene files alone hold none).
  std::vector<AutomatonCloudView> automata;
};

// `scene` with its fields' heaps around its camera added to its clouds (MODEL.md section 10);
// what every renderer draws.
Scene withFieldClouds(const Scene& scene);

}  // namespace nephele
