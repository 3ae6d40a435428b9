#pragma once
// Labelled cloud-clutter datasets (docs/DATASETS.md): a description of ranges, one scene per
// sample drawn from them by counter-based randomness keyed by (dataset seed, sample index),
// and the labels of a rendered sample. No files, no GL: the dataset command does those.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "renderer/frame.h"
#include "world/formations/cloud_field.h"
#include "world/scene.h"

namespace nephele {

// A closed interval each sample draws uniformly from; lo == hi is a fixed value.
struct Span {
  double lo = 0.0, hi = 0.0;
};

// One category of target and how its instances are placed.
struct TargetClass {
  std::string name;  // the COCO category name
  TargetShape shape = TargetShape::kBox;
  std::shared_ptr<const TriangleMesh> mesh;  // shape mesh
  std::string mesh_path;                     // as written, for the manifest
  glm::dvec3 size{10.0, 10.0, 3.0};          // as Target::size
  glm::dvec3 colour{0.35, 0.35, 0.38};
  Span count{1.0, 1.0};  // instances per sample (integers)
  Span distance{300.0, 3000.0};
  Span heading{0.0, 360.0}, pitch{0.0, 0.0}, roll{0.0, 0.0};
  Span temperature{300.0, 300.0};  // kelvin, the infrared band's
  // Afloat: placed where its pixel's ray meets the sea (or the ground), a fifth of its height
  // under water, within `distance`; samples without a sea place it on the ground alike.
  bool afloat = false;
};

enum class Band { kVisible, kLwir };

struct DatasetSpec {
  std::uint64_t seed = 1;
  int samples = 100;
  int width = 640, height = 480;
  // The visible band, or long-wave infrared (world/infrared.h): then images are brightness
  // temperature mapped linearly from display_k.lo (black) to display_k.hi (white), and the
  // EXR holds radiance and brightness temperature.
  Band band = Band::kVisible;
  InfraredModel infrared;
  Span display_k{220.0, 320.0};
  // What each sample writes besides its PNG, YOLO text and record (docs/DATASETS.md).
  bool write_masks = true;
  bool write_depth = false;     // depth, cloud depth and object id as an EXR
  bool write_coverage = false;  // coverage and visibility as an EXR
  // How heaps are drawn by distance (RenderSettings::heaps: `heap_range`, `heap_detail`).
  HeapDrawing heaps;

  // Sky: each sample has `layers` weather layers, each of a genus drawn from `genera`.
  std::vector<CloudType> genera{CloudType::kCumulus};
  Span layers{1.0, 1.0};
  Span coverage{0.2, 0.6};
  Span base{600.0, 2000.0};
  Span thickness{300.0, 1500.0};
  Span sun_azimuth{0.0, 360.0}, sun_elevation{15.0, 70.0};
  double fog_probability = 0.0;
  Span fog_top{50.0, 300.0}, fog_visibility{2000.0, 20000.0};
  // Rain from the lowest layer (MODEL.md section 17) in `rain_probability` of the samples, at
  // a rate drawn from `rain_rate` mm/h.
  double rain_probability = 0.0;
  Span rain_rate{1.0, 25.0};

  // The sea (MODEL.md section 18) in place of the ground in `sea_probability` of the samples,
  // as a host sets it: its surface wind's speed and the direction it blows towards (clockwise
  // from north), the water's clarity, whitecaps. Its glint is a channel of every such sample:
  // masks where the glint's luminance (renderer/frame.h) is at least `glint_threshold`.
  double sea_probability = 0.0;
  Span sea_wind{2.0, 15.0}, sea_wind_direction{0.0, 360.0}, sea_clarity{0.3, 0.9};
  bool sea_whitecaps = true;
  double glint_threshold = 0.25;

  // Camera at (0, 0, altitude).
  Span altitude{300.0, 3000.0};
  Span heading{0.0, 360.0}, pitch{-5.0, 10.0}, roll{0.0, 0.0}, vfov{30.0, 60.0};

  std::vector<TargetClass> targets;
  // The share of targets placed behind cloud (centre ray's cloud transmittance below 0.9);
  // the others are placed in the clear (above 0.99) where the sky allows.
  double occluded_fraction = 0.5;
};

// The same checks the dataset file reader applies after its per-key ranges: empty when the
// description can be drawn, else what is wrong.
std::string datasetSpecError(const DatasetSpec& spec);

// One sample's scene and the record of every draw (for the manifest).
struct SampleScene {
  Scene scene;
  InfraredModel infrared;         // the spec's, with the targets' drawn temperatures
  std::vector<int> target_class;  // per scene target: index into spec.targets
  nlohmann::json record;          // index, seed, sky, sun, fog, camera, targets
};
SampleScene drawSample(const DatasetSpec& spec, int index);

// Labels of one rendered sample. `frame` holds object_id and visibility.
struct TargetLabel {
  int target = 0;                  // index into the scene's targets
  int category = 0;                // index into spec.targets
  int silhouette_px = 0;           // pixels where the target is the first opaque surface
  int visible_px = 0;              // of those, pixels with cloud transmittance >= 1/2
  double visibility = 0.0;         // mean transmittance over the silhouette
  double box_full[4]{};            // x, y, width, height of the silhouette, pixels
  double box[4]{};                 // of the visible part
  std::vector<std::uint32_t> rle;  // COCO uncompressed RLE of the visible part, column-major
  int glint_px = -1;  // glint pixels in its visible box (glintMask); -1 without a glint channel
};
// `frame` holds object_id and visibility, and glint when its sample has a sea.
std::vector<TargetLabel> labelTargets(const Frame& frame, const std::vector<int>& target_class,
                                      double glint_threshold = 0.25);

// Masks as float planes, which hold every integer to 65535 exactly: derived planes that encode
// writes as 16-bit grey (Channels::Pixels::kGrey16).
// The sun's glint on the sea (a false alarm's first cause): 65535 where the frame's glint
// luminance is at least `threshold`, 0 elsewhere; empty without a glint channel.
std::vector<float> glintMask(const Frame& frame, double threshold);

// The visible-part mask of every target: 1 + target index where visible, 0 elsewhere.
std::vector<float> instanceMask(const Frame& frame);

// One sample's COCO image entry and annotations (ids filled in when merged), YOLO lines.
nlohmann::json sampleLabelsJson(const std::vector<TargetLabel>& labels, int width, int height);
std::string yoloText(const std::vector<TargetLabel>& labels, int width, int height);

// Pieces of a dataset's COCO file, which the merge streams record by record: its info and
// categories, one sample's image entry, and one sample's annotations (ids from `next_id` on;
// targets with no visible pixel have none).
nlohmann::json cocoInfo(const DatasetSpec& spec);
nlohmann::json cocoCategories(const DatasetSpec& spec);
nlohmann::json cocoImage(const DatasetSpec& spec, const nlohmann::json& record);
std::vector<nlohmann::json> cocoAnnotations(const nlohmann::json& record, int& next_id);

}  // namespace nephele
