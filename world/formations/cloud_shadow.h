#pragma once
// Cloud shadows (MODEL.md section 16): the share of the sunlight that reaches a point through
// the heaps' lobes on its ray to the sun, each lobe taken at its mean opacity for the limb value
// the ray has through it and at the optical depth of its chord (CloudShadows), and through the
// sky planes above it (PlaneShadows). On the ground the reference evaluates it per sample, the
// GL in a map along the sun built once per sun and world change (renderer/gl/shadow_map.h); on
// lobes and targets the reference per sample, the GL once per lobe and target (SceneSunlight).
#include <array>
#include <limits>
#include <vector>

#include <glm/glm.hpp>

#include "world/formations/cloud_field.h"
#include "world/formations/ellipsoid_cloud.h"
#include "world/formations/heap_light.h"
#include "world/formulas/shadow.h"
#include "world/textures/layer_texture.h"

namespace nephele {

struct CloudLayer;
struct Scene;

// The mean opacity C(g) of a cloud's surface over its texture's values, at limb values
// g = i / (kShadowTableSize - 1): a table read linearly in g.
inline constexpr int kShadowTableSize = 33;
using ShadowTable = std::array<float, kShadowTableSize>;

// C(g) = mean over the texture's values It of 1 - TR(It, T1, T2, g, D) (Gardner eq. 11), the
// values taken at kShadowTextureSamples points spread over one period of the cloud's solid
// texture (the same points for every cloud). Cached by texture and thresholds.
inline constexpr int kShadowTextureSamples = 512;
ShadowTable meanOpacityTable(const EllipsoidCloud& cloud);
// The table read linearly at g in [0, 1].
double meanOpacity(const ShadowTable& table, double g);

// The ground's brightness relative to the unshadowed ground for a share of the sunlight, and
// the share a point in full shadow keeps (MODEL.md section 16): world/formulas/shadow.h.
using formulas::groundLight;
using formulas::kGroundSkyShare;

// Below this elevation of the sun no cloud casts a shadow: the ground is lit by the sky alone,
// and a shadow would reach 60 times a cloud's height.
inline constexpr double kMinShadowElevationDeg = 1.0;

// Sky planes cast shadows too (MODEL.md section 16, "sky planes"): a point below a plane keeps
// the plane's translucence where the sun's ray through the point crosses it. The planes that
// cast, the kMaxCastingPlanes lowest of the scene's layers but far decks while the sun is up:
// indices into scene.layers, lowest first. A far deck stands for heaps, whose shadows are the
// shadow map's within its range (CloudShadows); as a plane, its opaque cover cast shadows darker
// than the heaps' beyond it.
inline constexpr int kMaxCastingPlanes = 8;
std::vector<std::size_t> castingPlanes(const Scene& scene);
// Where the line through p along a direction crosses the plane Z = altitude
// (world/formulas/shadow.h).
using formulas::planeCrossing;

// How far from the camera's ground point shadows are drawn: 24 km, doubled until it is at
// least 4 times the camera's height (a high camera sees the ground farther out), at most 64
// times. The GL's map is a square of twice this side (ShadowMap).
double shadowRange(double camera_z);

// One lobe that casts a shadow.
struct ShadowCaster {
  glm::dvec3 centre{0.0};
  glm::dmat3 to_unit{1.0};  // world offsets from the centre into the unit sphere (W)
  double reach = 0.0;       // its largest semi-axis
  double extinction = 0.0;  // the cloud's light_extinction, per metre
  int table = 0;            // its cloud's mean-opacity table
};

// The share of the sunlight a caster lets through along p + s to_sun, s > 0 (to_sun unit,
// rising): 1 - C(g) (1 - T(sigma l)), g = 1 - |o_perp|^2 the ray's limb value through the
// lobe (its unit-sphere distance from the centre, as the limb function of an eye at infinity),
// l the chord's length beyond p and T the two-stream transmittance. 1 where the ray misses.
double casterSunlight(const ShadowCaster& caster, const ShadowTable& table, glm::dvec3 p,
                      glm::dvec3 to_sun);

// Every lobe of a scene that may shadow the ground it shows: the lobes of its clouds with a
// light_extinction above 0 (heap light, MODEL.md section 14) and the heaps of its fields within
// heap range of the camera, in view or not, but no farther than the shadows they can cast
// within shadowRange (a heap at height h shadows h / tan(elevation) downsun of itself), drawn
// coarse (a shadow has no use for the detail lobes). None while the sun is below
// kMinShadowElevationDeg.
class CloudShadows {
 public:
  CloudShadows() = default;  // none
  // `lookups`: sunlight() will be asked (the reference), which needs a grid over the casters.
  CloudShadows(const Scene& scene, const HeapDrawing& heaps, bool lookups);

  bool empty() const { return casters_.empty(); }
  const std::vector<ShadowCaster>& casters() const { return casters_; }
  const std::vector<ShadowTable>& tables() const { return tables_; }
  glm::dvec3 toSun() const { return to_sun_; }
  // The ground rectangle outside which no caster shadows: [lo, hi] in world X, Y.
  glm::dvec2 lo() const { return lo_; }
  glm::dvec2 hi() const { return hi_; }
  // The lowest point of any caster: a sky plane at or below it has every caster above it, so the
  // sunlight its points receive is the ground's where the sun's ray through them lands
  // (MODEL.md section 16, "planes under heaps").
  double floor() const { return floor_; }
  // Where caster i's shadow can fall on the ground Z = 0: its bounding sphere projected
  // along the sun, as a square.
  void footprint(const ShadowCaster& caster, glm::dvec2& lo, glm::dvec2& hi) const;

  // The share of the sunlight reaching ground point (x, y, 0): the product of casterSunlight
  // over every caster. Only when made with `lookups`.
  double sunlight(glm::dvec2 ground) const { return sunlightAt({ground, 0.0}); }
  // The same at any point p, from the casters on p's ray to the sun above it: those along the
  // sun's line through p (the grid cell where it lands on the ground), each counted for its
  // chord beyond p. `own`, if given, is the envelope of the heap p lies on: casters whose
  // centre lies inside it are its own lobes, which light it through heapLightAt, and are left
  // out (MODEL.md section 16, "heaps under clouds").
  double sunlightAt(glm::dvec3 p, const HeapEnvelope* own = nullptr) const;

 private:
  glm::dvec3 to_sun_{0.0, 0.0, 1.0};
  std::vector<ShadowCaster> casters_;
  std::vector<ShadowTable> tables_;
  glm::dvec2 lo_{0.0}, hi_{0.0};
  double floor_ = std::numeric_limits<double>::infinity();
  // A grid over [lo, hi] listing the casters whose footprint meets each cell: cell k's are
  // listed_[first_[k]] to listed_[first_[k + 1]] (one array, filled in two passes).
  double cell_ = 1.0;
  glm::ivec2 cells_{0};
  std::vector<int> first_, listed_;
  // The cells caster i's footprint meets, [c0, c1].
  void footprintCells(const ShadowCaster& caster, glm::ivec2& c0, glm::ivec2& c1) const;
};

// The sky planes' shadows (MODEL.md section 16, "sky planes"): the casting planes
// (castingPlanes) with their textures, for the share of the sunlight they let through to any
// point below them.
class PlaneShadows {
 public:
  PlaneShadows() = default;  // none
  explicit PlaneShadows(const Scene& scene);

  bool empty() const { return planes_.empty(); }
  // The product over the casting planes above p (altitude above p.z, so that a plane never
  // shadows itself, and above `top`) of the plane's translucence where the sun's ray through p
  // crosses it, its threshold taken with the sun's direction as the view's.
  double sunlight(glm::dvec3 p, double top = -std::numeric_limits<double>::infinity()) const;

 private:
  struct Plane {
    const CloudLayer* layer;
    LayerTexture texture;
  };
  std::vector<Plane> planes_;
  glm::dvec3 to_sun_{0.0, 0.0, 1.0};
  double time_s_ = 0.0;
  glm::dvec2 eye_{0.0};
};

// The sunlight reaching a point of the scene through the clouds above it (MODEL.md section 16):
// the planes' share times the heaps' (either may be missing). The scene the planes were made
// from must outlive it.
struct SceneSunlight {
  const PlaneShadows* planes = nullptr;
  const CloudShadows* heaps = nullptr;
  bool empty() const { return (!planes || planes->empty()) && (!heaps || heaps->empty()); }
  // At point p of anything but a lobe: the ground, a plane, a target.
  double at(glm::dvec3 p) const { return at(p, nullptr, p.z); }
  // At point p of a lobe, whose heap's envelope is `own` and whose highest point is `top`: a
  // plane it reaches through does not shadow it.
  double at(glm::dvec3 p, const HeapEnvelope* own, double top) const {
    return (planes ? planes->sunlight(p, top) : 1.0) * (heaps ? heaps->sunlightAt(p, own) : 1.0);
  }
};

}  // namespace nephele
