// libFuzzer target for the files an operator hands the daemon and the render command: scene
// files and daemon configs (TOML). Built with clang by tests/CMakeLists.txt and run briefly
// by ctest. The first input byte picks the reader. Every input must end in a parsed value or
// an error message; nothing may crash, hang or read outside the text.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "config/daemon_config.h"
#include "config/scene_file.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace nephele;
  if (size < 1) return 0;
  const std::uint8_t selector = data[0];
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  if (selector % 2 == 0) {
    SceneFile scene;
    (void)parseSceneText(text, "fuzz.toml", scene);
  } else {
    // The config's scene path is resolved beside this name; presets sit in config/scenes.
    DaemonConfig config;
    (void)parseDaemonConfig(text, NEPHELE_SOURCE_DIR "/config/fuzz.toml", config);
  }
  return 0;
}
