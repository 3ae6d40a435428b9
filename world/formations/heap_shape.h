#pragma once
// The shape of one heap of a field (MODEL.md section 10): a cumulus's tiers of lobes, leaning
// with the shear, or a cumulonimbus's flat base, tower, rings and anvil. Internal to
// world/formations (cloud_field.cpp places the heaps; heap_shape.cpp shapes each).
#include <cstddef>
#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "world/formations/cloud_field.h"
#include "world/formations/ellipsoid.h"

namespace nephele {

// Purposes of the counter-based draws of a field's heaps (hashCounters' third key).
enum Draw : std::uint64_t { kCount = 1, kX, kY, kSize, kHeight, kShape, kKeep, kCover, kRise };

// How a field's heaps take the wind shear: the direction downwind at their tops relative to the
// wind carrying them, and its share of the shear at which they lean and spread most.
struct Shear {
  glm::dvec2 direction;  // unit, downwind at the top relative to the heap
  double amount;         // 0 (none) to 1
};
Shear shearOf(const CloudField& f);

// The ellipsoids of one heap of base radius r and height h standing on `base` (the middle of its
// flat bottom), drawn from `seed`; `detailed`: every lobe, else its tower merged into one mound.
// Those from `anvil_from` on are a cumulonimbus's anvil, lit as a heap of its own (MODEL.md
// section 14).
std::vector<Ellipsoid> heapEllipsoids(const CloudField& f, glm::dvec3 base, double r, double h,
                                      std::uint64_t seed, bool detailed, std::size_t& anvil_from);

}  // namespace nephele
