// Gardner's texture seen through a pixel (MODEL.md section 2): how many of its terms the
// pixel's footprint resolves. Shared by world/textures/gardner_texture.cpp
// (termCountForFootprint) and the GL renderer's sky and ellipsoid shaders (see prelude.h).
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

#ifdef __cplusplus
}  // namespace nephele::formulas
#endif
