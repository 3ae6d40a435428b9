// A table read linearly (the far decks' thresholds, the shadows' mean opacities): where a value
// in [0, 1] falls. Shared by world/formations/region.cpp (farThreshold), cloud_shadow.cpp
// (meanOpacity) and the GL renderer's sky/layers.glsl and shadow_map/sunlight.glsl (see
// prelude.h).
#ifdef __cplusplus
#pragma once
#include "world/formulas/prelude.h"

namespace nephele::formulas {
#endif

// The cell of a table of steps + 1 values at 0, 1 / steps, ..., 1 where x (clamped to [0, 1])
// falls and the place in it, (k, f): the value is mix(t[k], t[k + 1], f), k at most steps - 1.
FORMULA vec2 tableCell(real x, int steps) {
  real at = clamp(x, 0.0, 1.0) * real(steps);
  real k = min(floor(at), real(steps - 1));
  return vec2(k, at - k);
}

#ifdef __cplusplus
}  // namespace nephele::formulas
#endif
