#pragma once
// Speed-for-accuracy knobs of the GL renderer; each is measured against the CPU reference by
// `nephele bench` (docs/ACCURACY.md).
#include "world/formations/cloud_field.h"
#include "world/sea.h"
#include "world/textures/gardner_texture.h"

namespace nephele {

enum class TextureEvaluation {
  kAuto,        // baked for ellipsoids; a layer's clipmap filled over the frames after its first
  kBaked,       // Gardner's texture baked per layer into a mip chain of term truncations
  kProcedural,  // Gardner's sum of sines evaluated per fragment
};

enum class SkyPasses {
  kFused,      // background and every layer in one pass, composited in the shader
  kMultipass,  // a background pass, then one blended pass per layer (Elinas-style)
};

// Ellipsoid clouds (Gardner; Elinas and Stuerzlinger).
enum class EllipsoidPasses {
  kFused,      // one pass per ellipsoid straight to the screen: exact ray-quadric hit per
               // fragment over its screen rectangle, every term of eq. 8 and 11 at once
  kMultipass,  // Elinas: per-ellipsoid tiles in an atlas (threshold, limb, colour passes on a
               // tessellated ellipsoid), a shader pass applying 1/D, then tiles composited
};

enum class EllipsoidOrder {
  kCentre,    // back to front by distance to each ellipsoid's centre (Elinas)
  kPerPixel,  // each pixel composites the cloud's ellipsoids by the depth of their hits
};

enum class LimbEvaluation {
  kExact,      // g from the discriminant form per fragment (MODEL.md section 4)
  kSpotlight,  // Elinas: a radial 1 - rho^2 texture projected from the eye along the cone
};

enum class TileFormat { kRgba8, kFloat };

// The CPU reference's supersampling per pixel axis by default (the knob reference_samples).
inline constexpr int kReferenceSamples = 4;

// The knobs' fields and defaults come from their rows in render_knobs.inc, which documents
// each; render_knobs.h reads, checks, documents and sweeps them.
struct RenderSettings {
#define NEPHELE_KNOB(Type, field, default_value, ...) Type field = default_value;
#define NEPHELE_HEAP_KNOB(...)
#include "renderer/render_knobs.inc"
#undef NEPHELE_KNOB
#undef NEPHELE_HEAP_KNOB
  // Heaps of cloud fields, as the reference draws them too: `heap_range` and `heap_detail`.
  HeapDrawing heaps{};

  // Cloud depth and the infrared band (renderer/frame.h) are traced on the CPU, one ray per
  // block of channel_divisor x channel_divisor pixels copied to the block: cost falls with its
  // square, error grows at cloud edges. Set by `nephele dataset --channel-divisor`, not by
  // scene files; `nephele bench` sweeps it apart (the label channels).
  int channel_divisor = 1;
};

// The CPU reference (MODEL.md section 7).
struct ReferenceSettings {
  int samples_per_axis = kReferenceSamples;  // supersampling grid per pixel
  int threads = 0;                           // 0: one per hardware thread
  HeapDrawing heaps{};                       // as RenderSettings::heaps
  int label_divisor = 1;           // depth, cloud depth, object id: one centre ray per N x N block
  int sea_waves = kSeaComponents;  // as RenderSettings::sea_waves
};

// The reference's settings that render settings give: its supersampling (reference_samples),
// the heaps and sea both renderers draw, and the label channels' divisor.
inline ReferenceSettings referenceSettingsOf(const RenderSettings& render) {
  ReferenceSettings out;
  out.samples_per_axis = render.reference_samples;
  out.heaps = render.heaps;
  out.sea_waves = render.sea_waves;
  out.label_divisor = render.channel_divisor;
  return out;
}

}  // namespace nephele
