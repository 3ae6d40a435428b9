// Gardner's texture (MODEL.md section 2): how many of its terms a pixel's footprint resolves, and
// T from its sums. Shared by world/textures/gardner_texture (termCountForFootprint,
// textureFromSums) and the GL renderer's sky and ellipsoid shaders (see prelude.h). The sums
// themselves are each side's: the GPU takes phases reduced about an origin and gardnerSin.
#ifdef __cplusplus
#pragma once
#include "world/formulas/prelude.h"

namespace nephele::formulas {
#endif

// How terms above the pixel's frequency are removed: TermFilter's kFade, kCut and kNone.
CONSTANT int kTermFade = 0;
CONSTANT int kTermCut = 1;
CONSTANT int kTermAll = 2;

// The terms a footprint of `footprint` periods resolves, of `terms`: term j (1-based) resolves
// while 2^j footprint <= 1/2. kTermFade fades a term out over the octave below that (a
// fractional count), kTermCut drops it there, kTermAll keeps every term.
FORMULA real resolvedTerms(real footprint, real terms, int removal) {
  if (removal == kTermAll) return terms;
  real highest = log2(0.5 / max(footprint, 1e-30));
  if (removal == kTermCut) return clamp(floor(highest), 0.0, terms);
  return clamp(highest - 1.0, 0.0, terms);
}

// Gardner's T from the two sums and k (MODEL.md section 2): k max(SX, 0) max(SY, 0).
FORMULA real textureFromSums(real sx, real sy, real k) {
  return k * max(sx, 0.0) * max(sy, 0.0);
}

#ifdef __cplusplus
}  // namespace nephele::formulas
#endif
