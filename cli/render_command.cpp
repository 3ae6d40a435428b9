#include "cli/render_command.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "config/scene_file.h"
#include "renderer/renderer.h"
#include "world/check.h"
#include "world/world.h"

namespace nephele {
namespace {

using Clock = std::chrono::steady_clock;

double millisecondsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Applies command-line overrides to the scene; returns an error for invalid values.
std::string applyOverrides(const RenderCommandOptions& o, SceneFile& file) {
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
      return "command line: " + out.str();
    file.scene.sun.azimuth_deg = (*o.sun)[0];
    file.scene.sun.elevation_deg = (*o.sun)[1];
  }
  if (o.time && !file.dynamics.automata.empty() && *o.time > Limits::kMaxAutomatonTime)
    return "command line: --time " + std::to_string(*o.time) +
           " is out of range with automaton clouds (allowed: 0 to 86400 s)";
  if (o.time)
    if (std::string e = automatonWorkError(file.dynamics.automata, *o.time); !e.empty())
      return "command line: --time: " + e;
  // The names were checked against the same lists when the flags were parsed.
  if (o.texture)
    file.render.texture_evaluation =
        TextureEvaluation(nameIndex(kTextureEvaluationNames, *o.texture));
  if (o.term_filter)
    file.render.term_filter = TermFilter(nameIndex(kTermFilterNames, *o.term_filter));
  if (o.sky_passes) file.render.sky_passes = SkyPasses(nameIndex(kSkyPassesNames, *o.sky_passes));
  RenderSettings& r = file.render;
  if (o.ellipsoid_passes)
    r.ellipsoid_passes = EllipsoidPasses(nameIndex(kEllipsoidPassesNames, *o.ellipsoid_passes));
  if (o.ellipsoid_order)
    r.ellipsoid_order = EllipsoidOrder(nameIndex(kEllipsoidOrderNames, *o.ellipsoid_order));
  if (o.limb) r.limb = LimbEvaluation(nameIndex(kLimbNames, *o.limb));
  if (o.tile_format) r.tile_format = TileFormat(nameIndex(kTileFormatNames, *o.tile_format));
  if (o.tile_resolution) r.tile_resolution = *o.tile_resolution;
  if (o.tessellation) r.tessellation = *o.tessellation;
  if (o.impostor_tolerance) r.impostor_tolerance_px = *o.impostor_tolerance;
  if (o.volume_step) r.volume_step = *o.volume_step;
  if (o.heap_range) r.heaps.range_m = *o.heap_range;
  if (o.heap_detail) r.heaps.detail_px = *o.heap_detail;
  if (o.ellipsoid_budget) r.ellipsoid_budget = *o.ellipsoid_budget;
  if (o.ellipsoid_overdraw) r.ellipsoid_overdraw = *o.ellipsoid_overdraw;
  if (o.heap_shading_rate) r.heap_shading_rate = *o.heap_shading_rate;
  file.reference.heaps = r.heaps;  // both renderers draw the same heaps
  if (o.samples) file.reference.samples_per_axis = *o.samples;
  std::string error = validateCamera(camera);
  if (error.empty()) error = validateRenderSettings(r);
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
  cmd->add_option("--width", o.width, "Image width in pixels")
      ->check(CLI::Range(1, Limits::kMaxImageSide));
  cmd->add_option("--height", o.height, "Image height in pixels")
      ->check(CLI::Range(1, Limits::kMaxImageSide));
  cmd->add_option("--position", o.position, "Camera position X,Y,Z in metres")
      ->expected(3)
      ->delimiter(',');
  cmd->add_option("--heading", o.heading, "Camera heading, degrees clockwise from north")
      ->check(CLI::Range(-Limits::kMaxHeading, Limits::kMaxHeading));
  cmd->add_option("--pitch", o.pitch, "Camera pitch, degrees, positive up")
      ->check(CLI::Range(-Limits::kMaxPitch, Limits::kMaxPitch));
  cmd->add_option("--roll", o.roll, "Camera roll, degrees, positive right wing down")
      ->check(CLI::Range(-Limits::kMaxRoll, Limits::kMaxRoll));
  cmd->add_option("--vfov", o.vfov, "Vertical field of view, degrees")
      ->check(CLI::Range(Limits::kMinVfov, Limits::kMaxVfov));
  cmd->add_option("--sun", o.sun,
                  "Sun azimuth (degrees clockwise from north) and elevation (degrees), AZ,EL")
      ->delimiter(',');
  cmd->add_option("--time", o.time, "Simulation time in seconds (layers drift with it)")
      ->check(CLI::Range(0.0, Limits::kMaxTime));
  cmd->add_flag("--stats", o.stats,
                "Print what the frame did: passes, ellipsoids drawn and culled, texture terms, "
                "automaton steps and relights");
  cmd->add_option("--texture", o.texture, "Gardner texture on the GPU: auto, baked or procedural")
      ->check(CLI::IsMember(kTextureEvaluationNames));
  cmd->add_option("--term-filter", o.term_filter,
                  "Removal of texture terms above the pixel frequency: fade, cut or none")
      ->check(CLI::IsMember(kTermFilterNames));
  cmd->add_option("--sky-passes", o.sky_passes, "fused, or multipass (one pass per layer)")
      ->check(CLI::IsMember(kSkyPassesNames));
  cmd->add_option("--ellipsoid-passes", o.ellipsoid_passes,
                  "Ellipsoids: fused (exact hit per fragment) or multipass (Elinas tiles)")
      ->check(CLI::IsMember(kEllipsoidPassesNames));
  cmd->add_option("--ellipsoid-order", o.ellipsoid_order,
                  "Fused ellipsoids: per-pixel depth order, or centre (by ellipsoid centre)")
      ->check(CLI::IsMember(kEllipsoidOrderNames));
  cmd->add_option("--limb", o.limb, "Limb function g: exact, or spotlight (Elinas' texture)")
      ->check(CLI::IsMember(kLimbNames));
  cmd->add_option("--tile-resolution", o.tile_resolution,
                  "Multipass tile size: 0 adaptive, or a power of two 8..1024");
  cmd->add_option("--tile-format", o.tile_format, "Multipass tiles: float or rgba8")
      ->check(CLI::IsMember(kTileFormatNames));
  cmd->add_option("--tessellation", o.tessellation,
                  "Multipass ellipsoid mesh: 0 adaptive, or N slices by N stacks (3..256)");
  cmd->add_option("--impostor-tolerance", o.impostor_tolerance,
                  "Reuse far-cloud impostors while they move less than this many pixels (0 off)");
  cmd->add_option("--heap-range", o.heap_range,
                  "Cloud fields: heaps as ellipsoids to this distance (m), a far deck beyond; "
                  "0 is 40 km plus twice the height");
  cmd->add_option("--heap-detail", o.heap_detail,
                  "Cloud fields: every lobe of heaps whose radius spans this many pixels, their "
                  "outline below (0..10000; default 32; 0 every lobe)");
  cmd->add_option("--ellipsoid-budget", o.ellipsoid_budget,
                  "Ellipsoids a frame draws at most, those of largest projected size "
                  "(0..16777216; default 65536; 0 every ellipsoid)");
  cmd->add_option("--ellipsoid-overdraw", o.ellipsoid_overdraw,
                  "Views that the footprints of the ellipsoids a frame draws may cover, those of "
                  "largest projected size first (0..65536; default 256; 0 no bound)");
  cmd->add_option("--heap-shading-rate", o.heap_shading_rate,
                  "Heaps: walk one pixel in N x N and blend those samples to full size (1, 2 "
                  "or 4; default 1, every pixel)");
  cmd->add_option("--volume-step", o.volume_step,
                  "Automaton clouds: view march step in lattice spacings (0.25..8)");
  cmd->add_option("--samples", o.samples, "Reference supersampling per pixel axis")
      ->check(CLI::Range(1, 16));
  cmd->add_option("--png-compression", o.encode.png_compression, "PNG zlib level")
      ->check(CLI::Range(0, 9))
      ->capture_default_str();
  cmd->add_option("--jpeg-quality", o.encode.jpeg_quality, "JPEG quality")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("--exr-compression", o.encode.exr_compression, "EXR compression")
      ->check(CLI::IsMember({"none", "zip", "zips", "piz", "rle", "pxr24", "b44", "dwaa", "dwab"}))
      ->capture_default_str();
  cmd->add_flag("!--exr-float", o.encode.exr_half, "Write EXR as 32-bit float instead of half");
}

int runRenderCommand(const RenderCommandOptions& o) {
  const auto format = imageFileFormatForPath(o.output_path);
  if (!format) {
    spdlog::error("output '{}': unknown image extension (allowed: {})", o.output_path,
                  kImageExtensions);
    return 2;
  }
  SceneFile file;
  if (std::string error = loadSceneFile(o.scene_path, file); !error.empty()) {
    spdlog::error("{}", error);
    return 2;
  }
  if (std::string error = applyOverrides(o, file); !error.empty()) {
    spdlog::error("{}", error);
    return 2;
  }
  FrameRequest request;
  if (!o.channels.empty()) {
    std::string channel_error;
    request.channels = parseChannelList(o.channels, channel_error);
    if (!channel_error.empty()) {
      spdlog::error("--channels: {}", channel_error);
      return 2;
    }
    if (!isFloatFormat(*format)) {
      spdlog::error("--channels: '{}' is an 8-bit format holding colour only; write an .exr",
                    o.output_path);
      return 2;
    }
  }
  // The renderer and its target first: a size the platform cannot allocate is refused before
  // the world is simulated or anything is drawn.
  RendererOptions options;
  options.kind = o.renderer == "reference" ? RendererKind::kReference : RendererKind::kGl;
  options.gl_backend = backendFromName(o.gl_backend);
  options.render = file.render;
  options.reference = file.reference;
  std::string renderer_error;
  const std::unique_ptr<Renderer> renderer = createRenderer(options, renderer_error);
  if (!renderer) {
    spdlog::error("{}", renderer_error);
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
  const Scene scene = world.scene();
  std::size_t ellipsoids = 0;
  for (const EllipsoidCloud& cloud : scene.clouds) ellipsoids += cloud.ellipsoids.size();
  spdlog::info(
      "scene {} at t = {} s: {}x{}, {} layer(s), {} cloud(s) of {} ellipsoid(s), {} automaton "
      "cloud(s), {} target(s){}{}",
      o.scene_path, scene.time_s, scene.camera.width, scene.camera.height, scene.layers.size(),
      scene.clouds.size(), ellipsoids, scene.automata.size(), scene.targets.size(),
      scene.fog ? ", fog" : "", scene.haze ? ", haze" : "");
  renderer->setProgress([&](double done) {
    const double seconds = millisecondsSince(start) / 1000.0;
    if (seconds >= 2.0)  // only long renders need a progress line
      spdlog::info("render: {:.0f} % after {:.1f} s", 100.0 * done, seconds);
  });
  // EXR: every channel asked, as float planes; else 8-bit colour.
  const auto render_start = Clock::now();
  Frame frame;
  if (isFloatFormat(*format))
    frame = renderer->render(scene, request);
  else
    frame.srgb = renderer->renderSrgb8(scene);
  spdlog::info("render: {:.1f} ms", millisecondsSince(render_start));
  const Channels channels = isFloatFormat(*format)
                                ? Channels::planesOf(frame.channels)
                                : Channels{{Channel::kColour}, Channels::Pixels::kSrgb8};
  const std::string error = writeImage(o.output_path, frame, channels, o.encode);
  if (o.stats)
    std::printf("stats: %s automaton_steps=%llu relights=%llu\n", renderer->statsLine().c_str(),
                static_cast<unsigned long long>(world.automatonStepsRun()),
                static_cast<unsigned long long>(world.relightsRun()));
  if (!error.empty()) {
    spdlog::error("{}", error);
    return 1;
  }
  spdlog::info("wrote {} in {:.0f} ms", o.output_path, millisecondsSince(start));
  return 0;
}

}  // namespace nephele
