#include "config/scene_file.h"

#include <toml++/toml.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <variant>
#include <vector>

#include "config/obj_mesh.h"
#include "config/table_reader.h"
#include "world/counter_random.h"
#include "world/formations/cluster.h"
#include "world/formations/weather.h"

namespace nephele {
void config_detail::readCameraKeys(TableReader& t, Camera& camera) {
  t.vector("position", camera.position, -Limits::kMaxCoordinate, Limits::kMaxCoordinate);
  if (camera.position.z < 0.0)
    t.failAt("position",
             "z = " + formatNumber(camera.position.z) + " is below the ground (allowed: z >= 0)");
  t.number("heading", camera.orientation.heading_deg, -Limits::kMaxHeading, Limits::kMaxHeading);
  t.number("pitch", camera.orientation.pitch_deg, -Limits::kMaxPitch, Limits::kMaxPitch);
  t.number("roll", camera.orientation.roll_deg, -Limits::kMaxRoll, Limits::kMaxRoll);
  t.number("vfov", camera.vfov_deg, Limits::kMinVfov, Limits::kMaxVfov);
}

namespace {

using config_detail::joinKeys;
using config_detail::SceneError;
using config_detail::TableReader;

void readImage(TableReader& t, Camera& camera) {
  t.allow({"width", "height"});
  t.integer("width", camera.width, 1, Limits::kMaxImageSide);
  t.integer("height", camera.height, 1, Limits::kMaxImageSide);
  t.finish();
}

void readCamera(TableReader& t, Camera& camera) {
  t.allow({"position", "heading", "pitch", "roll", "vfov"});
  config_detail::readCameraKeys(t, camera);
  t.finish();
}

void readSun(TableReader& t, Sun& sun) {
  t.allow({"azimuth", "elevation", "colour"});
  t.number("azimuth", sun.azimuth_deg, -Limits::kMaxHeading, Limits::kMaxHeading);
  t.number("elevation", sun.elevation_deg, -Limits::kMaxPitch, Limits::kMaxPitch);
  t.vector("colour", sun.colour, Limits::kColour);
  t.finish();
}

void readSky(TableReader& t, Sky& sky) {
  t.allow({"model", "zenith", "horizon", "ground"});
  t.choice("model", {"gradient"}, 0);
  t.vector("zenith", sky.zenith, Limits::kColour);
  t.vector("horizon", sky.horizon, Limits::kColour);
  t.vector("ground", sky.ground, Limits::kColour);
  t.finish();
}

void readHaze(TableReader& t, Haze& haze) {
  t.allow({"visibility", "scale_height"});
  t.number("visibility", haze.visibility_m, Limits::kHazeVisibility);
  t.number("scale_height", haze.scale_height_m, Limits::kHazeScaleHeight);
  t.finish();
}

void readFog(TableReader& t, Fog& fog) {
  t.allow({"top", "visibility", "colour"});
  t.number("top", fog.top_m, 0.0, Limits::kMaxAltitude);
  t.number("visibility", fog.visibility_m, Limits::kFogVisibility);
  t.vector("colour", fog.colour, Limits::kColour);
  t.finish();
}

// A [[sea.wave]] table: one of a host's wave trains (CIGI 3.3 Wave Control) over the sea.
void readWave(TableReader& t, WaveTrain& wave) {
  t.allow({"id", "height", "wavelength", "period", "direction", "phase"});
  if (!t.has("id"))
    t.failHere("missing key id (0 to " + std::to_string(Limits::kMaxWaveId) +
               ", one train per id)");
  t.integer("id", wave.id, 0, Limits::kMaxWaveId);
  t.number("height", wave.height_m, Limits::kWaveHeight);
  t.number("wavelength", wave.wavelength_m, Limits::kWavelength);
  t.number("period", wave.period_s, Limits::kWavePeriod);
  t.number("direction", wave.direction_deg, Limits::kWaveDirection);
  t.number("phase", wave.phase_deg, Limits::kWavePhase);
  t.finish();
}

// The sea in place of the ground plane (MODEL.md section 18). Its wind is the surface wind:
// `surface_wind` (the [[wind]] at altitude 0) unless the table gives one.
void readSea(TableReader& t, std::optional<glm::dvec2> surface_wind, Sea& sea) {
  t.allow({"wind", "fetch", "temperature", "clarity", "whitecaps", "seed", "wave"});
  if (surface_wind) sea.wind = *surface_wind;
  t.vector("wind", sea.wind, -Limits::kMaxWind, Limits::kMaxWind);
  if (t.has("wind") && glm::length(sea.wind) > Limits::kMaxWind)
    t.failAt("wind", formatNumber(glm::length(sea.wind)) +
                         " m/s is out of range (allowed: a speed of at most " +
                         formatNumber(Limits::kMaxWind) + " m/s)");
  t.number("fetch", sea.fetch_m, Limits::kSeaFetch);
  t.number("temperature", sea.temperature_c, Limits::kSeaTemperature);
  t.number("clarity", sea.clarity, Limits::kSeaClarity);
  t.boolean("whitecaps", sea.whitecaps);
  t.seed("seed", sea.seed);
  std::vector<TableReader> waves = t.tables("wave");
  if (waves.size() > std::size_t(kMaxWaveTrains))
    t.failAt("wave", std::to_string(waves.size()) + " wave trains (allowed: at most " +
                         std::to_string(kMaxWaveTrains) + ")");
  for (TableReader& w : waves) {
    WaveTrain wave;
    readWave(w, wave);
    for (const WaveTrain& other : sea.trains)
      if (other.id == wave.id)
        w.failAt("id", std::to_string(wave.id) + " is given twice (allowed: one train per id)");
    sea.trains.push_back(wave);
  }
  std::sort(sea.trains.begin(), sea.trains.end(),
            [](const WaveTrain& a, const WaveTrain& b) { return a.id < b.id; });
  if (std::string e = seaError(sea); !e.empty()) t.failHere(e);  // a backstop: not reached
  t.finish();
}

// One knob's key, typed by its row and checked by its one check (renderer/render_knobs.h).
void readKnob(TableReader& t, const RenderKnob& knob, RenderSettings& settings) {
  double value = knob.get(settings);
  if (knob.type == KnobType::kChoice) {
    value = t.choice(knob.name, knob.values.names, int(value));
  } else if (knob.type == KnobType::kBoolean) {
    bool on = value != 0.0;
    t.boolean(knob.name, on);
    value = on;
  } else if (const auto number =
                 t.numberToCheck(knob.name, knob.type == KnobType::kInteger, knob.allowed())) {
    value = *number;
  }
  if (std::string error = knobError(knob, value); !error.empty())
    t.failAt(knob.name, error.substr(knob.name.size() + 2));
  knob.set(settings, value);
}

void readRender(TableReader& t, SceneFile& out) {
  std::vector<std::string> keys;
  for (const RenderKnob& knob : renderKnobs()) keys.emplace_back(knob.name);
  t.allow(keys);
  for (const RenderKnob& knob : renderKnobs()) readKnob(t, knob, out.render);
  t.finish();
}

// Gardner's texture keys, shared by layer and solid textures; base frequencies from
// `min_frequency` to 10 radians per metre.
void readGardnerParams(TableReader& t, GardnerTextureParams& g, double min_frequency) {
  t.integer("terms", g.terms, 1, GardnerTextureParams::kMaxTerms);
  t.number("fx1", g.fx1, min_frequency, 10.0);
  t.number("fy1", g.fy1, min_frequency, 10.0);
  t.number("t0", g.t0, Limits::kContrastOffset);
  t.boolean("phases", g.seeded_phases);
  t.number("amplitude_ratio", g.amplitude_ratio, Limits::kAmplitudeRatio);
}

void readTexture(TableReader& t, LayerTextureSpec& texture) {
  t.allow({"source", "terms", "fx1", "fy1", "t0", "phases", "amplitude_ratio", "rotation", "jitter",
           "tile_size", "size_log2", "roughness", "cells", "octaves", "persistence"});
  texture.source = TextureSource(
      t.choice("source", {"gardner", "perlin", "diamond-square"}, int(texture.source)));
  const std::string source(textureSourceName(texture.source));
  const bool gardner = texture.source == TextureSource::kGardner;
  const bool perlin = texture.source == TextureSource::kPerlin;
  for (const char* key :
       {"terms", "fx1", "fy1", "t0", "phases", "amplitude_ratio", "rotation", "jitter"})
    if (!gardner) t.forbid(key, "applies to source \"gardner\" only, not \"" + source + "\"");
  for (const char* key : {"tile_size", "size_log2"})
    if (gardner) t.forbid(key, "applies to sources \"perlin\" and \"diamond-square\" only");
  for (const char* key : {"cells", "octaves", "persistence"})
    if (!perlin) t.forbid(key, "applies to source \"perlin\" only, not \"" + source + "\"");
  if (texture.source != TextureSource::kDiamondSquare)
    t.forbid("roughness", "applies to source \"diamond-square\" only, not \"" + source + "\"");

  readGardnerParams(t, texture.gardner, 1.0e-7);
  t.number("rotation", texture.gardner.rotation_deg, Limits::kTermRotation);
  t.number("jitter", texture.gardner.jitter_octaves, Limits::kTermJitter);
  NoiseTableParams& n = texture.table;
  t.vector("tile_size", n.tile_size_m, 1.0, 1.0e7);
  t.integer("size_log2", n.size_log2, 4, 12);
  t.number("roughness", n.roughness, 0.0, 4.0);
  t.integer("cells", n.cells, 1, 64);
  t.integer("octaves", n.octaves, 1, 12);
  t.number("persistence", n.persistence, 0.0, 1.0);
  t.finish();
}

// A [*.develop] table: `times` and, for each key in `keys`, one value per time.
void readDevelop(TableReader& t, const std::vector<std::pair<std::string, Schedule*>>& keys,
                 double lo, double hi) {
  constexpr std::size_t kMaxKeyframes = 1024;
  std::vector<std::string> allowed{"times"};
  for (const auto& [key, schedule] : keys) allowed.push_back(key);
  t.allow(allowed);
  if (!t.has("times")) t.failHere("missing key times (seconds of simulation time, increasing)");
  std::vector<double> times;
  t.numbers("times", times, 0.0, Limits::kMaxTime, kMaxKeyframes);
  for (std::size_t i = 1; i < times.size(); ++i)
    if (!(times[i] > times[i - 1])) t.failAt("times", "must increase strictly");
  for (const auto& [key, schedule] : keys) {
    if (!t.has(key)) continue;
    schedule->times_s = times;
    t.numbers(key, schedule->values, lo, hi, kMaxKeyframes);
    if (schedule->values.size() != times.size())
      t.failAt(key, "has " + std::to_string(schedule->values.size()) + " values for " +
                        std::to_string(times.size()) + " times (one per time)");
  }
  t.finish();
}

void readWind(TableReader& t, WindSample& sample) {
  t.allow({"altitude", "velocity"});
  if (!t.has("velocity")) t.failHere("missing key velocity ([east, north] in m/s)");
  t.number("altitude", sample.altitude_m, 0.0, Limits::kMaxAltitude);
  t.vector("velocity", sample.velocity, -Limits::kMaxWind, Limits::kMaxWind);
  t.finish();
}

// Gardner eq. 8's a, t, s and e, as layers and clouds spell them.
void readShading(TableReader& t, ShadingParams& shading) {
  t.number("ambient", shading.ambient, Limits::kFraction);
  t.number("texture_fraction", shading.texture_fraction, Limits::kFraction);
  t.number("specular", shading.specular, Limits::kFraction);
  t.number("shininess", shading.shininess, Limits::kShininess);
}

void readLayer(TableReader& t, CloudLayer& layer, LayerDevelopment& develop) {
  t.allow({"name", "altitude", "colour", "threshold", "transition", "ambient", "texture_fraction",
           "specular", "shininess", "drift", "seed", "texture", "develop"});
  t.name("name", layer.name);
  t.number("altitude", layer.altitude_m, 0.0, Limits::kMaxAltitude);
  t.vector("colour", layer.colour, Limits::kColour);
  t.number("threshold", layer.threshold, Limits::kLayerThreshold);
  t.number("transition", layer.transition, Limits::kTransition);
  readShading(t, layer.shading);
  t.vector("drift", layer.texture.drift_velocity, -Limits::kMaxDrift, Limits::kMaxDrift);
  t.seed("seed", layer.texture.seed);
  if (auto texture = t.table("texture")) readTexture(*texture, layer.texture);
  if (auto d = t.table("develop")) {
    readDevelop(*d,
                {{"threshold", &develop.threshold},
                 {"transition", &develop.transition},
                 {"t0", &develop.t0}},
                0.0, 10.0);
    if (!develop.t0.empty() && layer.texture.source != TextureSource::kGardner)
      d->failAt("t0", "applies to texture source \"gardner\" only");
    if (!develop.threshold.empty() &&
        std::ranges::any_of(develop.threshold.values, [](double v) { return v > 1.0; }))
      d->failAt("threshold", "values must lie in 0 to 1");
  }
  t.finish();
}

void readSolidTexture(TableReader& t, SolidTextureSpec& texture) {
  t.allow({"source", "terms", "fx1", "fy1", "t0", "phases", "amplitude_ratio", "period",
           "size_log2", "cells", "octaves", "persistence"});
  texture.source =
      SolidTextureSource(t.choice("source", {"gardner", "perlin"}, int(texture.source)));
  const bool gardner = texture.source == SolidTextureSource::kGardner;
  for (const char* key : {"terms", "fx1", "fy1", "t0", "phases", "amplitude_ratio", "rotation"})
    if (!gardner) t.forbid(key, "applies to source \"gardner\" only, not \"perlin\"");
  for (const char* key : {"period", "size_log2", "cells", "octaves", "persistence"})
    if (gardner) t.forbid(key, "applies to source \"perlin\" only, not \"gardner\"");
  readGardnerParams(t, texture.gardner, 1.0e-6);
  t.number("period", texture.perlin_period_m, 1.0, 1.0e6);
  t.integer("size_log2", texture.perlin_size_log2, 3, 8);
  t.integer("cells", texture.perlin_cells, 1, 32);
  t.integer("octaves", texture.perlin_octaves, 1, 8);
  t.number("persistence", texture.perlin_persistence, 0.0, 1.0);
  t.finish();
}

void readOrientation(TableReader& t, Orientation& o) {
  t.number("heading", o.heading_deg, -Limits::kMaxHeading, Limits::kMaxHeading);
  t.number("pitch", o.pitch_deg, -Limits::kMaxPitch, Limits::kMaxPitch);
  t.number("roll", o.roll_deg, -Limits::kMaxRoll, Limits::kMaxRoll);
}

void readEllipsoid(TableReader& t, Ellipsoid& e) {
  t.allow({"radii", "centre", "heading", "pitch", "roll"});
  if (!t.has("radii")) t.failHere("missing key radii (three semi-axes in metres)");
  t.vector("radii", e.radii, Limits::kMinRadius, Limits::kMaxRadius);
  t.vector("centre", e.centre, -Limits::kMaxCoordinate, Limits::kMaxCoordinate);
  readOrientation(t, e.orientation);
  t.finish();
}

void readCumulus(TableReader& t, std::uint64_t seed, std::vector<Ellipsoid>& out) {
  t.allow({"count", "base", "width", "seed"});
  int count = 27;
  glm::dvec3 base{0.0, 0.0, 1000.0};
  double width = 1500.0;
  t.integer("count", count, 1, Limits::kMaxEllipsoidsPerCloud);
  t.vector("base", base, -Limits::kMaxCoordinate, Limits::kMaxCoordinate);
  t.number("width", width, 1.0, 1.0e5);
  t.seed("seed", seed);
  t.finish();
  out = cumulusEllipsoids(count, base, width, seed);
}

// Gardner's cluster (world/formations/cluster.h); [[cloud.cluster.terrain]] ellipsoids raise
// it and are not drawn.
void readCluster(TableReader& t, std::uint64_t seed, std::vector<Ellipsoid>& out) {
  t.allow({"radii", "heading", "pitch", "roll", "centre", "boundary", "boundary_heading", "spacing",
           "altitude", "size_variation", "position_variation", "heading_variation",
           "vertical_scale", "seed", "terrain"});
  ClusterSpec c;
  c.seed = seed;
  if (!t.has("radii")) t.failHere("missing key radii (the template ellipsoid's semi-axes)");
  t.vector("radii", c.element.radii, Limits::kMinRadius, Limits::kMaxRadius);
  readOrientation(t, c.element.orientation);
  t.vector("centre", c.centre, -Limits::kMaxCoordinate, Limits::kMaxCoordinate);
  t.vector("boundary", c.boundary_radii, Limits::kClusterBoundary);
  t.number("boundary_heading", c.boundary_heading_deg, -Limits::kMaxHeading, Limits::kMaxHeading);
  t.vector("spacing", c.spacing, Limits::kClusterSpacing);
  t.number("altitude", c.altitude_m, 0.0, Limits::kMaxAltitude);
  t.number("size_variation", c.size_variation, Limits::kSizeVariation);
  t.number("position_variation", c.position_variation, Limits::kPositionVariation);
  t.number("heading_variation", c.heading_variation_deg, Limits::kHeadingVariation);
  t.number("vertical_scale", c.vertical_scale, Limits::kVerticalScale);
  t.seed("seed", c.seed);
  std::vector<TableReader> terrain_tables = t.tables("terrain");
  if (terrain_tables.size() > std::size_t(Limits::kMaxEllipsoidsPerCloud))
    t.failAt("terrain",
             "more than " + std::to_string(Limits::kMaxEllipsoidsPerCloud) + " terrain ellipsoids");
  std::vector<Ellipsoid> terrain;
  for (TableReader& e : terrain_tables) readEllipsoid(e, terrain.emplace_back());
  if (std::string e = clusterError(c); !e.empty()) t.failHere(e);
  t.finish();
  out = clusterEllipsoids(c, terrain);
  if (out.empty())
    t.failHere(
        "has no ellipsoids inside its boundary (allowed: a boundary wider "
        "than the spacing)");
}

void readCloud(TableReader& t, std::uint64_t seed, EllipsoidCloud& cloud,
               CloudDevelopment& develop) {
  t.allow({"name", "colour", "threshold", "limb_threshold", "transition", "ambient",
           "texture_fraction", "specular", "shininess", "light_extinction", "seed", "texture",
           "cumulus", "cluster", "ellipsoid", "develop"});
  t.name("name", cloud.name);
  t.vector("colour", cloud.colour, Limits::kColour);
  t.number("threshold", cloud.threshold_centre, Limits::kCloudThreshold);
  t.number("limb_threshold", cloud.threshold_limb, Limits::kCloudThreshold);
  t.number("transition", cloud.transition, Limits::kTransition);
  readShading(t, cloud.shading);
  t.number("light_extinction", cloud.light_extinction, Limits::kLightExtinction);
  cloud.texture.seed = seed;
  t.seed("seed", cloud.texture.seed);
  if (auto texture = t.table("texture")) readSolidTexture(*texture, cloud.texture);
  if (auto cumulus = t.table("cumulus"))
    readCumulus(*cumulus, cloud.texture.seed, cloud.ellipsoids);
  if (auto cluster = t.table("cluster")) {
    if (!cloud.ellipsoids.empty())
      cluster->failHere("a cloud takes [cumulus] or [cluster], not both");
    readCluster(*cluster, cloud.texture.seed, cloud.ellipsoids);
  }
  std::vector<TableReader> ellipsoids = t.tables("ellipsoid");
  if (cloud.ellipsoids.size() + ellipsoids.size() > std::size_t(Limits::kMaxEllipsoidsPerCloud))
    t.failAt("ellipsoid", "more than " + std::to_string(Limits::kMaxEllipsoidsPerCloud) +
                              " ellipsoids in one cloud");
  for (TableReader& e : ellipsoids) readEllipsoid(e, cloud.ellipsoids.emplace_back());
  if (cloud.ellipsoids.empty())
    t.failHere(
        "has no ellipsoids (add [[cloud.ellipsoid]] tables, a [cloud.cumulus] or a [cloud.cluster] "
        "table)");
  if (auto d = t.table("develop"))
    readDevelop(*d,
                {{"threshold", &develop.threshold_centre},
                 {"limb_threshold", &develop.threshold_limb},
                 {"transition", &develop.transition}},
                -2.0, 10.0);
  t.finish();
}

void readShape(TableReader& t, ShapeEllipsoid& shape) {
  t.allow({"centre", "radii"});
  t.vector("centre", shape.centre, -10.0, 10.0);
  t.vector("radii", shape.radii, 1e-3, 10.0);
  t.finish();
}

void readAutomaton(TableReader& t, std::uint64_t seed, AutomatonCloudSpec& a) {
  t.allow({"name", "cells", "cell_size", "position", "seed", "step_interval", "warmup_steps",
           "humidity", "activation", "extinction", "colour", "ambient", "phase", "phase_u",
           "samples_per_cell", "shape", "develop"});
  t.name("name", a.name);
  int cells[3] = {a.cells.nx, a.cells.ny, a.cells.nz};
  t.integers3("cells", cells, 1, Limits::kMaxCellsPerAxis);
  a.cells = {cells[0], cells[1], cells[2]};
  if (a.cells.cells() > Limits::kMaxCells)
    t.failAt("cells", std::to_string(a.cells.cells()) + " cells (allowed: at most " +
                          std::to_string(Limits::kMaxCells) + ")");
  t.number("cell_size", a.cell_size_m, Limits::kCellSize);
  t.vector("position", a.position, -Limits::kMaxCoordinate, Limits::kMaxCoordinate);
  a.seed = seed;
  t.seed("seed", a.seed);
  t.number("step_interval", a.step_interval_s, Limits::kStepInterval);
  t.integer("warmup_steps", a.warmup_steps, 0, Limits::kMaxWarmupSteps);
  t.number("humidity", a.humidity, Limits::kFraction);
  t.number("activation", a.activation, Limits::kFraction);
  t.number("extinction", a.extinction, Limits::kFraction);
  t.vector("colour", a.colour, Limits::kColour);
  t.number("ambient", a.ambient, Limits::kFraction);
  a.phase = PhaseFunction(t.choice("phase", kPhaseFunctionNames, int(a.phase)));
  if (a.phase != PhaseFunction::kCornetteShanks)
    t.forbid("phase_u", "applies to phase \"cornette-shanks\" only");
  t.number("phase_u", a.phase_u, 0.0, 1.0);
  t.integer("samples_per_cell", a.samples_per_cell, 1, Limits::kMaxSamplesPerCell);
  for (TableReader& s : t.tables("shape")) readShape(s, a.shape.emplace_back());
  if (auto d = t.table("develop"))
    readDevelop(*d,
                {{"humidity", &a.humidity_schedule},
                 {"activation", &a.activation_schedule},
                 {"extinction", &a.extinction_schedule}},
                0.0, 1.0);
  t.finish();
}

}  // namespace

void readTarget(TableReader& t, const std::string& scene_path, Target& target,
                std::vector<std::string> extra_keys) {
  std::vector<std::string> keys{"name", "shape", "centre", "heading", "pitch",
                                "roll", "size",  "colour", "mesh"};
  keys.insert(keys.end(), extra_keys.begin(), extra_keys.end());
  t.allow(keys);
  t.name("name", target.name);
  target.shape = TargetShape(t.choice("shape", {"box", "ellipsoid", "mesh"}, int(target.shape)));
  t.vector("centre", target.centre, -Limits::kMaxCoordinate, Limits::kMaxCoordinate);
  readOrientation(t, target.orientation);
  if (target.shape == TargetShape::kMesh) target.size = glm::dvec3(1.0);
  t.vector("size", target.size, Limits::kMinRadius, Limits::kMaxRadius);
  t.vector("colour", target.colour, Limits::kColour);
  std::string mesh_path;
  t.string("mesh", mesh_path);
  if (target.shape == TargetShape::kMesh) {
    if (mesh_path.empty()) t.failAt("shape", "shape \"mesh\" needs a mesh = \"file.obj\" key");
    // Relative paths are relative to the scene file.
    const std::filesystem::path resolved =
        std::filesystem::path(mesh_path).is_absolute()
            ? std::filesystem::path(mesh_path)
            : std::filesystem::path(scene_path).parent_path() / mesh_path;
    auto mesh = std::make_shared<TriangleMesh>();
    if (std::string error = loadObjMesh(resolved.string(), *mesh); !error.empty())
      t.failAt("mesh", error);
    target.mesh = std::move(mesh);
  } else if (!mesh_path.empty()) {
    t.failAt("mesh", "applies to shape \"mesh\" only");
  }
  if (extra_keys.empty()) t.finish();
}

namespace {

// The rules between a weather layer's keys are the world's, shared with set_weather; the
// error points at the key it names.
void checkWeather(TableReader& t, const WeatherLayer& w) {
  if (std::string e = weatherLayerError(w); !e.empty()) {
    const std::string key = e.substr(0, e.find(':'));
    if (t.has(key) && e.size() > key.size() + 2) t.failAt(key, e.substr(key.size() + 2));
    t.failHere(e);
  }
}

// The keys a [[macrocluster]] adds to a weather layer (MODEL.md section 11): the region it
// fills, its cluster grid and variation, and a front's side.
void readMacrocluster(TableReader& t, WeatherLayer& w) {
  Region& r = w.region;
  if (!t.has("size"))
    t.failHere("size is missing ([across, along] metres, each " +
               formatNumber(Limits::kRegionSize.lo) + " to " +
               formatNumber(Limits::kRegionSize.hi) + ")");
  t.vector("centre", r.centre, -Limits::kMaxCoordinate, Limits::kMaxCoordinate);
  glm::dvec2 size(0.0);
  t.vector("size", size, Limits::kRegionSize);
  r.half_size = 0.5 * size;
  t.number("heading", r.heading_deg, -Limits::kMaxHeading, Limits::kMaxHeading);
  t.number("edge", r.edge_m, Limits::kRegionBand);
  r.side = std::array{0, -1, 1}[std::size_t(t.choice("front", {"none", "left", "right"}, 0))];
  t.number("transition", r.transition_m, Limits::kRegionBand);
  t.number("spacing", w.clusters.spacing_m, Limits::kClusterSpacing);
  t.number("variation", w.clusters.amount, Limits::kClusterVariation);
  checkWeather(t, w);
}

// A [[weather]] layer as a host sends it (MODEL.md section 10): the same mapping as set_weather.
// A [[macrocluster]] is a weather layer filling a region (`macro`).
WeatherLayer readWeather(TableReader& t, bool macro = false) {
  t.allow(macro ? std::vector<std::string>{"type", "base", "thickness", "coverage", "seed",
                                           "centre", "size", "heading", "edge", "front",
                                           "transition", "spacing", "variation"}
                : std::vector<std::string>{"type", "base", "thickness", "coverage", "visibility",
                                           "transition_band", "scud", "precipitation",
                                           "precipitation_rate", "precipitation_visibility"});
  std::vector<std::string> names;
  for (int i = 0; i < kCloudTypeCount; ++i) names.emplace_back(cloudTypeName(CloudType(i)));
  WeatherLayer w;
  w.type = CloudType(t.choice("type", names, int(CloudType::kStratus)));
  t.number("base", w.base_m, 0.0, Limits::kMaxBase);
  t.number("thickness", w.thickness_m, Limits::kThickness);
  double percent = 100.0 * w.coverage;
  t.number("coverage", percent, Limits::kCoveragePercent);
  w.coverage = percent / 100.0;
  if (!macro) {  // inside the layer (MODEL.md section 5); 0 takes the genus's visibility
    t.number("visibility", w.visibility_m, 0.0, Limits::kLayerVisibility.hi);
    t.number("transition_band", w.transition_band_m, Limits::kTransitionBand);
    double scud = 100.0 * w.scud;
    t.number("scud", scud, Limits::kCoveragePercent);
    w.scud = scud / 100.0;
    // Rain and the rest (MODEL.md section 17): from the base down, or base to top for "none".
    Precipitation& p = w.precipitation;
    p.kind = PrecipitationKind(
        t.choice("precipitation", {kPrecipitationNames.begin(), kPrecipitationNames.end()}, 0));
    t.number("precipitation_rate", p.rate_mm_h, Limits::kPrecipitationRate);
    t.number("precipitation_visibility", p.visibility_m, 0.0, Limits::kPrecipitationVisibility.hi);
    checkWeather(t, w);
  }
  if (macro) readMacrocluster(t, w);
  t.finish();
  return w;
}

// The [[wind]] samples, by altitude; true when there are any.
bool readWinds(TableReader& t, WindProfile& wind) {
  std::vector<TableReader> tables = t.tables("wind");
  for (TableReader& w : tables) readWind(w, wind.samples.emplace_back());
  std::sort(wind.samples.begin(), wind.samples.end(),
            [](const WindSample& a, const WindSample& b) { return a.altitude_m < b.altitude_m; });
  for (std::size_t i = 1; i < wind.samples.size(); ++i)
    if (wind.samples[i].altitude_m == wind.samples[i - 1].altitude_m)
      t.failAt("wind",
               "two [[wind]] samples at altitude " + formatNumber(wind.samples[i].altitude_m));
  return !tables.empty();
}

// The [[automaton]] clouds, and the work the scene's start time asks of them.
void readAutomata(TableReader& t, const Scene& scene, std::vector<AutomatonCloudSpec>& out) {
  std::vector<TableReader> automata = t.tables("automaton");
  if (automata.size() > std::size_t(Limits::kMaxAutomata))
    t.failAt("automaton",
             "more than " + std::to_string(Limits::kMaxAutomata) + " automaton clouds");
  for (std::size_t i = 0; i < automata.size(); ++i) {
    AutomatonCloudSpec& a = out.emplace_back();
    readAutomaton(automata[i], hashCounters(scene.seed, 0x4175746f6dull, i), a);
    if (a.name.empty()) a.name = "automaton" + std::to_string(i);
  }
  if (!automata.empty() && scene.time_s > Limits::kMaxAutomatonTime)
    t.failAt("time", formatNumber(scene.time_s) + " is out of range with automaton clouds " +
                         "(allowed: 0 to " + formatNumber(Limits::kMaxAutomatonTime) +
                         " s; every automaton step is simulated)");
  if (std::string e = automatonWorkError(out, scene.time_s); !e.empty())
    t.failAt(t.has("time") ? "time" : "automaton", e);
}

void readScene(const toml::table& root, const std::string& file, SceneFile& out) {
  TableReader t(root, "", file);
  t.allow({"seed", "time", "image", "camera", "sun", "sky", "fog", "haze", "sea", "render", "wind",
           "layer", "cloud", "automaton", "target", "weather", "macrocluster"});
  Scene& scene = out.scene;
  t.seed("seed", scene.seed);
  t.number("time", scene.time_s, 0.0, Limits::kMaxTime);
  if (auto image = t.table("image")) readImage(*image, scene.camera);
  if (auto camera = t.table("camera")) readCamera(*camera, scene.camera);
  if (auto sun = t.table("sun")) readSun(*sun, scene.sun);
  if (auto sky = t.table("sky")) readSky(*sky, scene.sky);
  if (auto fog = t.table("fog")) readFog(*fog, scene.fog.emplace());
  if (auto haze = t.table("haze")) readHaze(*haze, scene.haze.emplace());
  if (auto render = t.table("render")) readRender(*render, out);
  WorldDynamics& dynamics = out.dynamics;
  const bool wind = readWinds(t, dynamics.wind);
  if (auto sea = t.table("sea"))
    readSea(*sea, dynamics.wind.empty() ? std::nullopt : std::optional(dynamics.wind.at(0.0)),
            scene.sea.emplace());
  std::vector<TableReader> layers = t.tables("layer");
  for (std::size_t i = 0; i < layers.size(); ++i) {
    CloudLayer& layer = scene.layers.emplace_back();
    layer.texture.seed = hashCounters(scene.seed, 0x4c61796572ull, i);  // unless given
    if (wind)
      layers[i].forbid("drift",
                       "conflicts with [[wind]]: layers drift with the wind at their "
                       "altitude (remove one of them)");
    readLayer(layers[i], layer, dynamics.layers.emplace_back());
    if (layer.name.empty()) layer.name = "layer" + std::to_string(i);
  }
  std::vector<TableReader> weather = t.tables("weather");
  for (std::size_t i = 0; i < weather.size(); ++i) {
    const WeatherLayer w = readWeather(weather[i]);
    if (std::string e = placeWeather(scene, dynamics, {int(i + 1), std::nullopt}, w); !e.empty())
      weather[i].failAt("type", e);  // readWeather checked it already: not reached
  }
  std::vector<TableReader> macro = t.tables("macrocluster");
  for (std::size_t i = 0; i < macro.size(); ++i) {
    std::uint64_t seed = hashCounters(scene.seed, 0x4d6163726full, i);
    macro[i].seed("seed", seed);
    appendWeatherClouds(
        scene, dynamics,
        weatherClouds(readWeather(macro[i], true), "macrocluster/" + std::to_string(i + 1), seed));
  }
  std::vector<TableReader> clouds = t.tables("cloud");
  for (std::size_t i = 0; i < clouds.size(); ++i) {
    EllipsoidCloud& cloud = scene.clouds.emplace_back();
    readCloud(clouds[i], hashCounters(scene.seed, 0x436c6f7564ull, i), cloud,
              dynamics.clouds.emplace_back());
    if (cloud.name.empty()) cloud.name = "cloud" + std::to_string(i);
  }
  readAutomata(t, scene, dynamics.automata);
  std::vector<TableReader> targets = t.tables("target");
  for (std::size_t i = 0; i < targets.size(); ++i) {
    Target& target = scene.targets.emplace_back();
    readTarget(targets[i], file, target);
    if (target.name.empty()) target.name = "target" + std::to_string(i);
  }
  t.finish();
}

// JSON to TOML, so that JSON objects go through the same readers as scene files. Null has
// no TOML form and yields nothing.
using TomlValue = std::variant<toml::table, toml::array, bool, std::int64_t, double, std::string>;

std::optional<TomlValue> tomlFromJson(const nlohmann::json& j);

bool fillTable(const nlohmann::json& j, toml::table& out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    std::optional<TomlValue> v = tomlFromJson(*it);
    if (!v) return false;
    std::visit([&](auto&& x) { out.insert(it.key(), std::move(x)); }, std::move(*v));
  }
  return true;
}

std::optional<TomlValue> tomlFromJson(const nlohmann::json& j) {
  if (j.is_object()) {
    toml::table table;
    if (!fillTable(j, table)) return std::nullopt;
    return TomlValue(std::move(table));
  }
  if (j.is_array()) {
    toml::array array;
    for (const auto& e : j) {
      std::optional<TomlValue> v = tomlFromJson(e);
      if (!v) return std::nullopt;
      std::visit([&](auto&& x) { array.push_back(std::move(x)); }, std::move(*v));
    }
    return TomlValue(std::move(array));
  }
  if (j.is_boolean()) return TomlValue(j.get<bool>());
  if (j.is_number_integer() &&
      !(j.is_number_unsigned() && j.get<std::uint64_t>() > std::uint64_t(INT64_MAX)))
    return TomlValue(j.get<std::int64_t>());
  if (j.is_number()) return TomlValue(j.get<double>());
  if (j.is_string()) return TomlValue(j.get<std::string>());
  return std::nullopt;
}

}  // namespace

std::string parseCloudJson(const nlohmann::json& cloud, std::uint64_t seed, EllipsoidCloud& out) {
  toml::table table;
  if (!cloud.is_object() || !fillTable(cloud, table))
    return "cloud: must be an object without null values";
  const std::string source = "request";
  try {
    TableReader reader(table, "cloud", source);
    EllipsoidCloud parsed;
    CloudDevelopment develop;
    reader.forbid("develop", "development schedules come from scene files only");
    readCloud(reader, seed, parsed, develop);
    out = std::move(parsed);
  } catch (const SceneError& e) {
    // "request:LINE: cloud.key: what": the line means nothing for JSON.
    const std::size_t key = e.message.find(": ");
    return key == std::string::npos ? e.message : e.message.substr(key + 2);
  }
  return "";
}

std::string parseTargetJson(const nlohmann::json& target, const std::vector<EntityType>& types,
                            Target& out) {
  toml::table table;
  if (!target.is_object() || !fillTable(target, table))
    return "target: must be an object without null values";
  Target parsed;
  if (const auto type = target.find("type"); type != target.end()) {
    std::string names;
    for (const EntityType& e : types) names += (names.empty() ? "" : ", ") + e.name;
    const auto it = std::find_if(types.begin(), types.end(), [&](const EntityType& e) {
      return type->is_string() && e.name == type->get<std::string>();
    });
    if (it == types.end())
      return "target.type: " + type->dump() +
             " is not an entity type of the daemon config (allowed: " +
             (names.empty() ? std::string("none are configured") : names) + ")";
    parsed = it->prototype;
    table.erase("type");
  }
  try {
    TableReader reader(table, "target", "request");
    reader.forbid("mesh", "meshes come from the daemon config's [[entity_type]] (give \"type\")");
    if (parsed.shape == TargetShape::kMesh) reader.forbid("shape", "the entity type fixes it");
    readTarget(reader, "", parsed);
    if (parsed.name.empty())
      reader.failHere("name is missing (a unique name, to move or remove the target by)");
    if (parsed.shape == TargetShape::kMesh && !parsed.mesh)
      reader.failAt("shape", "shape \"mesh\" needs an [[entity_type]] with a mesh");
  } catch (const SceneError& e) {
    const std::size_t key = e.message.find(": ");
    return key == std::string::npos ? e.message : e.message.substr(key + 2);
  }
  out = std::move(parsed);
  return "";
}

int nameIndex(const std::vector<std::string>& names, std::string_view name) {
  for (std::size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return int(i);
  return -1;
}

std::string parseSceneText(std::string_view text, const std::string& source_name, SceneFile& out) {
  SceneFile parsed;
  try {
    const toml::table root = config_detail::parseToml(text, source_name);
    readScene(root, source_name, parsed);
  } catch (const SceneError& e) {
    return e.message;
  }
  // Whatever the per-key checks cannot see (a backstop; they should catch everything).
  if (std::string e = worldDynamicsError(parsed.scene, parsed.dynamics); !e.empty())
    return source_name + ": " + e;
  out = std::move(parsed);
  return "";
}

std::string loadSceneFile(const std::string& path, SceneFile& out) {
  std::string text;
  if (std::string error = config_detail::readTextFile(path, "scene file", text); !error.empty())
    return error;
  return parseSceneText(text, path, out);
}

std::string validateCamera(const Camera& c) {
  if (c.width < 1 || c.width > Limits::kMaxImageSide || c.height < 1 ||
      c.height > Limits::kMaxImageSide)
    return ("image size " + std::to_string(c.width) + "x" + std::to_string(c.height) +
            " is out of range (allowed: 1 to " + std::to_string(Limits::kMaxImageSide) +
            " per side)");
  for (int i = 0; i < 3; ++i)
    if (!std::isfinite(c.position[i]) || std::abs(c.position[i]) > Limits::kMaxCoordinate)
      return ("camera position is out of range (allowed: |x|, |y|, |z| <= " +
              formatNumber(Limits::kMaxCoordinate) + " m)");
  if (c.position.z < 0.0) return ("camera z is below the ground (allowed: z >= 0)");
  if (!(c.vfov_deg >= Limits::kMinVfov && c.vfov_deg <= Limits::kMaxVfov))
    return ("vfov " + formatNumber(c.vfov_deg) + " is out of range (allowed: " +
            formatNumber(Limits::kMinVfov) + " to " + formatNumber(Limits::kMaxVfov) + ")");
  const Orientation& o = c.orientation;
  if (!(std::abs(o.heading_deg) <= Limits::kMaxHeading) ||
      !(std::abs(o.pitch_deg) <= Limits::kMaxPitch) || !(std::abs(o.roll_deg) <= Limits::kMaxRoll))
    return "camera orientation is out of range (allowed: heading, pitch, roll within +-" +
           formatNumber(Limits::kMaxHeading) + ", +-" + formatNumber(Limits::kMaxPitch) + ", +-" +
           formatNumber(Limits::kMaxRoll) + " degrees)";
  return "";
}

}  // namespace nephele
