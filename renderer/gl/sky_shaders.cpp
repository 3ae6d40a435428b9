#include "renderer/gl/sky_shaders.h"

#include "renderer/gl/shaders/formulas_glsl.h"
#include "renderer/gl/shaders/sky_glsl.h"
#include "renderer/gl/view_uniforms.h"
#include "world/formations/cloud_shadow.h"
#include "world/precipitation.h"
#include "world/textures/gardner_texture.h"

namespace nephele {
namespace {

// View (camera-relative: the shader knows only the camera's altitude), output, the air (fog and
// haze). The air is unlit and applied to each surface by its camera distance, which is exact
// under "over".
using glsl::sky::kCommon;  // shaders/sky/common.glsl

using glsl::sky::kClipmapBake;    // shaders/sky/clipmap_bake.glsl: the bake pass's main()
using glsl::sky::kLayers;         // shaders/sky/layers.glsl: the textured layers, in slots
using glsl::sky::kPolygonVertex;  // shaders/polygon.vert: a whole vertex stage

// The expression for slot `slot`'s texture value at `hit`.
std::string slotValue(int slot, LayerKind kind, const std::string& hit) {
  const std::string i = std::to_string(slot);
  switch (kind) {
    case LayerKind::kBakedGardner:
      return "bakedValue(u_table" + i + ", " + i + ", " + hit + ")";
    case LayerKind::kTable:
      return "tableValue(u_table" + i + ", " + i + ", " + hit + ")";
    case LayerKind::kProceduralGardner:
      return "proceduralValue(" + i + ", " + hit + ")";
    case LayerKind::kClipmapGardner:
      return "clipmapValue(u_table" + i + ", " + i + ", " + hit + ")";
  }
  return "0.0";
}

// A casting slot's share of the sunlight at a point below it: its translucence (Gardner eq. 9)
// where the sun's ray through the point crosses its plane (MODEL.md section 16, "sky planes").
// Its threshold takes the sun's direction as the view's, for a far deck's cover. The term
// filter reads the texture over the receiving pixel's footprint or, where wider, the shadow's
// penumbra: the sun's disc, 0.0093 radians across, seen over the distance to the plane.
std::string casterFunction(int caster, int slot, LayerKind kind) {
  const std::string c = std::to_string(caster), i = std::to_string(slot);
  return "float casterSunlight" + c + "(LayerHit hit, float height) {\n" +
         "  float rise = u_height[" + i + "] - height;\n" + "  if (!(rise > 0.0)) return 1.0;\n" +
         "  hit.p = planeCrossing(vec3(hit.p, height), u_height[" + i + "], u_to_sun);\n" +
         "  float t1 = layerThreshold(" + i + ", u_to_sun, hit.p);\n" +
         "  if (t1 >= 1.0) return 1.0;\n" + "  float penumbra = 0.0093 * rise / u_to_sun.z;\n" +
         "  if (length(hit.dpdx) < penumbra) hit.dpdx = vec2(penumbra, 0.0);\n" +
         "  if (length(hit.dpdy) < penumbra) hit.dpdy = vec2(0.0, penumbra);\n" +
         "  return translucence(" + slotValue(slot, kind, "hit") + " - t1, u_transition[" + i +
         "]);\n}\n";
}

// The function of the sunlight the `n` highest casters of `total` let through (skySlots).
std::string planesSunlightName(int n, int total) {
  return "planesSunlight" + std::to_string(n) + "of" + std::to_string(total);
}

// Its value at `hit` on the plane at `height`; 1 with no caster.
std::string planesSunlight(int n, int total, const std::string& hit, const std::string& height) {
  return n == 0 ? std::string("1.0")
                : planesSunlightName(n, total) + "(" + hit + ", " + height + ")";
}

std::string slotStatement(int slot, LayerKind kind, int shaded_by, int casters) {
  const std::string i = std::to_string(slot);
  const std::string value = slotValue(slot, kind, "hit");
  // Behind a surface that is opaque to within 1/1024 nothing more is evaluated (what the
  // layers there could add is below half an 8-bit step): a full deck costs its nearest plane.
  // Nor is the texture where the threshold is 1 or more, since T <= 1 (MODEL.md section 2)
  // leaves the layer clear there: a far deck's hole around the camera, where the heaps stand,
  // costs its threshold only.
  return "    if (transmittance > kClear) { LayerHit hit = hitLayer(" + i +
         ", r); float t1 = inFront(hit.distance) ? layerThreshold(" + i +
         ", r, hit.p) : 1.0; if (t1 < 1.0) composite(" + i + ", r, hit, t1, " + value + ", " +
         planesSunlight(shaded_by, casters, "hit", "u_height[" + i + "]") +
         ", colour, transmittance); }\n";
}

// kCommon after the constants it takes from C++ and the formulas it shares with the CPU
// reference (world/formulas/).
std::string commonSource() {
  return "const int kPrecipitationSlabs = " + std::to_string(kPrecipitationSlabs) +
         ";\nconst int kRainShafts = " + std::to_string(kMaxRainShafts) + ";\n" + formulaSource() +
         kCommon;
}

}  // namespace

std::string SkyPassLayout::key() const {
  std::string k = background ? "bg/" : "--/";
  for (LayerKind kind : above) k += char('a' + int(kind));
  k += '/';
  for (LayerKind kind : below) k += char('a' + int(kind));
  k += '/';
  k += char('0' + int(term_filter));
  k += char('a' + int(air));
  k += specular ? 's' : '-';
  k += targets ? 't' : '-';
  k += regions ? 'r' : '-';
  k += shadows ? 'h' : '-';
  k += sea ? 'w' : '-';
  k += ground ? 'g' : '-';
  k += '/';
  for (LayerKind kind : casters) k += char('a' + int(kind));
  k += '/';
  for (int n : shaded_by) k += char('0' + n);
  return k;
}

std::string airDefines(unsigned media) {
  if (media == 0) return "";
  std::string s = "#define AIR\n";
  if (media & kAirFog) s += "#define AIR_FOG\n";
  if (media & kAirVeil) s += "#define AIR_VEIL\n";
  if (media & kAirHaze) s += "#define AIR_HAZE\n";
  if (media & kAirSlabs) s += "#define AIR_SLABS\n";
  if (media & kAirShafts) s += "#define AIR_SHAFTS\n";
  return s;
}

std::string formulaSource() {
  using namespace glsl::formulas;
  return std::string(kPrelude) + kTable + kAir + kShading + kSea + kEllipsoid + kHeap + kFarDeck +
         kRegion + kTexture + kShadow + kVolume;
}

std::string viewShaderSource() {
  return commonSource();
}

std::string clipmapBakeSource() {
  std::string s = "#version 450 core\n#define PROCEDURAL\n";
  s += "const int kComponents = " + std::to_string(GardnerTextureParams::kComponents) + ";\n";
  s += "const int kSlots = 1;\n";
  s += commonSource();
  s += kLayers;
  // Slot 0's phases are taken at the corner of the ring's window (lattice index `first` in
  // absolute terms); the fragment at storage texel s holds the window's texel (s - first) mod N.
  s += kClipmapBake;
  return s;
}

std::string polygonVertexSource() {
  return kPolygonVertex;
}

namespace {

// The pass's defines and constants: what the layout draws, and its slots.
std::string skyDefines(const SkyPassLayout& layout) {
  std::string s = "#version 450 core\n";
  s += airDefines(layout.air);
  if (layout.background) s += "#define BACKGROUND\n";
  if (layout.specular) s += "#define SPECULAR\n";
  if (layout.targets) s += "#define TARGETS\n";
  if (layout.regions) s += "#define REGIONS\n";
  if (layout.shadows) s += "#define SHADOWS\n";
  if (!layout.casters.empty()) s += "#define PLANE_SHADOWS\n";
  if (layout.sea)
    s += "#define SEA\nconst int kSeaWaves = " + std::to_string(kMaxSeaWaves) +
         ";\nconst float kWaveModulation = " + std::to_string(kWaveModulation) + ";\n";
  if (layout.term_filter == TermFilter::kCut) s += "#define FILTER_CUT\n";
  if (layout.term_filter == TermFilter::kNone) s += "#define FILTER_NONE\n";
  bool procedural = false, clipmap = false;
  // Slots 0 .. slots() - 1 are drawn; the casters follow them.
  for (const auto* side : {&layout.above, &layout.below, &layout.casters})
    for (LayerKind kind : *side) {
      procedural |= kind == LayerKind::kProceduralGardner;
      clipmap |= kind == LayerKind::kClipmapGardner;
    }
  if (procedural) s += "#define PROCEDURAL\n";
  if (clipmap) s += "#define CLIPMAP\n";
  s += "const int kComponents = " + std::to_string(GardnerTextureParams::kComponents) + ";\n";
  const int slots = layout.slots() + int(layout.casters.size());
  s += "const int kSlots = " + std::to_string(std::max(slots, 1)) + ";\n";
  return s;
}

// The layer code, a sampler per sampled slot and the casters' sunlight, when there are slots.
std::string skySlots(const SkyPassLayout& layout) {
  std::string s;
  const int slots = layout.slots() + int(layout.casters.size());
  if (slots > 0) s += kLayers;
  // One sampler uniform per sampled slot: llvmpipe samples a sampler-array element far more
  // slowly.
  int slot = 0;
  for (const auto* side : {&layout.above, &layout.below, &layout.casters})
    for (LayerKind kind : *side) {
      const std::string name = " u_table" + std::to_string(slot++) + ";\n";
      if (kind == LayerKind::kClipmapGardner) s += "uniform sampler2DArray" + name;
      if (kind == LayerKind::kBakedGardner || kind == LayerKind::kTable)
        s += "uniform sampler2D" + name;
    }
  // planesSunlightNofK: the product over the N highest of the K casters, for a plane that
  // only they lie above; the ground reads all K.
  const int total = int(layout.casters.size());
  for (int c = 0; c < total; ++c)
    s += casterFunction(c, layout.slots() + c, layout.casters[std::size_t(c)]);
  for (int n = 1; n <= total; ++n) {
    std::string product = "1.0";
    for (int c = total - n; c < total; ++c)
      product += " * casterSunlight" + std::to_string(c) + "(hit, height)";
    s += "float " + planesSunlightName(n, total) + "(LayerHit hit, float height) { return " +
         product + "; }\n";
  }

  return s;
}

// Casters above slot `slot`'s plane; all of them where the layout does not say.
int shadedBy(const SkyPassLayout& layout, int slot) {
  return std::size_t(slot) < layout.shaded_by.size() ? layout.shaded_by[std::size_t(slot)]
                                                     : int(layout.casters.size());
}

// main(): the slots nearest first on the side the ray looks to, then the background.
std::string skyMain(const SkyPassLayout& layout) {
  std::string s;
  const int total = int(layout.casters.size());
  s += "const float kClear = 1.0 / 1024.0;\n";
  s += "void main() {\n  vec3 r = viewRay();\n";
  if (layout.targets) {
    // Layers behind a target are hidden; the target replaces the background.
    s += "  float target_distance = targetDistance();\n";
    s += "#define inFront(d) ((d) < target_distance)\n";
  } else {
    s += "#define inFront(d) true\n";
  }
  s += "  vec3 colour = vec3(0.0);\n  float transmittance = 1.0;\n";
  // Slots are listed farthest first on each side: emitted in reverse, nearest first.
  const int above = int(layout.above.size());
  if (above > 0) {
    s += "  if (r.z > 0.0) {\n";
    for (int slot = above - 1; slot >= 0; --slot)
      s += slotStatement(slot, layout.above[std::size_t(slot)], shadedBy(layout, slot), total);
    s += "  }\n";
  }
  if (!layout.below.empty()) {
    s += "  if (r.z < 0.0) {\n";
    for (int k = int(layout.below.size()) - 1; k >= 0; --k)
      s += slotStatement(above + k, layout.below[std::size_t(k)], shadedBy(layout, above + k),
                         total);
    s += "  }\n";
  }
  if (layout.background) {
    if (layout.ground && total > 0)  // the ground, where the layers in front let it show
      s += "  if (r.z < 0.0 && transmittance > kClear) g_planes_sun = " +
           planesSunlight(total, total, "hitPlane(-u_camera_z, r)", "-u_camera_z") + ";\n";
    s += "  vec3 behind = background(r);\n";
    if (layout.targets) s += "  if (target_distance < kFar) behind = targetColour();\n";
    s += "  colour += transmittance * behind;\n";
  }
  s += "  o_colour = vec4(colour, 1.0 - transmittance);\n}\n";
  return s;
}

}  // namespace

std::string skyFragmentSource(const SkyPassLayout& layout) {
  return skyDefines(layout) + commonSource() + skySlots(layout) + skyMain(layout);
}

}  // namespace nephele
