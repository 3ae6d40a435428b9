#pragma once
// The CPU reference renderer (MODEL.md section 7): double precision, exact ray-plane hits, every
// texture term, exact ray-ellipsoid hits and limb function, per-pixel depth order,
// supersampled. Slow and simple enough to trust.
#include <functional>

#include "image/image.h"
#include "renderer/render_settings.h"
#include "world/scene.h"

namespace nephele {

// `progress`, if given, is called on the calling thread with the fraction of rows started,
// about every tenth of the image.
FloatImage renderReference(const Scene& scene, const ReferenceSettings& settings = {},
                           const std::function<void(double)>& progress = {});

}  // namespace nephele
