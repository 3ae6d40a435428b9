#pragma once
// `nephele render SCENE -o OUT`: one image of a scene file.
#include <array>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "config/scene_file.h"
#include "image/image_encoding.h"
#include "renderer/frame.h"
#include "renderer/gl/gl_platform.h"
#include "world/world.h"

namespace nephele {

struct RenderCommandOptions {
  std::string scene_path;
  std::string output_path;
  std::string gl_backend = "auto";
  std::string renderer = "gl";  // or "reference"
  std::string channels;         // comma-separated channel names (renderer/frame.h); EXR only
  std::optional<int> width, height;
  std::optional<std::vector<double>> position;
  std::optional<double> heading, pitch, roll, vfov, time;
  std::optional<std::array<double, 2>> sun;  // azimuth, elevation, degrees
  // Render knobs given as flags (one per row of renderer/render_knobs.inc): name, value as
  // written, in the order given.
  std::vector<std::pair<std::string, std::string>> knobs;
  bool stats = false;
  EncodeOptions encode;
};

void addRenderCommand(CLI::App& app, RenderCommandOptions& options);

// The world at the scene file's time: automaton clouds are stepped from time 0, with a
// progress line when that takes a while.
Scene sceneAtTime(const SceneFile& file);
World worldAtTime(const SceneFile& file);

// The --gl values, and the back end each names (checked when the flag was parsed).
inline const std::vector<std::string> kGlBackendNames{"auto", "egl", "osmesa"};
GlBackend backendFromName(const std::string& name);
// Channel names separated by commas into a set; `error` names an unknown one and lists the
// allowed.
ChannelSet parseChannelList(const std::string& list, std::string& error);

// Runs the command; returns the process exit code (0 ok, 2 bad input, 1 failure).
int runRenderCommand(const RenderCommandOptions& options);

}  // namespace nephele
