#pragma once
// What the world thread does with the scene a request or a file leaves it (issue 31, item 6):
// the world built and ticked once, hashed, saved and restored (the copy must hash alike), and
// the heaps a render would build around a camera in the middle of each field. Legal input that
// makes that work heavy is then a finding: libFuzzer's -timeout (5 s in ctest) reports an input
// whose work stalls as it reports a crash, and -rss_limit_mb one whose memory runs away.
#include "world/scene.h"
#include "world/world.h"

namespace nephele {

inline void exerciseWorld(const Scene& scene, const WorldDynamics& dynamics) {
  World world(scene, dynamics);
  if (!world.advance(1.0 / 30.0).empty()) return;
  const std::uint64_t hash = world.hash();
  World copy(Scene{}, WorldDynamics{});
  if (!copy.restore(world.snapshot()).empty() || copy.hash() != hash) __builtin_trap();
  Scene now = world.scene();
  for (const CloudField& field : scene.fields) {
    now.camera.position.z = field.base_m + 0.5 * field.thickness_m;
    (void)withFieldClouds(now);
  }
}

}  // namespace nephele
