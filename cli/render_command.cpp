#include "cli/render_command.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "config/scene_file.h"
#include "renderer/encode.h"
#include "renderer/renderer.h"
#include "world/check.h"
#include "world/world.h"

namespace nephele {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Applies the camera's, the sun's and the time's flags; returns an error for invalid values.
std::string applyViewOverrides(const RenderCommandOptions& o, SceneFile& file) {
  Camera& camera = file.scene.camera;
  if (o.width) camera.width = *o.width;
  if (o.height) camera.height = *o.height;
  if (o.position) camera.position = {(*o.position)[0], (*o.position)[1], (*o.position)[2]};
  if (o.heading) camera.orientation.heading_deg = *o.heading;
  if (o.pitch) camera.orientation.pitch_deg = *o.pitch;
  if (o.roll) camera.orientation.roll_deg = *o.roll;
  if (o.vfov) camera.vfov_deg = *o.vfov;
  if (o.time) file.scene.time_s = *o.time;
  if (o.sun) {
    std::ostringstream out;
    if (outOfRange(out, "--sun azimuth", (*o.sun)[0],
                   {-Limits::kMaxHeading, Limits::kMaxHeading}) ||
        outOfRange(out, "--sun elevation", (*o.sun)[1], {-Limits::kMaxPitch, Limits::kMaxPitch}))
      return out.str();
    file.scene.sun.azimuth_deg = (*o.sun)[0];
    file.scene.sun.elevation_deg = (*o.sun)[1];
  }
  if (o.time && !file.dynamics.automata.empty() && *o.time > Limits::kMaxAutomatonTime)
    return "--time " + std::to_string(*o.time) +
           " is out of range with automaton clouds (allowed: 0 to 86400 s)";
  if (o.time)
    if (std::string e = automatonWorkError(file.dynamics.automata, *o.time); !e.empty())
      return "--time: " + e;
  return validateCamera(camera);
}

// Applies the render knobs' flags, each through its knob's one check.
std::string applyKnobOverrides(const RenderCommandOptions& o, SceneFile& file) {
  for (const auto& [name, text] : o.knobs) {
    const RenderKnob& knob = *findRenderKnob(name);  // the flags were made from the table
    double value = 0.0;
    if (std::string e = parseKnobText(knob, text, value); !e.empty()) return e;
    if (std::string e = knobError(knob, value); !e.empty()) return e;
    knob.set(file.render, value);
  }
  return "";
}

// Applies every command-line override to the scene; returns an error for invalid values.
std::string applyOverrides(const RenderCommandOptions& o, SceneFile& file) {
  std::string error = applyViewOverrides(o, file);
  if (error.empty()) error = applyKnobOverrides(o, file);
  return error.empty() ? "" : "command line: " + error;
}

}  // namespace

Scene sceneAtTime(const SceneFile& file) {
  return worldAtTime(file).scene();
}

World worldAtTime(const SceneFile& file) {
  World world(file.scene, file.dynamics);
  // Twenty pieces with automaton clouds, for the progress line.
  const auto start = Clock::now();
  const std::string error = world.advanceInPieces(
      file.scene.time_s, world.automata().empty() ? 1 : 20, [&](int i, int n) {
        if (const double seconds = millisecondsSince(start) / 1000.0; seconds >= 2.0 && i < n)
          spdlog::info("simulating to t = {:.1f} s: {} %, {} automaton steps", file.scene.time_s,
                       100 * i / n, world.automatonStepsRun());
      });
  NEPHELE_CHECK(error.empty(), error);  // the time was validated with the scene
  return world;
}

ChannelSet parseChannelList(const std::string& list, std::string& error) {
  ChannelSet set;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t comma = std::min(list.find(',', start), list.size());
    const std::string name = list.substr(start, comma - start);
    const auto channel = channelFromName(name);
    if (!channel) {
      error = "unknown channel '" + name + "' (allowed: " + channelNames() + ")";
      return {};
    }
    set.add(*channel);
    start = comma + 1;
  }
  return set;
}

GlBackend backendFromName(const std::string& name) {
  if (name == "egl") return GlBackend::kEgl;
  if (name == "osmesa") return GlBackend::kOsmesa;
  return GlBackend::kAuto;
}

namespace {

void addViewFlags(CLI::App& cmd, RenderCommandOptions& o) {
  cmd.add_option("--width", o.width, "Image width in pixels")
      ->check(CLI::Range(1, Limits::kMaxImageSide));
  cmd.add_option("--height", o.height, "Image height in pixels")
      ->check(CLI::Range(1, Limits::kMaxImageSide));
  cmd.add_option("--position", o.position, "Camera position X,Y,Z in metres")
      ->expected(3)
      ->delimiter(',');
  cmd.add_option("--heading", o.heading, "Camera heading, degrees clockwise from north")
      ->check(CLI::Range(-Limits::kMaxHeading, Limits::kMaxHeading));
  cmd.add_option("--pitch", o.pitch, "Camera pitch, degrees, positive up")
      ->check(CLI::Range(-Limits::kMaxPitch, Limits::kMaxPitch));
  cmd.add_option("--roll", o.roll, "Camera roll, degrees, positive right wing down")
      ->check(CLI::Range(-Limits::kMaxRoll, Limits::kMaxRoll));
  cmd.add_option("--vfov", o.vfov, "Vertical field of view, degrees")
      ->check(CLI::Range(Limits::kMinVfov, Limits::kMaxVfov));
  cmd.add_option("--sun", o.sun,
                 "Sun azimuth (degrees clockwise from north) and elevation (degrees), AZ,EL")
      ->delimiter(',');
  cmd.add_option("--time", o.time, "Simulation time in seconds (layers drift with it)")
      ->check(CLI::Range(0.0, Limits::kMaxTime));
}

// One flag per render knob (renderer/render_knobs.inc): --kebab-case of its name, its doc as
// help. Values are checked with the scene file's, by the knob's one check.
void addKnobFlags(CLI::App& cmd, RenderCommandOptions& o) {
  for (const RenderKnob& knob : renderKnobs()) {
    CLI::Option* flag = cmd.add_option_function<std::string>(
        knob.flag(),
        [&o, name = std::string(knob.name)](const std::string& value) {
          o.knobs.emplace_back(name, value);
        },
        knob.helpText());
    if (knob.type == KnobType::kChoice)
      flag->check(CLI::IsMember(knob.values.names));
    else
      flag->type_name(knob.type == KnobType::kInteger   ? "INT"
                      : knob.type == KnobType::kBoolean ? "BOOL"
                                                        : "FLOAT");
  }
  // --samples: the short name of --reference-samples, as `nephele bench` names its reference's.
  cmd.add_option_function<std::string>(
         "--samples",
         [&o](const std::string& value) { o.knobs.emplace_back("reference_samples", value); },
         "The same as --reference-samples")
      ->type_name("INT");
}

void addEncodeFlags(CLI::App& cmd, RenderCommandOptions& o) {
  cmd.add_option("--png-compression", o.encode.png_compression, "PNG zlib level")
      ->check(CLI::Range(0, 9))
      ->capture_default_str();
  cmd.add_option("--jpeg-quality", o.encode.jpeg_quality, "JPEG quality")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd.add_option("--exr-compression", o.encode.exr_compression, "EXR compression")
      ->check(CLI::IsMember({"none", "zip", "zips", "piz", "rle", "pxr24", "b44", "dwaa", "dwab"}))
      ->capture_default_str();
  cmd.add_flag("!--exr-float", o.encode.exr_half, "Write EXR as 32-bit float instead of half");
}

}  // namespace

void addRenderCommand(CLI::App& app, RenderCommandOptions& o) {
  CLI::App* cmd = app.add_subcommand("render", "Render one image of a scene file");
  cmd->add_option("scene", o.scene_path, "Scene file (TOML)")->required()->check(CLI::ExistingFile);
  cmd->add_option("-o,--output", o.output_path,
                  "Output image; the extension picks the format: " + std::string(kImageExtensions))
      ->required();
  cmd->add_option("--gl", o.gl_backend, "OpenGL back end")
      ->check(CLI::IsMember(kGlBackendNames))
      ->capture_default_str();
  cmd->add_option("--renderer", o.renderer, "gl, or the CPU reference (slow, exact)")
      ->check(CLI::IsMember({"gl", "reference"}))
      ->capture_default_str();
  cmd->add_option("--channels", o.channels,
                  "EXR output: channels to write, comma-separated, from " + channelNames() +
                      " (default colour,coverage)");
  cmd->add_flag("--stats", o.stats,
                "Print what the frame did: passes, ellipsoids drawn and culled, texture terms, "
                "automaton steps and relights");
  addViewFlags(*cmd, o);
  addKnobFlags(*cmd, o);
  addEncodeFlags(*cmd, o);
}

namespace {

// The scene file with the flags applied; an error for bad input.
std::string loadScene(const RenderCommandOptions& o, SceneFile& file) {
  if (std::string error = loadSceneFile(o.scene_path, file); !error.empty()) return error;
  return applyOverrides(o, file);
}

// The channels --channels asks for; an error for an unknown one or an 8-bit format.
std::string readChannels(const RenderCommandOptions& o, ImageFileFormat format,
                         FrameRequest& request) {
  if (o.channels.empty()) return "";
  std::string error;
  request.channels = parseChannelList(o.channels, error);
  if (!error.empty()) return "--channels: " + error;
  if (!isFloatFormat(format))
    return "--channels: '" + o.output_path +
           "' is an 8-bit format holding colour only; write an .exr";
  return "";
}

void logScene(const std::string& path, const Scene& scene) {
  std::size_t ellipsoids = 0;
  for (const EllipsoidCloud& cloud : scene.clouds) ellipsoids += cloud.ellipsoids.size();
  spdlog::info(
      "scene {} at t = {} s: {}x{}, {} layer(s), {} cloud(s) of {} ellipsoid(s), {} automaton "
      "cloud(s), {} target(s){}{}",
      path, scene.time_s, scene.camera.width, scene.camera.height, scene.layers.size(),
      scene.clouds.size(), ellipsoids, scene.automata.size(), scene.targets.size(),
      scene.fog ? ", fog" : "", scene.haze ? ", haze" : "");
}

// Renders the world's scene and writes the image; the write's error, or empty. Progress
// counts from `start`, before the world was simulated.
std::string renderAndWrite(const RenderCommandOptions& o, Renderer& renderer, const World& world,
                           const FrameRequest& request, ImageFileFormat format,
                           Clock::time_point start) {
  const Scene& scene = world.scene();
  logScene(o.scene_path, scene);
  renderer.setProgress([&](double done) {
    const double seconds = millisecondsSince(start) / 1000.0;
    if (seconds >= 2.0)  // only long renders need a progress line
      spdlog::info("render: {:.0f} % after {:.1f} s", 100.0 * done, seconds);
  });
  // EXR: every channel asked, as float planes; else 8-bit colour.
  const auto render_start = Clock::now();
  Frame frame;
  if (isFloatFormat(format))
    frame = renderer.render(scene, request);
  else
    frame.srgb = renderer.renderSrgb8(scene);
  spdlog::info("render: {:.1f} ms", millisecondsSince(render_start));
  const Channels channels = isFloatFormat(format)
                                ? Channels::planesOf(frame.channels)
                                : Channels{{Channel::kColour}, Channels::Pixels::kSrgb8};
  const std::string error = writeImage(o.output_path, frame, channels, o.encode);
  if (o.stats)
    std::printf("stats: %s automaton_steps=%llu relights=%llu\n", renderer.statsLine().c_str(),
                static_cast<unsigned long long>(world.automatonStepsRun()),
                static_cast<unsigned long long>(world.relightsRun()));
  return error;
}

}  // namespace

int runRenderCommand(const RenderCommandOptions& o) {
  const auto format = imageFileFormatForPath(o.output_path);
  if (!format) {
    spdlog::error("output '{}': unknown image extension (allowed: {})", o.output_path,
                  kImageExtensions);
    return 2;
  }
  SceneFile file;
  FrameRequest request;
  std::string error = loadScene(o, file);
  if (error.empty()) error = readChannels(o, *format, request);
  if (!error.empty()) {
    spdlog::error("{}", error);
    return 2;
  }
  // The renderer and its target first: a size the platform cannot allocate is refused before
  // the world is simulated or anything is drawn.
  RendererOptions options;
  options.kind = o.renderer == "reference" ? RendererKind::kReference : RendererKind::kGl;
  options.gl_backend = backendFromName(o.gl_backend);
  options.render = file.render;
  const std::unique_ptr<Renderer> renderer = createRenderer(options, error);
  if (!renderer) {
    spdlog::error("{}", error);
    return 1;
  }
  spdlog::info("renderer: {}", renderer->description());
  const Camera& camera = file.scene.camera;
  const bool targets = needsTargetLayers(!file.scene.targets.empty(), request.channels);
  if (std::string e =
          renderer->reserve(camera.width, camera.height, isFloatFormat(*format), targets);
      !e.empty()) {
    spdlog::error("--width/--height: {}", e);
    return 2;
  }
  const auto start = Clock::now();
  const World world = worldAtTime(file);
  if (error = renderAndWrite(o, *renderer, world, request, *format, start); !error.empty()) {
    spdlog::error("{}", error);
    return 1;
  }
  spdlog::info("wrote {} in {:.0f} ms", o.output_path, millisecondsSince(start));
  return 0;
}

}  // namespace nephele
