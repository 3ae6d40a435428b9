// Where a layer's cover is (MODEL.md section 11): a region's weight from its bands, and the
// threshold it raises. Shared by world/formations/region.h and region.cpp (bandRamp,
// regionLocal, regionWeight, regionThreshold) and the GL renderer's
// renderer/gl/shaders/sky/layers.glsl (layerThreshold; see prelude.h).
#ifdef __cplusplus
#pragma once
#include "world/formulas/prelude.h"

namespace nephele::formulas {
#endif

// Bands narrower than this count as this wide (a step, without dividing by zero).
CONSTANT real kRegionMinBand = 1.0e-3;

// Smoothstep of x / width clamped to [0, 1] (width at least kRegionMinBand): every band of a
// region, and a far deck's hole, ramps this way.
FORMULA real bandRamp(real x, real width) {
  real u = clamp(x / max(width, kRegionMinBand), 0.0, 1.0);
  return u * u * (3.0 - 2.0 * u);
}

// A region's coordinates of offset d from its centre, its heading's cosine and sine given: x
// across the front line (positive to the right of the heading), y along it.
FORMULA vec2 regionAxes(vec2 d, real cos_heading, real sin_heading) {
  return vec2(d.x * cos_heading - d.y * sin_heading, d.x * sin_heading + d.y * cos_heading);
}

// How much of the cover is present at region coordinates q, 0..1: smoothstep ramps over the
// edge band inside each half size, times, for one side of a front (side -1 or +1; 0 the whole
// rectangle), weight 1/2 on the line rising to 1 half a transition band into that side.
FORMULA real regionWeightAt(vec2 q, vec2 half_size, real edge, real side, real transition) {
  real w = bandRamp(half_size.x - abs(q.x), edge) * bandRamp(half_size.y - abs(q.y), edge);
  if (side != 0.0) w *= bandRamp(side * q.x + 0.5 * transition, transition);
  return w;
}

// A sky plane's T1 where the region's weight is w: raised towards 1, above every value of T,
// as w falls to 0, so that cover thins out and breaks up into the texture's highest peaks
// before it ends, as a layer's edge does.
FORMULA real regionThreshold(real t1, real weight) {
  return t1 >= 1.0 ? t1 : t1 + (1.0 - weight) * (1.0 - t1);
}

#ifdef __cplusplus
}  // namespace nephele::formulas
#endif
