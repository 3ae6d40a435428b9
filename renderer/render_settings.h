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
  // Baked texture resolution per cycle of each level's highest term. 4 costs 0.3 dB against
  // 16 on the cirrus preset and is 5 ms faster at 1280x1024 (texture cache traffic).
  int bake_texels_per_cycle = 4;
};

// The CPU reference (SPEC section 7).
struct ReferenceSettings {
  int samples_per_axis = 4;  // supersampling grid per pixel
  int threads = 0;           // 0: one per hardware thread
};

}  // namespace nephele
