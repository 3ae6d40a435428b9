#pragma once
// The CPU reference renderer (SPEC section 7): double precision, exact ray-plane hits, every
// texture term, per-pixel depth order, supersampled. Slow and simple enough to trust.
#include "renderer/render_settings.h"
#include "world/image.h"
#include "world/scene.h"

namespace nephele {

FloatImage renderReference(const Scene& scene, const ReferenceSettings& settings = {});

}  // namespace nephele
