#pragma once
// The one table of allowed input ranges. Scene files, the command line, the socket protocol,
// the Modbus register map and the World all read their edges from here, so that a value one
// of them accepts is never refused by another (docs/ACCURACY.md lists how each edge is
// tested).
#include <cmath>
#include <cstdint>
#include <ostream>
#include <sstream>
#include <string>
#include <string_view>

namespace nephele {

// A closed interval [lo, hi].
struct Range {
  double lo;
  double hi;
  constexpr bool contains(double x) const { return x >= lo && x <= hi; }
};

// A number as every error message shows it (the stream's default: 6 significant digits).
inline std::string formatNumber(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Writes "name: value is out of range (allowed: lo to hi)" to `out` and returns true when
// `value` is not finite or outside `range`; the one wording of a range error in world/.
inline bool outOfRange(std::ostream& out, const char* name, double value, Range range) {
  if (std::isfinite(value) && range.contains(value)) return false;
  out << name << ": " << value << " is out of range (allowed: " << range.lo << " to " << range.hi
      << ")";
  return true;
}

// IEEE 754 binary64 holds every integer of magnitude up to 2^53 exactly, and not every one
// beyond. Where a reader takes a number, an integer outside +-2^53 is refused rather than
// rounded, in every reader alike (scene files, configs, requests).
inline constexpr std::int64_t kMaxExactInteger = std::int64_t(1) << 53;
inline bool heldExactly(std::int64_t v) {
  return v >= -kMaxExactInteger && v <= kMaxExactInteger;
}

struct Limits {
  // Camera and image.
  static constexpr int kMaxImageSide = 16384;      // GL_MAX_RENDERBUFFER_SIZE on llvmpipe
  static constexpr double kMaxCoordinate = 1.0e8;  // metres from the origin
  static constexpr double kMaxAltitude = 1.0e5;
  static constexpr double kMinVfov = 0.01, kMaxVfov = 179.0;
  // Angles in degrees, each allowed from -max to +max; sun azimuth and elevation follow
  // heading and pitch.
  static constexpr double kMaxHeading = 360.0, kMaxPitch = 90.0, kMaxRoll = 180.0;
  static constexpr Range kFrustumAngle{-89.0, 89.0};  // an off-axis view's sides, degrees

  // Time, seconds of simulation time.
  static constexpr double kMaxTime = 1.0e9;     // a scene's start time
  static constexpr double kMaxAdvance = 1.0e7;  // one advance of the World's clock
  static constexpr double kMaxTick = 3600.0;    // one lockstep tick
  // Automaton steps are simulated one by one: a scene with automaton clouds may start at most
  // a day into its simulation.
  static constexpr double kMaxAutomatonTime = 86400.0;

  // Appearance (Gardner eq. 8, 9 and 11).
  // T1 of a sky plane; below 0 makes even T = 0 partly opaque (full cover, section 9).
  static constexpr Range kLayerThreshold{-10.0, 1.0};
  static constexpr Range kCloudThreshold{-2.0, 2.0};  // T1 and T2 of an ellipsoid cloud
  static constexpr Range kTransition{0.0, 10.0};      // D; 0 is a hard threshold
  static constexpr Range kFraction{0.0, 1.0};         // a, t, s of eq. 8; probabilities
  static constexpr Range kShininess{1.0, 1000.0};
  static constexpr Range kLightExtinction{0.0, 1.0};  // per metre, through a heap (section 14)
  static constexpr Range kColour{0.0, 100.0};         // linear RGB; above 1 for bright HDR suns
  static constexpr Range kContrastOffset{0.0, 10.0};  // Gardner's T0
  static constexpr Range kTermRotation{0.0, 90.0};    // lattice-breaking angle, degrees
  static constexpr Range kTermJitter{0.0, 1.0};       // lattice-breaking scale spread, octaves
  static constexpr Range kAmplitudeRatio{0.3, 1.0};   // Gardner C(i+1) / C(i)

  // Ellipsoids and targets, metres: zero, negative and NaN are rejected.
  static constexpr double kMinRadius = 1.0e-3, kMaxRadius = 1.0e5;
  static constexpr int kMaxEllipsoidsPerCloud = 4096;
  // Ellipsoids one world may hold (the daemon's `[world] max_ellipsoids`, whose default
  // follows the machine's memory: defaultMaxEllipsoids). Held and rendered, an ellipsoid
  // costs the daemon about 1.1 KB: 1,638,400 of them raise it from 1,020 to 2,748 MiB, 1,106
  // bytes each (docs/RELIABILITY.md).
  static constexpr int kMaxWorldEllipsoids = 4096 * kMaxEllipsoidsPerCloud;
  static constexpr int kBytesPerEllipsoid = 1106;

  // Wind, drift and weather.
  static constexpr double kMaxWind = 200.0;   // m/s, the speed of a wind sample
  static constexpr double kMaxDrift = 300.0;  // m/s, a layer's own drift per axis
  static constexpr double kMaxBase = 20000.0;
  static constexpr Range kThickness{1.0, 15000.0};
  // Inside a stratiform weather layer: its visibility (0 takes the genus's) and the band
  // beyond its base and top over which it thins (MODEL.md section 5).
  static constexpr Range kLayerVisibility{1.0, 1.0e7};
  static constexpr Range kTransitionBand{0.0, 1.0e4};
  // Precipitation (world/precipitation.h): liquid-water rate, mm/h (the world record is about
  // 300 in an hour), and the visibility a host may give instead, metres.
  static constexpr Range kPrecipitationRate{0.0, 500.0};
  static constexpr Range kPrecipitationVisibility{1.0, 1.0e6};
  static constexpr Range kCoveragePercent{0.0, 100.0};

  // Macroclusters and fronts (world/formations/region.h), metres.
  static constexpr Range kRegionSize{1.0, 2.0e7};      // full extent along each axis
  static constexpr Range kRegionBand{0.0, 1.0e7};      // edge and front transition widths
  static constexpr Range kClusterVariation{0.0, 1.0};  // per-cluster spread of cover, height
  // The heaps' drawing by distance (HeapDrawing, world/formations/cloud_field.h), which scene
  // files' render knobs `heap_range` and `heap_detail` (renderer/render_knobs.inc) and
  // dataset files both set: heaps as ellipsoids this far (0 automatic), and every lobe of
  // heaps this many pixels wide.
  static constexpr Range kHeapRange{0.0, 1.0e6};
  static constexpr Range kHeapDetail{0.0, 1.0e4};
  // The sea's sines (`sea_waves`) and its probe's width over the view's (`sea_probe_scale`),
  // render knobs that bench/sea_bench sweeps too. The other render knobs' ranges are in their
  // rows alone.
  static constexpr Range kSeaWaves{16.0, 128.0};
  static constexpr Range kSeaProbeScale{0.25, 2.0};

  // Datasets (dataset/dataset.h).
  static constexpr int kMaxSamples = 100000000;
  static constexpr Range kLayersPerSample{0.0, 4.0};
  static constexpr Range kTargetsPerClass{0.0, 64.0};
  static constexpr int kMaxTargetClasses = 256;
  static constexpr Range kTargetDistance{1.0, 1.0e6};

  // Gardner's clusters (world/formations/cluster.h).
  static constexpr Range kClusterSpacing{1.0, 1.0e5};
  static constexpr Range kClusterBoundary{1.0, 1.0e6};
  static constexpr Range kSizeVariation{0.0, 0.9};
  static constexpr Range kPositionVariation{0.0, 1.0};
  static constexpr Range kHeadingVariation{0.0, 180.0};
  static constexpr Range kVerticalScale{0.01, 100.0};

  // Automaton clouds (Dobashi; Shen).
  static constexpr int kMaxAutomata = 256;
  static constexpr int kMaxCellsPerAxis = 1024;
  static constexpr long long kMaxCells = 1LL << 24;
  // Work and memory, summed over a scene's automata and checked before any is built
  // (automatonWorkError; docs/RELIABILITY.md). Lattice points (cells x samples_per_cell^3)
  // dominate memory and start-up time: 2^24 of them measured 1.1 GB and 37 s on the machines
  // of ../shared/PLATFORM.md, so the bound is half that. A step costs about 1 us plus 6 ns
  // per cell.
  static constexpr long long kMaxLatticePoints = 1LL << 23;
  static constexpr double kMaxAutomatonSteps = 1.0e7;  // warm-up and steps to the time
  static constexpr double kMaxCellSteps = 4.0e9;       // cells x steps, ~25 s
  // One daemon request (tick, set_time advance) runs at most this much automaton work.
  static constexpr double kMaxStepsPerAdvance = 2.0e4;
  static constexpr double kMaxCellStepsPerAdvance = 5.0e8;
  static constexpr Range kCellSize{0.01, 1.0e4};
  static constexpr Range kStepInterval{1.0e-3, 3600.0};
  static constexpr int kMaxWarmupSteps = 100000;
  static constexpr int kMaxSamplesPerCell = 8;

  // The site and the sun's date (world/solar.h). The low-precision solar coordinates hold to
  // about 0.01 degree from 1901 to 2099 (NOAA's solar calculator notes).
  static constexpr Range kLatitude{-90.0, 90.0};
  static constexpr Range kLongitude{-180.0, 180.0};
  static constexpr int kMinSolarYear = 1901, kMaxSolarYear = 2099;
  // A CIGI host's world re-centres on its ownship this far from the origin (MODEL.md section
  // 13; 0: never): the flat database's distances hold to 0.1 % within 280 km of its origin.
  static constexpr Range kRecentreDistance{0.0, 1.0e6};
  static constexpr double kMinRecentreDistance = 1000.0, kDefaultRecentreDistance = 50000.0;
  // Ground fog (McReynolds and Blythe): top and meteorological visibility, metres.
  static constexpr Range kFogVisibility{1.0, 1.0e7};
  // Distance haze (MODEL.md section 5): visibility at Z = 0 and the extinction's scale height,
  // metres.
  static constexpr Range kHazeVisibility{10.0, 1.0e7};
  static constexpr Range kHazeScaleHeight{10.0, 1.0e5};
  // The sea (world/sea.h; CIGI 3.3 Maritime Surface Conditions and Wave Control): the distance
  // the wind has blown over water, metres (0: a fully developed sea), the surface water's
  // temperature, Celsius (sea water freezes near -2), and its clarity, 0 turbid to 1 clear.
  static constexpr Range kSeaFetch{0.0, 2.0e6};
  static constexpr Range kSeaTemperature{-2.0, 40.0};
  static constexpr Range kSeaClarity{0.0, 1.0};
  // A host's wave train: trough to crest and crest to crest, metres; its period, seconds (0:
  // from the deep-water dispersion of its wavelength); where it travels towards and its phase
  // offset, degrees. The sea holds at most kMaxWaveTrains (world/sea.h) of them, by id.
  static constexpr Range kWaveHeight{0.0, 30.0};
  static constexpr Range kWavelength{1.0, 2000.0};
  static constexpr Range kWavePeriod{0.0, 60.0};
  static constexpr Range kWaveDirection{-360.0, 360.0};
  static constexpr Range kWavePhase{-360.0, 360.0};
  static constexpr int kMaxWaveId = 255;  // CIGI's wave id is one byte

  // A scene file, daemon config or mesh read whole.
  static constexpr unsigned long long kMaxTextFileBytes = 64ull << 20;

  // Names of views, clouds, layers, automata, targets and snapshots.
  static constexpr std::size_t kMaxNameLength = 64;
};

// Where a host places a camera or a target: each coordinate within Limits::kMaxCoordinate of the
// origin (a camera's readers also keep its z at or above the ground). Every reader of positions
// (requests, scene files and configs, snapshots) and every move of the world under them
// (set_site's re-centring) keep to it, so that whatever the daemon holds can be saved and read
// back. Returns "" or "WHAT: (x, y, z) lies beyond ... (allowed: ...)".
inline std::string placementError(std::string_view what, double x, double y, double z) {
  const double c = Limits::kMaxCoordinate;
  if (std::isfinite(x) && std::isfinite(y) && std::isfinite(z) && std::abs(x) <= c &&
      std::abs(y) <= c && std::abs(z) <= c)
    return "";
  return std::string(what) + ": (" + formatNumber(x) + ", " + formatNumber(y) + ", " +
         formatNumber(z) + ") lies beyond " + formatNumber(c) +
         " m of the origin (allowed: each coordinate " + formatNumber(-c) + " to " +
         formatNumber(c) + ")";
}

// The one name rule, for every name a user gives (scene files, daemon configs, requests):
// 1 to 64 ASCII letters, digits, '_', '-' or '.', not starting with '.'. A name is thus
// also a safe file name. '/' is kept for names the daemon makes itself (a weather layer's
// clouds are "weather/1/heap3"), so no user name can collide with them.
inline constexpr std::string_view kNameRule =
    "1 to 64 ASCII letters, digits, '_', '-' or '.', not starting with '.'";
inline std::string nameError(std::string_view name) {
  bool ok = !name.empty() && name.size() <= Limits::kMaxNameLength && name[0] != '.';
  for (char c : name)
    ok = ok && ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                c == '_' || c == '-' || c == '.');
  if (ok) return {};
  std::string shown;
  for (char c : name.substr(0, 80))
    shown += (c >= 0x20 && c < 0x7f && c != '"' && c != '\\') ? std::string(1, c) : "?";
  return "\"" + shown + (name.size() > 80 ? "...\"" : "\"") +
         " is not a name (allowed: " + std::string(kNameRule) + ")";
}

}  // namespace nephele
