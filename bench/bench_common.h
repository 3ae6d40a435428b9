#pragma once
// Pieces both benchmark programs share: a named knob setting and the timed frame.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "config/scene_file.h"
#include "renderer/frame_timing.h"
#include "renderer/renderer.h"

namespace nephele::bench {

struct Knob {
  const char* name;
  RenderSettings settings;
};

// A knob from a name and an edit of the default settings.
template <typename Edit>
Knob knob(const char* name, Edit edit) {
  Knob k{name, {}};
  edit(k.settings);
  return k;
}

// Relative luminance of linear RGB (ITU-R BT.709 weights).
inline double linearLuminance(double r, double g, double b) {
  return 0.2126 * r + 0.7152 * g + 0.0722 * b;
}

// The GL renderer on the default platform, or null after printing why there is none.
inline std::unique_ptr<Renderer> openRenderer() {
  std::string error;
  auto renderer = createRenderer({}, error);
  if (!renderer) std::fprintf(stderr, "%s\n", error.c_str());
  return renderer;
}

// Median milliseconds of `repeats` frames after one warm-up (shader compile, texture bake).
// Each frame includes its readback, so it has finished when timed.
inline double medianFrameMilliseconds(Renderer& renderer, const Scene& scene,
                                      const RenderSettings& settings, int repeats,
                                      bool float_target) {
  return medianMilliseconds(repeats, [&] {
    if (float_target)
      renderer.renderFloat(scene, settings);
    else
      renderer.renderSrgb8(scene, settings);
  });
}

// A frame's budget in one line (FrameTimes): the CPU stages, the GPU passes by timer query,
// the wait for them and the readback, in milliseconds; stages and passes at 0 left out.
inline std::string frameBudgetLine(const FrameTimes& t) {
  std::string out = "cpu";
  char item[64];
  auto add = [&](const char* name, double ms) {
    std::snprintf(item, sizeof item, " %s %.2f", name, ms);
    out += item;
  };
  for (std::size_t i = 0; i < t.cpu_ms.size(); ++i)
    if (t.cpu_ms[i] > 0.005) add(kCpuStageNames[i], t.cpu_ms[i]);
  add("(submit", t.submit_ms);
  out += ") | gpu";
  for (std::size_t i = 0; i < t.gpu_ms.size(); ++i)
    if (t.gpu_ms[i] > 0.005) add(kGpuPassNames[i], t.gpu_ms[i]);
  add("(sum", t.gpuTotal());
  out += ") |";
  add("wait", t.wait_ms);
  add("readback", t.readback_ms);
  return out;
}

// Sets the camera's image size from "WxH"; false, after saying why, when it is not one.
inline bool parseSize(const std::string& size, Camera& camera) {
  int width = 0, height = 0;
  if (std::sscanf(size.c_str(), "%dx%d", &width, &height) != 2 || width < 1 || height < 1) {
    std::fprintf(stderr, "size '%s' is not WxH with both sides at least 1\n", size.c_str());
    return false;
  }
  camera.width = width, camera.height = height;
  return true;
}

// Reads the scene file at `path`; false, after printing the error, when it cannot be used.
inline bool loadPreset(const std::string& path, SceneFile& file) {
  const std::string error = loadSceneFile(path, file);
  if (!error.empty()) std::fprintf(stderr, "%s\n", error.c_str());
  return error.empty();
}

// Resident memory of this process, MiB (Linux /proc/self/statm).
inline double residentMiB() {
  std::ifstream statm("/proc/self/statm");
  double pages = 0.0, resident = 0.0;
  statm >> pages >> resident;
  return resident * 4096.0 / (1024.0 * 1024.0);
}

// The scene files (*.toml) in `directory`, sorted by name.
inline std::vector<std::filesystem::path> presetFiles(const std::string& directory) {
  std::vector<std::filesystem::path> files;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(directory, error))
    if (entry.path().extension() == ".toml") files.push_back(entry.path());
  if (error)
    std::fprintf(stderr, "%s: cannot read the directory (%s)\n", directory.c_str(),
                 error.message().c_str());
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace nephele::bench
