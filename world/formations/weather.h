#pragma once
// Weather as host simulators describe it (CIGI Weather Control: per layer a cloud type, base,
// thickness, coverage and wind), turned into what the world can draw: a textured sky plane
// for stratiform types, a field of cumulus heaps for convective ones.
#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "world/formations/ellipsoid_cloud.h"
#include "world/scene.h"

namespace nephele {

// The cloud-type enumeration of CIGI Weather Control packets, in its numbering.
enum class CloudType : int {
  kNone = 0,
  kAltocumulus = 1,
  kAltostratus = 2,
  kCirrocumulus = 3,
  kCirrostratus = 4,
  kCirrus = 5,
  kCumulonimbus = 6,
  kCumulus = 7,
  kNimbostratus = 8,
  kStratocumulus = 9,
  kStratus = 10,
};
inline constexpr int kCloudTypeCount = 11;
std::string_view cloudTypeName(CloudType type);

struct WeatherLayer {
  CloudType type = CloudType::kNone;
  double base_m = 1000.0;          // cloud base above the ground
  double thickness_m = 500.0;      // base to top
  double coverage = 0.5;           // fraction of the sky covered, 0..1
  std::optional<glm::dvec2> wind;  // east, north m/s at this layer; unset keeps the world's
};

// Input ranges are in world/limits.h.
struct WeatherLimits {
  // Convective layers become at most this many heaps, spread over a disc of this radius.
  static constexpr int kMaxHeaps = 32;
  static constexpr double kFieldRadius = 8000.0;
};

// What one weather layer adds to the world. Layer and cloud names start with `prefix`.
struct WeatherClouds {
  std::vector<CloudLayer> layers;
  std::vector<EllipsoidCloud> clouds;
};
WeatherClouds weatherClouds(const WeatherLayer& weather, const std::string& prefix,
                            glm::dvec2 field_centre, std::uint64_t seed);

// Gardner's T1 for a layer texture such that `coverage` of the plane has T above it
// (measured on a grid over one period of the texture).
double thresholdForCoverage(const LayerTextureSpec& texture, double coverage);

}  // namespace nephele
