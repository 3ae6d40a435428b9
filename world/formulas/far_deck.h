// A far deck standing for a field's heaps (MODEL.md section 11): the cover it shows along a
// view ray, for which its threshold table is read. Shared by world/formations/region.cpp
// (farApparentCover, farThreshold) and the GL renderer's
// renderer/gl/shaders/sky/layers.glsl (layerThreshold; see prelude.h). Its light is the
// heaps' mean light, computed once on the CPU for both renderers (lightFarDeck,
// meanHeapLight), and sphereDiffuse (shading.h) per pixel.
#ifdef __cplusplus
#pragma once
#include "world/formulas/prelude.h"

namespace nephele::formulas {
#endif

// The apparent cover along view ray r (any length, not level) of heaps covering `coverage` of
// the ground seen straight down: 1 - (1 - coverage)^(1 + k cot e), e the ray's elevation and k
// the ratio of a heap's side silhouette to its footprint (a Boolean model seen from the side
// over a path cot e times as long). |r.z| counts as at least 1e-9 |r|.
FORMULA real farApparentCover(real coverage, real side_ratio, vec3 r) {
  real cot_e = length(vec2(r.x, r.y)) / max(abs(r.z), 1e-9 * length(r));
  return 1.0 - pow(1.0 - min(coverage, 1.0), 1.0 + side_ratio * cot_e);
}

// A far deck's threshold table holds T1 at apparent cover 0, 1 / kFarCoverSteps, ..., 1
// (FarCover::threshold, filled by thresholdForCoverage), read at tableCell (table.h).
CONSTANT int kFarCoverSteps = 16;

#ifdef __cplusplus
}  // namespace nephele::formulas
#endif
