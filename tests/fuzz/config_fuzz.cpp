// libFuzzer target for the files an operator hands the daemon and the render command: scene
// files and daemon configs (TOML). Built with clang by tests/CMakeLists.txt and run briefly
// by ctest. The first input byte picks the reader. Every input must end in a parsed value or
// an error message; nothing may crash, hang or read outside the text.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "config/scene_file.h"
#include "server/daemon_config.h"
#include "tests/fuzz/world_work.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace nephele;
  if (size < 1) return 0;
  const std::uint8_t selector = data[0];
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  if (selector % 2 == 0) {
    SceneFile scene;
    // A scene that reads is then built and ticked as the daemon would (world_work.h), unless
    // its automata's start-up work passes 1/200 of what one request may run (3 s in a release
    // build; under the fuzzer's sanitizers a cell step costs about 0.4 us, 70 times as much,
    // so 1/200 is about a second there): the limits allow a scene file
    // up to about 25 s of it at start-up (world/limits.h), longer than the fuzzer's timeout,
    // and the daemon reads its scene once, before it serves anyone.
    if (!parseSceneText(text, "fuzz.toml", scene).empty()) return 0;
    double work = 0.0;
    for (const AutomatonCloudSpec& a : scene.dynamics.automata)
      work += double(a.cells.cells()) *
              (a.warmup_steps + 1 + a.samples_per_cell * a.samples_per_cell * a.samples_per_cell);
    if (work <= Limits::kMaxCellStepsPerAdvance / 200.0) exerciseWorld(scene.scene, scene.dynamics);
  } else {
    // The config's scene path is resolved beside this name; presets sit in config/scenes.
    DaemonConfig config;
    (void)parseDaemonConfig(text, NEPHELE_SOURCE_DIR "/config/fuzz.toml", config);
  }
  return 0;
}
