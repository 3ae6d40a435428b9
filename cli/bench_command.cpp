#include "cli/bench_command.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

#include <unistd.h>

#include "cli/render_command.h"
#include "config/scene_file.h"
#include "image/image_metrics.h"
#include "renderer/frame_timing.h"
#include "renderer/reference/reference_renderer.h"
#include "renderer/renderer.h"
#include "world/formations/ellipsoid_cloud.h"
#include "world/infrared.h"

namespace nephele {
namespace {

using Clock = std::chrono::steady_clock;

double secondsSince(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// One point of the sweep: the scene's own settings with one knob changed (or none).
struct Setting {
  std::string knob;   // empty for the defaults
  std::string value;  // the knob's value, as a scene file or flag spells it
  std::function<void(RenderSettings&)> edit = [](RenderSettings&) {};
  // A knob of the scene rather than of the renderer (the automaton lattice, the layers'
  // lattice breaking); null for none.
  std::function<void(SceneFile&)> scene_edit;
  // The knob changes the model itself (not how closely it is drawn): its error is measured
  // against the reference image of the edited scene.
  bool changes_model = false;
  // Drawn as a continuous view (Renderer::setContinuousView): its image is the frame after
  // flying into the view at 250 m/s for 16 frames at 30 Hz, its time that of the view streamed.
  bool stream = false;
  // Drawn by the CPU reference at this grid (reference_samples), not by the GL: its error
  // against the sweep's reference and its time on the CPU, once. 0 for a GL point.
  int reference_samples = 0;

  std::string name() const { return knob.empty() ? "defaults" : knob + "=" + value; }
};

struct BenchScene {
  std::string name;
  std::string what;
  SceneFile file;
};

struct Point {
  Setting setting;
  double ms = 0.0;
  double floor_multiple = 0.0;
  ImageError error;
  bool same_image = false;   // draws exactly what the defaults draw: its time is noise
  std::vector<float> image;  // its pixels, held while the sweep compares them with the defaults
  bool front = false;
  // Takes no part in the front: the defaults timed again, another model (another sky), or the
  // reference itself.
  bool apart() const {
    return same_image || setting.changes_model || setting.reference_samples > 0;
  }
};

struct SceneResult {
  std::string name;
  std::string what;
  double floor_ms = 0.0;
  double reference_s = 0.0;
  std::vector<Point> points;  // points[0] is the defaults
  std::string default_status;
};

// Gardner's lattice: a layer neither rotated nor jittered, whose texture is periodic and
// baked (bake_texels_per_cycle); rotated or jittered ones are evaluated in a clipmap around
// the camera (MODEL.md section 2).
bool periodic(const CloudLayer& l) {
  return l.texture.gardner.rotation_deg == 0.0 && l.texture.gardner.jitter_octaves == 0.0;
}

// Whether `file` holds what a knob of `scope` acts on.
bool holds(const SceneFile& file, KnobScope scope) {
  const Scene& s = file.scene;
  const bool layers = !s.layers.empty(), fields = !s.fields.empty();
  const bool clouds = !s.clouds.empty() || fields;
  switch (scope) {
    case KnobScope::kLayersOrClouds:
      return layers || clouds;
    case KnobScope::kLatticeLayers:
      return std::any_of(s.layers.begin(), s.layers.end(), periodic);
    case KnobScope::kLayers:
      return layers;
    case KnobScope::kClouds:
      return clouds;
    case KnobScope::kSingleClouds:
      return clouds && !fields;
    case KnobScope::kFields:
      return fields;
    case KnobScope::kShadowCasters:
      return fields || std::any_of(s.clouds.begin(), s.clouds.end(), [](const EllipsoidCloud& c) {
               return c.light_extinction > 0.0;
             });
    case KnobScope::kPlanes:
      return layers || !s.weather.empty();
    case KnobScope::kSea:
      return s.sea.has_value();
    case KnobScope::kAutomata:
      return !file.dynamics.automata.empty();
    case KnobScope::kAnything:
      return true;
  }
  return false;
}

// A render knob's points (its row's sweep), on a scene that holds what it acts on.
void addKnobPoints(const RenderKnob& knob, const SceneFile& file, std::vector<Setting>& out) {
  if (!holds(file, knob.scope)) return;
  const bool multipass = knob.how == KnobSweep::kMultipass;
  for (double value : knob.sweep) {
    Setting point;
    point.knob = (multipass ? "ellipsoid_passes=multipass " : "") + std::string(knob.name);
    point.value = knob.format(value);
    point.edit = [&knob, value, multipass](RenderSettings& s) {
      if (multipass) s.ellipsoid_passes = EllipsoidPasses::kMultipass;
      knob.set(s, value);
    };
    point.changes_model = knob.how == KnobSweep::kModel;
    point.stream = knob.how == KnobSweep::kStream;
    if (knob.how == KnobSweep::kReference) point.reference_samples = int(value);
    out.push_back(std::move(point));
  }
}

// The knobs of the scene rather than of the renderer, each another model measured against
// the reference of the edited scene: the automaton lattice, the layers' lattice breaking, a
// distance haze.
void addSceneKnobPoints(const SceneFile& file, std::vector<Setting>& out) {
  auto model = [&](std::string knob, std::string value, std::function<void(SceneFile&)> edit,
                   bool changes_model) {
    out.push_back({std::move(knob), std::move(value), [](RenderSettings&) {}, std::move(edit),
                   changes_model});
  };
  if (!file.dynamics.automata.empty())
    for (int samples : {1, 3})
      model(
          "samples_per_cell", std::to_string(samples),
          [samples](SceneFile& f) {
            for (AutomatonCloudSpec& a : f.dynamics.automata) a.samples_per_cell = samples;
          },
          false);
  // Lattice breaking (MODEL.md section 2) on layers that have it: "off" is Gardner's periodic
  // texture, which the renderer can bake; rotated or jittered terms are evaluated per pixel.
  if (!std::all_of(file.scene.layers.begin(), file.scene.layers.end(), periodic)) {
    auto layers = [&](std::string knob, std::string value, double rotation, double jitter) {
      model(
          std::move(knob), std::move(value),
          [rotation, jitter](SceneFile& f) {
            for (CloudLayer& l : f.scene.layers) {
              GardnerTextureParams& g = l.texture.gardner;
              if (rotation >= 0.0) g.rotation_deg = rotation;
              if (jitter >= 0.0) g.jitter_octaves = jitter;
            }
          },
          true);
    };
    layers("lattice_breaking", "off", 0.0, 0.0);
    layers("rotation", "15", 15.0, -1.0);
    for (double octaves : {0.0, 1.0}) layers("jitter", formatNumber(octaves), -1.0, octaves);
  }
  // Distance haze (MODEL.md section 5) on scenes of heaps, where it shows: its time is the
  // haze's cost, its error the renderer's against the hazy reference.
  if (!file.scene.fields.empty() && !file.scene.haze)
    model(
        "haze", "40000",
        [](SceneFile& f) {
          f.scene.haze = Haze{40000.0, 1200.0};
        },
        true);
}

// The defaults, then every render knob's points (renderer/render_knobs.inc) and the scene's
// knobs, each where it can change the scene's image.
std::vector<Setting> settingsFor(const SceneFile& file) {
  std::vector<Setting> out{{}};
  for (const RenderKnob& knob : renderKnobs()) addKnobPoints(knob, file, out);
  addSceneKnobPoints(file, out);
  return out;
}

// Twenty cumuli of 25 lobes over a 15 km by 12 km field, seen from 1.5 km: 500 ellipsoids.
SceneFile cumulusField(const SceneFile& cumulus) {
  SceneFile file = cumulus;
  const EllipsoidCloud model = cumulus.scene.clouds.at(0);
  file.scene.clouds.clear();
  for (int row = 0; row < 4; ++row)
    for (int column = 0; column < 5; ++column) {
      EllipsoidCloud cloud = model;
      cloud.name = "cumulus_" + std::to_string(row) + "_" + std::to_string(column);
      const glm::dvec3 base(-6000.0 + 3000.0 * column + 700.0 * (row % 2), 4000.0 + 3000.0 * row,
                            900.0);
      cloud.ellipsoids = cumulusEllipsoids(25, base, 1500.0, 100 + 5 * row + column);
      file.scene.clouds.push_back(cloud);
    }
  if (!file.dynamics.clouds.empty())
    file.dynamics.clouds.assign(file.scene.clouds.size(), file.dynamics.clouds.front());
  file.scene.camera.position = {0.0, -2000.0, 1500.0};
  file.scene.camera.orientation = {0.0, -4.0, 0.0};
  file.scene.camera.vfov_deg = 60.0;
  return file;
}

// The fixed scene set of issue 11, in the order the report lists them.
struct SceneEntry {
  const char* name;
  const char* preset;
  const char* what;
};
constexpr SceneEntry kScenes[] = {
    {"cirrus", "cirrus", "cirrus layer at 10 km"},
    {"stratus", "stratus", "stratus layer at 2 km"},
    {"cumulus", "cumulus", "the 27-lobe cumulus from 4.5 km"},
    {"close_up", "cumulus_target", "a cumulus filling a 4 degree view, with targets"},
    {"field_500", "cumulus", "20 cumuli, 500 ellipsoids, from 1.5 km"},
    {"automaton", "automaton_cloud", "one automaton cloud of 20x20x20 cells"},
    {"harbour", "harbour", "Shen's harbour: 20 automaton clouds, sea fog"},
    {"inside", "inside_cloud", "a camera inside the edge of a cloud lobe"},
    {"altocumulus", "genus_altocumulus", "altocumulus from the weather mapping, from the ground"},
    {"cumulus_field", "genus_cumulus", "a cumulus field from the weather mapping, from the ground"},
    {"cumulus_above", "genus_cumulus", "the same field from 1.5 km above its tops, 15 deg down"},
    {"sea", "sea_search", "sea state 4 under cumulus and altocumulus, from 300 m"},
};

// "cirrus, stratus, ...": the names --scenes allows.
std::string sceneNames() {
  std::string names;
  for (const SceneEntry& e : kScenes) names += (names.empty() ? "" : ", ") + std::string(e.name);
  return names;
}

std::string loadScenes(std::vector<BenchScene>& out) {
  for (const SceneEntry& e : kScenes) {
    SceneFile file;
    const std::string path = NEPHELE_SOURCE_DIR "/config/scenes/" + std::string(e.preset) + ".toml";
    if (std::string error = loadSceneFile(path, file); !error.empty()) return error;
    if (std::string(e.name) == "field_500") file = cumulusField(file);
    if (std::string(e.name) == "cumulus_above") {
      const CloudField& field = file.scene.fields.at(0);
      file.scene.camera.position.z = field.base_m + 1.2 * field.thickness_m + 1500.0;
      file.scene.camera.orientation.pitch_deg = -15.0;
    }
    out.push_back({e.name, e.what, file});
  }
  return {};
}

// Pareto front over (time, colour RMSE): no other point is as fast and as accurate and
// better in one of them. A setting that draws the defaults' image exactly is the defaults
// timed again, and one that changes the model draws another sky, so neither takes part.
void markFront(std::vector<Point>& points) {
  for (Point& p : points) {
    p.front = !p.apart() && std::none_of(points.begin(), points.end(), [&](const Point& q) {
      return !q.apart() && q.ms <= p.ms && q.error.rms <= p.error.rms &&
             (q.ms < p.ms || q.error.rms < p.error.rms);
    });
  }
}

// Where the defaults stand: on the front, within 10 % of it (no point both 10 % faster and
// as accurate, or 10 % more accurate and as fast), or which point dominates them.
std::string defaultStatus(const std::vector<Point>& points) {
  const Point& d = points.front();
  if (d.front) return "on the front";
  for (const Point& q : points) {
    if (q.apart()) continue;
    const bool much_faster = q.ms < 0.9 * d.ms && q.error.rms <= d.error.rms;
    const bool much_better = q.error.rms < 0.9 * d.error.rms && q.ms <= d.ms;
    if (much_faster || much_better) return "dominated by " + q.setting.name();
  }
  return "within 10 % of the front";
}

std::string fixed(double value, int decimals) {
  if (std::isinf(value)) return "inf";
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
  return buffer;
}

void printScene(const SceneResult& r, int width, int height, int samples) {
  std::printf("\n%s: %s (%dx%d; reference %dx%d samples, %.1f s; floor %.2f ms)\n", r.name.c_str(),
              r.what.c_str(), width, height, samples, samples, r.reference_s, r.floor_ms);
  std::printf("  %-46s %9s %7s %8s %8s %7s %8s %8s %7s\n", "setting", "ms", "xfloor", "PSNR",
              "RMSE", "max", "covPSNR", "covRMSE", "covmax");
  for (const Point& p : r.points) {
    const ImageError& e = p.error;
    std::printf("%s %-46s %9.2f %7.1f %8s %8.5f %7.4f %8s %8.5f %7.4f%s\n",
                p.front                   ? "*"
                : p.same_image            ? "="
                : p.setting.changes_model ? "m"
                                          : " ",
                p.setting.name().c_str(), p.ms, p.floor_multiple, fixed(e.psnr_db, 1).c_str(),
                e.rms, e.max_abs, fixed(e.coverage_psnr, 1).c_str(), e.coverage_rms, e.coverage_max,
                e.non_finite ? "  NON-FINITE" : "");
  }
  std::printf("  defaults: %s   (* front, = same image as the defaults, m another model)\n",
              r.default_status.c_str());
  std::fflush(stdout);
}

void writeCsv(const std::filesystem::path& path, const std::vector<SceneResult>& results) {
  std::ofstream out(path);
  out << "scene,setting,default,front,ms,floor_ms,floor_multiple,psnr_db,rmse,max_abs,"
         "coverage_psnr_db,coverage_rmse,coverage_max,non_finite\n";
  for (const SceneResult& r : results)
    for (const Point& p : r.points)
      out << r.name << ',' << p.setting.name() << ',' << p.setting.knob.empty() << ',' << p.front
          << ',' << p.ms << ',' << r.floor_ms << ',' << p.floor_multiple << ',' << p.error.psnr_db
          << ',' << p.error.rms << ',' << p.error.max_abs << ',' << p.error.coverage_psnr << ','
          << p.error.coverage_rms << ',' << p.error.coverage_max << ',' << p.error.non_finite
          << '\n';
}

void writeMarkdown(const std::filesystem::path& path, const std::vector<SceneResult>& results,
                   const std::string& header) {
  std::ofstream out(path);
  out << header << "\n\n";
  for (const SceneResult& r : results) {
    out << "#### " << r.name << ": " << r.what << "\n\n"
        << "Floor " << fixed(r.floor_ms, 2) << " ms; defaults " << r.default_status << ".\n\n"
        << "| setting | ms | x floor | PSNR dB | RMSE | max | coverage PSNR | coverage RMSE | "
           "coverage max | front |\n"
        << "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n";
    for (const Point& p : r.points) {
      const ImageError& e = p.error;
      out << "| " << (p.setting.knob.empty() ? "**defaults**" : p.setting.name()) << " | "
          << fixed(p.ms, 2) << " | " << fixed(p.floor_multiple, 1) << " | " << fixed(e.psnr_db, 1)
          << " | " << fixed(e.rms, 5) << " | " << fixed(e.max_abs, 4) << " | "
          << fixed(e.coverage_psnr, 1) << " | " << fixed(e.coverage_rms, 5) << " | "
          << fixed(e.coverage_max, 4) << " | "
          << (p.front                   ? "yes"
              : p.same_image            ? "same image"
              : p.setting.changes_model ? "another model"
                                        : "")
          << " |\n";
    }
    out << "\n";
  }
}

// The label knob channel_divisor: cloud depth and the infrared band, traced on the CPU once
// per N x N pixels, against N = 1 (renderer/render_settings.h).
struct LabelPoint {
  int divisor = 1;
  double ms = 0.0;
  PlaneError cloud_depth;
  double lwir_kelvin = 0.0;  // mean |brightness temperature - exact|
};
struct LabelResult {
  std::string name;
  std::vector<LabelPoint> points;
};

LabelResult measureLabelKnob(Renderer& renderer, const BenchScene& bench_scene, const Scene& scene,
                             const BandTable& band) {
  LabelResult result{bench_scene.name, {}};
  const FrameRequest request(ChannelSet{Channel::kCloudDepth, Channel::kLwir});
  Frame exact;
  std::vector<float> exact_kelvin;
  for (int divisor : {1, 2, 4, 8}) {
    RenderSettings settings = bench_scene.file.render;
    settings.channel_divisor = divisor;
    const auto start = Clock::now();
    Frame frame = renderer.render(scene, settings, request);
    LabelPoint point;
    point.divisor = divisor;
    point.ms = secondsSince(start) * 1e3;
    std::vector<float> kelvin(frame.lwir.size());
    for (std::size_t i = 0; i < kelvin.size(); ++i)
      kelvin[i] = float(band.temperature(frame.lwir[i]));
    if (divisor == 1) exact = frame, exact_kelvin = kelvin;
    point.cloud_depth = comparePlanes(frame.cloud_depth, exact.cloud_depth);
    point.lwir_kelvin = comparePlanes(kelvin, exact_kelvin).mean_abs;
    result.points.push_back(point);
  }
  return result;
}

void writeLabelMarkdown(std::ofstream& out, const std::vector<LabelResult>& results) {
  if (results.empty()) return;
  out << "### Label channels: channel_divisor\n\n"
      << "Cloud depth and lwir traced once per N x N pixels against N = 1: the share of pixels "
         "whose cloud depth turns finite or infinite, the mean relative cloud-depth error where "
         "both are finite, the mean brightness-temperature error, and the time of both "
         "channels.\n\n"
      << "| scene | N | ms | cloud/clear flipped | cloud depth rel. error | lwir K |\n"
      << "| --- | --- | --- | --- | --- | --- |\n";
  for (const LabelResult& r : results)
    for (const LabelPoint& p : r.points)
      out << "| " << r.name << " | " << p.divisor << " | " << fixed(p.ms, 1) << " | "
          << fixed(100.0 * p.cloud_depth.flipped, 2) << " % | "
          << fixed(p.cloud_depth.mean_relative, 4) << " | " << fixed(p.lwir_kelvin, 3) << " |\n";
  out << "\n";
}

// Error against time, one panel per scene: x the frame time in multiples of the floor (log
// scale), y the colour PSNR; the front joined by a line, the defaults ringed.
void writePlot(const std::filesystem::path& path, const std::vector<SceneResult>& results) {
  const int columns = 4, panel_w = 300, panel_h = 230, margin = 45;
  const int rows = int(results.size() + columns - 1) / columns;
  std::ofstream svg(path);
  svg << "<svg xmlns='http://www.w3.org/2000/svg' width='" << columns * panel_w << "' height='"
      << rows * panel_h + 40 << "' font-family='sans-serif' font-size='11'>\n"
      << "<rect width='100%' height='100%' fill='white'/>\n"
      << "<text x='10' y='20' font-size='14'>Error against run time: colour PSNR (dB, up is "
         "better) against frame time in multiples of the platform floor (log, left is faster). "
         "Blue: Pareto front; red ring: defaults.</text>\n";
  for (std::size_t i = 0; i < results.size(); ++i) {
    const SceneResult& r = results[i];
    const double ox = double(i % columns) * panel_w, oy = 40.0 + double(i / columns) * panel_h;
    double x_lo = 1e30, x_hi = -1e30, y_lo = 1e30, y_hi = -1e30;
    auto psnr = [](const Point& p) { return std::min(p.error.psnr_db, 80.0); };
    for (const Point& p : r.points) {
      x_lo = std::min(x_lo, std::log10(p.floor_multiple));
      x_hi = std::max(x_hi, std::log10(p.floor_multiple));
      y_lo = std::min(y_lo, psnr(p));
      y_hi = std::max(y_hi, psnr(p));
    }
    x_lo -= 0.05, x_hi += 0.05, y_lo = std::floor(y_lo / 5.0) * 5.0,
                                y_hi = std::ceil(y_hi / 5.0) * 5.0 + 1e-9;
    const double w = panel_w - margin - 10, h = panel_h - margin - 25;
    auto px = [&](const Point& p) {
      return ox + margin + (std::log10(p.floor_multiple) - x_lo) / (x_hi - x_lo) * w;
    };
    auto py = [&](const Point& p) { return oy + 20 + (y_hi - psnr(p)) / (y_hi - y_lo) * h; };
    svg << "<text x='" << ox + margin << "' y='" << oy + 12 << "' font-weight='bold'>" << r.name
        << "</text>\n<rect x='" << ox + margin << "' y='" << oy + 20 << "' width='" << w
        << "' height='" << h << "' fill='none' stroke='#888'/>\n";
    svg << "<text x='" << ox + 2 << "' y='" << oy + 28 << "'>" << fixed(y_hi, 0) << " dB</text>\n"
        << "<text x='" << ox + 2 << "' y='" << oy + 20 + h << "'>" << fixed(y_lo, 0)
        << " dB</text>\n<text x='" << ox + margin << "' y='" << oy + 35 + h << "'>"
        << fixed(std::pow(10.0, x_lo), 1) << "x</text>\n<text x='" << ox + margin + w - 30
        << "' y='" << oy + 35 + h << "'>" << fixed(std::pow(10.0, x_hi), 1) << "x</text>\n";
    std::vector<const Point*> front;
    for (const Point& p : r.points)
      if (p.front) front.push_back(&p);
    std::sort(front.begin(), front.end(),
              [](const Point* a, const Point* b) { return a->ms < b->ms; });
    svg << "<polyline fill='none' stroke='#2a6fdb' stroke-width='1.5' points='";
    for (const Point* p : front) svg << px(*p) << ',' << py(*p) << ' ';
    svg << "'/>\n";
    // The front last, so that a point equal to a front point does not hide it.
    std::vector<const Point*> order;
    for (const Point& p : r.points) order.push_back(&p);
    std::stable_partition(order.begin(), order.end(), [](const Point* p) { return !p->front; });
    for (const Point* point : order) {
      const Point& p = *point;
      svg << "<circle cx='" << px(p) << "' cy='" << py(p) << "' r='3' fill='"
          << (p.front ? "#2a6fdb" : "#999") << "'><title>" << p.setting.name() << ": "
          << fixed(p.ms, 2) << " ms, " << fixed(p.error.psnr_db, 1) << " dB</title></circle>\n";
      if (p.setting.knob.empty())
        svg << "<circle cx='" << px(p) << "' cy='" << py(p)
            << "' r='7' fill='none' stroke='#d62728' stroke-width='2'/>\n";
    }
  }
  svg << "</svg>\n";
}

// The sweep's size, timed frames and reference supersampling.
struct BenchRun {
  int width = 640, height = 480;
  int repeats = 7;
  int samples = 4;
};

// --size, --repeats and --samples, with --quick's defaults; an error for a bad size.
std::string readRun(const BenchCommandOptions& o, BenchRun& run) {
  run.width = o.quick ? 200 : 640, run.height = o.quick ? 150 : 480;
  if (!o.size.empty() && (std::sscanf(o.size.c_str(), "%dx%d", &run.width, &run.height) != 2 ||
                          run.width < 1 || run.height < 1 || run.width > 4096 || run.height > 4096))
    return "--size: '" + o.size + "' is not WxH with each side 1 to 4096";
  run.repeats = o.repeats > 0 ? o.repeats : o.quick ? 3 : 7;
  run.samples = o.samples > 0 ? o.samples : o.quick ? 2 : 4;
  return "";
}

// The scenes --scenes names (all when it is empty); an error for an unknown name.
std::string selectScenes(const std::vector<std::string>& names, std::vector<BenchScene>& scenes) {
  for (const std::string& name : names)
    if (std::none_of(scenes.begin(), scenes.end(),
                     [&](const BenchScene& s) { return s.name == name; }))
      return "--scenes: unknown scene '" + name + "' (allowed: " + sceneNames() + ")";
  if (!names.empty())
    std::erase_if(scenes, [&](const BenchScene& s) {
      return std::find(names.begin(), names.end(), s.name) == names.end();
    });
  return "";
}

// What a scene's sweep shares: its renderer, run, reference and progress line.
struct SweepContext {
  Renderer& renderer;
  const BenchRun& run;
  const ReferenceSettings& reference_settings;
  const FloatImage& reference;
  const std::string& tag;
  bool tty;
};

// A point of the reference's own grid: drawn and timed once on the CPU, its error against the
// sweep's reference.
Point measureReferencePoint(const SweepContext& c, const Setting& setting, const Scene& scene) {
  Point point;
  point.setting = setting;
  if (c.tty) std::fprintf(stderr, "\r%s: %s", c.tag.c_str(), setting.name().c_str());
  ReferenceSettings coarse = c.reference_settings;
  coarse.samples_per_axis = setting.reference_samples;
  const auto start = Clock::now();
  const FloatImage image = renderReference(scene, coarse);
  point.ms = 1e3 * secondsSince(start);
  point.error = compareImages(image, c.reference);
  return point;
}

// Point k of the sweep drawn as a running daemon would hold it, and its error; its time is
// left to timePoints.
Point measurePoint(const SweepContext& c, std::size_t k, const Setting& setting, const Scene& scene,
                   const RenderSettings& render) {
  if (setting.reference_samples > 0) return measureReferencePoint(c, setting, scene);
  Point point;
  point.setting = setting;
  // A still view as a running daemon holds it: every clipmap filled (`auto` fills them over
  // the frames after the first) before the image is measured and timed.
  for (int warm = 0; warm < 64; ++warm) {
    c.renderer.renderSrgb8(scene, render);
    if (warm > 0 && c.renderer.lastFrameStats().layer_texels_baked == 0) break;
  }
  if (setting.stream) {
    c.renderer.setContinuousView("sweep " + std::to_string(k));
    Scene approach = scene;
    for (int frame = 16; frame > 0; --frame) {
      approach.camera.position.x = scene.camera.position.x - 250.0 / 30.0 * frame;
      c.renderer.renderSrgb8(approach, render);
    }
  }
  const FloatImage image = c.renderer.renderFloat(scene, render);
  c.renderer.setContinuousView("");
  if (setting.changes_model) {
    if (c.tty)
      std::fprintf(stderr, "\r%s: reference for %s", c.tag.c_str(), setting.name().c_str());
    ReferenceSettings same = c.reference_settings;
    same.sea_waves = render.sea_waves;  // the same sea as the GL draws
    point.error = compareImages(image, renderReference(scene, same));
  } else {
    point.error = compareImages(image, c.reference);
  }
  point.image = image.rgba;
  point.ms = std::numeric_limits<double>::infinity();
  return point;
}

// Two timing rounds over every setting, each setting's time the lower of its two medians, so
// that the machine's drift and the order of the settings do not decide the front.
void timePoints(const SweepContext& c, const std::vector<Setting>& settings,
                const std::vector<Scene>& scenes, const std::vector<RenderSettings>& renders,
                SceneResult& result) {
  for (int round = 1; round <= 2; ++round)
    for (std::size_t k = 0; k < settings.size(); ++k) {
      if (c.tty)
        std::fprintf(stderr, "\r%s: timing round %d, %zu/%zu %-50s", c.tag.c_str(), round, k + 1,
                     settings.size(), settings[k].name().c_str());
      Point& point = result.points[k];
      if (settings[k].reference_samples > 0) {  // timed once as it was drawn
        point.floor_multiple = point.ms / result.floor_ms;
        continue;
      }
      if (settings[k].stream) c.renderer.setContinuousView("sweep " + std::to_string(k));
      point.ms = std::min(point.ms, medianMilliseconds(c.run.repeats, [&] {
                            c.renderer.renderSrgb8(scenes[k], renders[k]);
                          }));
      c.renderer.setContinuousView("");
      point.floor_multiple = point.ms / result.floor_ms;
    }
}

// Every setting of one scene drawn, compared and timed.
void sweepScene(const SweepContext& c, const BenchScene& bench_scene, const Scene& scene,
                SceneResult& result) {
  std::vector<Setting> settings = settingsFor(bench_scene.file);
  // The reference's own grid only below the sweep's: at it, it is the sweep's reference.
  std::erase_if(settings, [&](const Setting& p) { return p.reference_samples >= c.run.samples; });
  std::vector<Scene> edited(settings.size(), scene);
  std::vector<RenderSettings> renders(settings.size(), bench_scene.file.render);
  for (std::size_t k = 0; k < settings.size(); ++k) {
    settings[k].edit(renders[k]);
    if (settings[k].scene_edit) {
      SceneFile file = bench_scene.file;
      settings[k].scene_edit(file);
      edited[k] = sceneAtTime(file);
    }
    Point& point =
        result.points.emplace_back(measurePoint(c, k, settings[k], edited[k], renders[k]));
    if (k > 0) {
      point.same_image = point.image == result.points[0].image;
      point.image.clear();
    }
  }
  timePoints(c, settings, edited, renders, result);
  result.points[0].image.clear();
}

// One scene: its reference, the platform floor, then its sweep; printed as it ends.
SceneResult measureScene(Renderer& renderer, BenchScene& bench_scene, const BenchRun& run,
                         const std::string& tag, Clock::time_point start) {
  const bool tty = isatty(fileno(stderr));  // progress on one rewritten line, else a line each
  bench_scene.file.scene.camera.width = run.width;
  bench_scene.file.scene.camera.height = run.height;
  const Scene scene = sceneAtTime(bench_scene.file);
  SceneResult result;
  result.name = bench_scene.name;
  result.what = bench_scene.what;
  // The scene's own reference settings at the sweep's supersampling, with every lobe of
  // every heap in range, so that the heaps' level of detail is measured, not shared.
  ReferenceSettings reference_settings = bench_scene.file.reference();
  reference_settings.samples_per_axis = run.samples;
  reference_settings.heaps.detail_px = 0.0;
  const auto ref_start = Clock::now();
  const FloatImage reference = renderReference(scene, reference_settings, [&](double fraction) {
    if (tty) std::fprintf(stderr, "\r%s: reference %3.0f %%", tag.c_str(), 100.0 * fraction);
  });
  result.reference_s = secondsSince(ref_start);
  std::fprintf(stderr, "%s%s: reference in %.2f s\n", tty ? "\r" : "", tag.c_str(),
               result.reference_s);
  result.floor_ms =
      medianMilliseconds(run.repeats, [&] { renderer.renderFloor(run.width, run.height); });
  sweepScene({renderer, run, reference_settings, reference, tag, tty}, bench_scene, scene, result);
  std::fprintf(stderr, "%s%s: %zu settings, %.0f s since the start%40s\n", tty ? "\r" : "",
               tag.c_str(), result.points.size(), secondsSince(start), "");
  markFront(result.points);
  result.default_status = defaultStatus(result.points);
  printScene(result, run.width, run.height, run.samples);
  return result;
}

// The label knob, on every scene with clouds (after the sweep: its tracing would disturb no
// timing there).
std::vector<LabelResult> measureLabels(Renderer& renderer, const std::vector<BenchScene>& scenes) {
  std::vector<LabelResult> labels;
  const BandTable band{InfraredModel{}};
  for (const BenchScene& bench_scene : scenes) {
    const Scene scene = sceneAtTime(bench_scene.file);
    if (scene.layers.empty() && scene.clouds.empty() && scene.fields.empty() &&
        scene.automata.empty())
      continue;
    labels.push_back(measureLabelKnob(renderer, bench_scene, scene, band));
    std::fprintf(stderr, "%s: label channels\n", bench_scene.name.c_str());
    for (const LabelPoint& p : labels.back().points)
      std::printf(
          "  channel_divisor=%d: %.1f ms, %.2f %% cloud/clear flipped, cloud depth %.4f "
          "relative, lwir %.3f K\n",
          p.divisor, p.ms, 100.0 * p.cloud_depth.flipped, p.cloud_depth.mean_relative,
          p.lwir_kelvin);
  }
  return labels;
}

// accuracy.csv, .md (with the label channels) and .svg in `dir`.
void writeReports(const std::filesystem::path& dir, const std::vector<SceneResult>& results,
                  const std::vector<LabelResult>& labels, const std::string& header) {
  writeCsv(dir / "accuracy.csv", results);
  writeMarkdown(dir / "accuracy.md", results, header);
  {
    std::ofstream out(dir / "accuracy.md", std::ios::app);
    writeLabelMarkdown(out, labels);
  }
  writePlot(dir / "accuracy.svg", results);
}

}  // namespace

void addBenchCommand(CLI::App& app, BenchCommandOptions& o) {
  CLI::App* cmd = app.add_subcommand(
      "bench", "Sweep every quality knob: error against the CPU reference and frame time");
  cmd->add_flag("--quick", o.quick, "Small images and few repeats (under two minutes)");
  cmd->add_option("--size", o.size, "Image size WxH (default 640x480; --quick 200x150)");
  cmd->add_option("--repeats", o.repeats, "Timed frames per setting (default 7; --quick 3)")
      ->check(CLI::Range(1, 1000));
  cmd->add_option("--samples", o.samples,
                  "Reference supersampling per pixel axis (default 4; --quick 2)")
      ->check(CLI::Range(1, 16));
  cmd->add_option("--scenes", o.scenes, "Only these scenes: " + sceneNames())->delimiter(',');
  cmd->add_option("-o,--output", o.output_dir, "Directory for accuracy.csv, .md and .svg")
      ->capture_default_str();
  cmd->add_option("--gl", o.gl_backend, "OpenGL back end")
      ->check(CLI::IsMember(kGlBackendNames))
      ->capture_default_str();
}

int runBenchCommand(const BenchCommandOptions& o) {
  BenchRun run;
  std::vector<BenchScene> scenes;
  if (std::string error = readRun(o, run); !error.empty()) {
    spdlog::error("{}", error);
    return 2;
  }
  if (std::string error = loadScenes(scenes); !error.empty()) {
    spdlog::error("{}", error);
    return 1;
  }
  if (std::string error = selectScenes(o.scenes, scenes); !error.empty()) {
    spdlog::error("{}", error);
    return 2;
  }
  std::string error;
  RendererOptions options;
  options.gl_backend = backendFromName(o.gl_backend);
  const std::unique_ptr<Renderer> gl = createRenderer(options, error);
  if (!gl) {
    spdlog::error("{}", error);
    return 1;
  }
  Renderer& renderer = *gl;
  const RendererPlatform platform = renderer.platform();
  const std::string header =
      "Measured by `nephele bench" + std::string(o.quick ? " --quick" : "") + "` at " +
      std::to_string(run.width) + "x" + std::to_string(run.height) + ", median of " +
      std::to_string(run.repeats) + " frames (render + readback into an 8-bit target), " +
      platform.device + " (" + platform.backend + "); error against the CPU reference at " +
      std::to_string(run.samples) + "x" + std::to_string(run.samples) + " samples per pixel.";
  std::printf("%s\n", header.c_str());

  const auto start = Clock::now();
  std::vector<SceneResult> results;
  for (std::size_t index = 0; index < scenes.size(); ++index) {
    const std::string tag = "[" + std::to_string(index + 1) + "/" + std::to_string(scenes.size()) +
                            "] " + scenes[index].name;
    results.push_back(measureScene(renderer, scenes[index], run, tag, start));
  }
  const std::filesystem::path dir(o.output_dir);
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    spdlog::error("{}: {}", o.output_dir, ec.message());
    return 1;
  }
  writeReports(dir, results, measureLabels(renderer, scenes), header);
  std::printf("\nwrote %s, %s and %s in %.0f s\n", (dir / "accuracy.csv").c_str(),
              (dir / "accuracy.md").c_str(), (dir / "accuracy.svg").c_str(), secondsSince(start));
  return 0;
}

}  // namespace nephele
