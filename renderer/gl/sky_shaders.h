#pragma once
// GLSL for the sky: the background (sky gradient, ground) and textured cloud layers. One
// generator serves both pass structures: a fused pass (background and every layer composited
// in registers, written once) and multipass (background, then one blended pass per layer).
// Every pass writes premultiplied colour and coverage, blended with (ONE, ONE_MINUS_SRC_ALPHA).
#include <string>
#include <vector>

#include "renderer/render_settings.h"
#include "world/sea.h"

namespace nephele {

// How a slot reads its layer's texture: a periodic table of Gardner's texture (term
// truncations as mip levels), Gardner's sines per pixel, a clipmap of a texture that never
// repeats (LayerClipmaps), or a tabulated noise.
enum class LayerKind { kBakedGardner, kProceduralGardner, kTable, kClipmapGardner };

inline constexpr int kMaxLayerSlots = 8;
// The sea's sines a sky pass holds at most: the spectrum's (Limits::kSeaWaves) and the host's
// wave trains.
inline constexpr int kMaxSeaWaves = 128 + kMaxWaveTrains;

// What one pass computes; everything a scene does not need is compiled out.
struct SkyPassLayout {
  bool background = true;
  // Slots 0..above.size()-1 are layers above the camera, farthest (highest) first; the next
  // below.size() slots are layers below it, farthest (lowest) first.
  std::vector<LayerKind> above;
  std::vector<LayerKind> below;
  TermFilter term_filter = TermFilter::kFade;
  unsigned air = 0;  // the media of the air (airMedia, world/scene.h)
  bool specular = false;
  bool targets = false;  // opaque targets were drawn first (their colour and distance)
  bool regions = false;  // some layer lies in a bounded region (region.h)
  bool shadows = false;  // the ground takes the clouds' shadows from the shadow map
  bool sea = false;      // the sea in place of the ground (MODEL.md section 18)
  bool ground = true;    // with the background: the pass's area reaches below the horizon
  // Layers whose shadows fall on the ground and the slots' planes (MODEL.md section 16, "sky
  // planes"), as slots slots() onwards: every layer of the frame while the sun is up.
  std::vector<LayerKind> casters;
  // Per slot, how many casters lie above its plane: the last ones of `casters`, which run from
  // the lowest up. A slot reads only those (llvmpipe runs every branch a pixel group meets, so
  // a caster skipped at run time still costs its texture read).
  std::vector<int> shaded_by;

  int slots() const { return int(above.size() + below.size()); }
  std::string key() const;
};

// The view chunk every screen-space pass shares: the view ray, fog, the background and the
// targets' colour and distance, each behind its #define.
// The formulas the GL shares with the CPU reference (world/formulas/, prelude first), as GLSL:
// every stage that calls one holds them all (the compiler drops what a stage does not call).
std::string formulaSource();
// The #defines of a stage that draws the air's `media` (airMedia bits, world/scene.h): AIR and
// one per medium, so that applyAir holds only those (shaders/sky/common.glsl); none for none.
std::string airDefines(unsigned media);
std::string viewShaderSource();
std::string polygonVertexSource();
std::string skyFragmentSource(const SkyPassLayout& layout);
// The pass that fills a clipmap ring's texels from Gardner's sines (slot 0's uniforms).
std::string clipmapBakeSource();

}  // namespace nephele
