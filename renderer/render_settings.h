#pragma once
// Speed-for-accuracy knobs of the GL renderer; each is measured against the CPU reference by
// bench/render_bench.
#include "world/gardner_texture.h"

namespace nephele {

enum class TextureEvaluation {
  kBaked,       // Gardner's texture baked per layer into a mip chain of term truncations
  kProcedural,  // Gardner's sum of sines evaluated per fragment
};

enum class SkyPasses {
  kFused,      // background and every layer in one pass, composited in the shader
  kMultipass,  // a background pass, then one blended pass per layer (Elinas-style)
};

struct RenderSettings {
  SkyPasses sky_passes = SkyPasses::kFused;
  TextureEvaluation texture_evaluation = TextureEvaluation::kBaked;
  TermFilter term_filter = TermFilter::kFade;
  // Baked texture resolution per cycle of each level's highest term. Bilinear error falls as
  // 1/tpc^2 (mean 0.0075, 0.0020, 0.0005 for 4, 8, 16 on a close deck); cost rises with it
  // through texture cache traffic (18.3, 19.3, 23.6 ms for cirrus at 1280x1024).
  int bake_texels_per_cycle = 8;
};

// The CPU reference (SPEC section 7).
struct ReferenceSettings {
  int samples_per_axis = 4;  // supersampling grid per pixel
  int threads = 0;           // 0: one per hardware thread
};

}  // namespace nephele
