#pragma once
// Speed-for-accuracy knobs of the GL renderer; each is measured against the CPU reference by
// bench/render_bench.
#include "world/gardner_texture.h"

namespace nephele {

enum class TextureEvaluation {
  kBaked,       // Gardner's texture baked per layer into a mip chain of term truncations
  kProcedural,  // Gardner's sum of sines evaluated per fragment
};

struct RenderSettings {
  TextureEvaluation texture_evaluation = TextureEvaluation::kBaked;
  TermFilter term_filter = TermFilter::kFade;
  int bake_texels_per_cycle = 16;  // baked texture resolution per cycle of the highest term
};

// The CPU reference (SPEC section 7).
struct ReferenceSettings {
  int samples_per_axis = 4;  // supersampling grid per pixel
  int threads = 0;           // 0: one per hardware thread
};

}  // namespace nephele
