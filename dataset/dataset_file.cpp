#include "dataset/dataset_file.h"

#include <filesystem>
#include <memory>

#include "config/obj_mesh.h"
#include "config/table_reader.h"

namespace nephele {
namespace {

using config_detail::SceneError;
using config_detail::TableReader;

void readSpan(TableReader& t, std::string_view key, Span& s, Range range) {
  t.span(key, s.lo, s.hi, range);
}

std::vector<std::string> cloudTypeNames() {
  std::vector<std::string> names;
  for (int i = 1; i < kCloudTypeCount; ++i) names.emplace_back(cloudTypeName(CloudType(i)));
  return names;
}

void readDataset(TableReader& t, DatasetSpec& spec) {
  t.allow({"seed", "samples", "width", "height", "band", "masks", "depth", "coverage",
           "occluded_fraction", "heap_range", "heap_detail"});
  t.seed("seed", spec.seed);
  t.integer("samples", spec.samples, 1, Limits::kMaxSamples);
  t.integer("width", spec.width, 1, Limits::kMaxImageSide);
  t.integer("height", spec.height, 1, Limits::kMaxImageSide);
  spec.band = Band(t.choice("band", {"visible", "lwir"}, int(spec.band)));
  t.boolean("masks", spec.write_masks);
  t.boolean("depth", spec.write_depth);
  t.boolean("coverage", spec.write_coverage);
  t.number("occluded_fraction", spec.occluded_fraction, Limits::kFraction);
  t.number("heap_range", spec.heaps.range_m, Limits::kHeapRange);
  t.number("heap_detail", spec.heaps.detail_px, Limits::kHeapDetail);
  t.finish();
}

void readInfrared(TableReader& t, DatasetSpec& spec) {
  InfraredModel& m = spec.infrared;
  t.allow({"band", "steps", "surface_air", "ground", "ground_emissivity", "sky_zenith_emissivity",
           "display"});
  t.span("band", m.band_lo_um, m.band_hi_um, {0.5, 100.0});
  if (!(m.band_hi_um > m.band_lo_um)) t.failAt("band", "must be [low, high] with low < high");
  t.integer("steps", m.band_steps, 1, 10000);
  t.number("surface_air", m.surface_air_k, 150.0, 350.0);
  t.number("ground", m.ground_k, 150.0, 400.0);
  t.number("ground_emissivity", m.ground_emissivity, Limits::kFraction);
  t.number("sky_zenith_emissivity", m.sky_zenith_emissivity, Limits::kFraction);
  t.span("display", spec.display_k.lo, spec.display_k.hi, {1.0, 5000.0});
  if (!(spec.display_k.hi > spec.display_k.lo))
    t.failAt("display", "must be [black, white] kelvin with black < white");
  t.finish();
}

void readSky(TableReader& t, DatasetSpec& spec) {
  t.allow({"genera", "layers", "coverage", "base", "thickness", "rain_probability", "rain_rate"});
  if (t.has("genera")) {
    std::vector<std::string> names;
    t.strings("genera", names, kCloudTypeCount);
    const std::vector<std::string> allowed = cloudTypeNames();
    spec.genera.clear();
    for (const std::string& name : names) {
      const int i = nameIndex(allowed, name);
      if (i < 0)
        t.failAt("genera", "\"" + name + "\" is not a genus (allowed: " +
                               config_detail::joinKeys(allowed) + ")");
      spec.genera.push_back(CloudType(i + 1));
    }
  }
  readSpan(t, "layers", spec.layers, Limits::kLayersPerSample);
  readSpan(t, "coverage", spec.coverage, Limits::kFraction);
  readSpan(t, "base", spec.base, {0.0, Limits::kMaxBase});
  readSpan(t, "thickness", spec.thickness, Limits::kThickness);
  t.number("rain_probability", spec.rain_probability, Limits::kFraction);
  readSpan(t, "rain_rate", spec.rain_rate, Limits::kPrecipitationRate);
  t.finish();
}

void readSea(TableReader& t, DatasetSpec& spec) {
  t.allow({"probability", "wind", "direction", "clarity", "whitecaps", "glint_threshold"});
  t.number("probability", spec.sea_probability, Limits::kFraction);
  readSpan(t, "wind", spec.sea_wind, {0.0, Limits::kMaxWind});
  readSpan(t, "direction", spec.sea_wind_direction, {-Limits::kMaxHeading, Limits::kMaxHeading});
  readSpan(t, "clarity", spec.sea_clarity, Limits::kSeaClarity);
  t.boolean("whitecaps", spec.sea_whitecaps);
  t.number("glint_threshold", spec.glint_threshold, {0.0, 1.0e6});
  t.finish();
}

void readTargetClass(TableReader& t, const std::string& file, TargetClass& c) {
  t.allow({"name", "shape", "mesh", "size", "colour", "count", "distance", "heading", "pitch",
           "roll", "temperature", "afloat"});
  t.boolean("afloat", c.afloat);
  if (!t.has("name")) t.failHere("name is missing (the category's name)");
  t.name("name", c.name);
  c.shape = TargetShape(t.choice("shape", {"box", "ellipsoid", "mesh"}, int(c.shape)));
  if (c.shape == TargetShape::kMesh) c.size = glm::dvec3(1.0);
  t.vector("size", c.size, Limits::kMinRadius, Limits::kMaxRadius);
  t.vector("colour", c.colour, Limits::kColour);
  readSpan(t, "count", c.count, Limits::kTargetsPerClass);
  readSpan(t, "distance", c.distance, Limits::kTargetDistance);
  readSpan(t, "heading", c.heading, {-Limits::kMaxHeading, Limits::kMaxHeading});
  readSpan(t, "pitch", c.pitch, {-Limits::kMaxPitch, Limits::kMaxPitch});
  readSpan(t, "roll", c.roll, {-Limits::kMaxRoll, Limits::kMaxRoll});
  readSpan(t, "temperature", c.temperature, {1.0, 5000.0});
  t.string("mesh", c.mesh_path);
  if (c.shape == TargetShape::kMesh) {
    if (c.mesh_path.empty()) t.failAt("shape", "shape \"mesh\" needs a mesh = \"file.obj\" key");
    const std::filesystem::path path(c.mesh_path);
    const std::filesystem::path resolved =
        path.is_absolute() ? path : std::filesystem::path(file).parent_path() / path;
    auto mesh = std::make_shared<TriangleMesh>();
    if (std::string error = loadObjMesh(resolved.string(), *mesh); !error.empty())
      t.failAt("mesh", error);
    c.mesh = std::move(mesh);
  } else if (!c.mesh_path.empty()) {
    t.failAt("mesh", "applies to shape \"mesh\" only");
  }
  t.finish();
}

}  // namespace

std::string parseDatasetText(std::string_view text, const std::string& source_name,
                             DatasetSpec& out) {
  DatasetSpec spec;
  try {
    const toml::table root = config_detail::parseToml(text, source_name);
    TableReader t(root, "", source_name);
    t.allow({"dataset", "sky", "sun", "fog", "sea", "camera", "target", "infrared"});
    if (auto sea = t.table("sea")) readSea(*sea, spec);
    if (auto d = t.table("dataset")) readDataset(*d, spec);
    if (auto sky = t.table("sky")) readSky(*sky, spec);
    if (auto infrared = t.table("infrared")) readInfrared(*infrared, spec);
    if (auto sun = t.table("sun")) {
      sun->allow({"azimuth", "elevation"});
      readSpan(*sun, "azimuth", spec.sun_azimuth, {-Limits::kMaxHeading, Limits::kMaxHeading});
      readSpan(*sun, "elevation", spec.sun_elevation, {-Limits::kMaxPitch, Limits::kMaxPitch});
      sun->finish();
    }
    if (auto fog = t.table("fog")) {
      fog->allow({"probability", "top", "visibility"});
      fog->number("probability", spec.fog_probability, Limits::kFraction);
      readSpan(*fog, "top", spec.fog_top, {0.0, Limits::kMaxAltitude});
      readSpan(*fog, "visibility", spec.fog_visibility, {1.0, 1.0e7});
      fog->finish();
    }
    if (auto camera = t.table("camera")) {
      camera->allow({"altitude", "heading", "pitch", "roll", "vfov"});
      readSpan(*camera, "altitude", spec.altitude, {0.0, Limits::kMaxAltitude});
      readSpan(*camera, "heading", spec.heading, {-Limits::kMaxHeading, Limits::kMaxHeading});
      readSpan(*camera, "pitch", spec.pitch, {-Limits::kMaxPitch, Limits::kMaxPitch});
      readSpan(*camera, "roll", spec.roll, {-Limits::kMaxRoll, Limits::kMaxRoll});
      readSpan(*camera, "vfov", spec.vfov, {Limits::kMinVfov, Limits::kMaxVfov});
      camera->finish();
    }
    std::vector<TableReader> targets = t.tables("target");
    if (targets.size() > std::size_t(Limits::kMaxTargetClasses))
      t.failAt("target",
               "at most " + std::to_string(Limits::kMaxTargetClasses) + " [[target]] categories");
    for (TableReader& target : targets)
      readTargetClass(target, source_name, spec.targets.emplace_back());
    for (std::size_t i = 0; i < spec.targets.size(); ++i)
      for (std::size_t j = 0; j < i; ++j)
        if (spec.targets[i].name == spec.targets[j].name)
          t.failAt("target",
                   "two [[target]] categories are named \"" + spec.targets[i].name + "\"");
    t.finish();
  } catch (const SceneError& e) {
    return e.message;
  }
  if (std::string e = datasetSpecError(spec); !e.empty()) return source_name + ": " + e;
  out = std::move(spec);
  return "";
}

std::string loadDatasetFile(const std::string& path, DatasetSpec& out) {
  std::string text;
  if (std::string e = config_detail::readTextFile(path, "dataset description", text); !e.empty())
    return e;
  return parseDatasetText(text, path, out);
}

}  // namespace nephele
