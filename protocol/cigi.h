#pragma once
// CIGI 3.3 (Common Image Generator Interface, SISO-STD-013 / the Boeing CIGI 3.3 ICD):
// datagrams to typed packets and back, for the packets Nephele uses (docs/CIGI.md). No
// sockets. Every size, identifier and field position below is the ICD's; the byte order of
// a message is the sender's, detected by the magic number of its first packet.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <variant>
#include <vector>

namespace nephele::cigi {

inline constexpr std::uint8_t kVersion = 3;       // CIGI major version
inline constexpr std::uint8_t kMinorVersion = 3;  // 3.3
inline constexpr std::uint16_t kMagic = 0x8000;   // the byte-swap magic number
// The largest message accepted (UDP allows 65,507 bytes; the ICD sets no limit).
inline constexpr std::size_t kMaxMessageBytes = 32768;
inline constexpr std::size_t kPacketAlign = 8;  // every CIGI 3 packet size is a multiple of 8

// Packet identifiers and sizes in bytes.
struct Id {
  static constexpr std::uint8_t kIgControl = 1, kEntityControl = 2, kCelestialSphereControl = 9,
                                kAtmosphereControl = 10, kEnvironmentalRegionControl = 11,
                                kWeatherControl = 12, kMaritimeSurfaceConditionsControl = 13,
                                kWaveControl = 14, kViewControl = 16, kViewDefinition = 21,
                                kStartOfFrame = 101;
};
struct Size {
  static constexpr std::uint8_t kIgControl = 24, kEntityControl = 48, kCelestialSphereControl = 16,
                                kAtmosphereControl = 32, kEnvironmentalRegionControl = 48,
                                kWeatherControl = 56, kMaritimeSurfaceConditionsControl = 24,
                                kWaveControl = 32, kViewControl = 32, kViewDefinition = 32,
                                kStartOfFrame = 24;
};

enum class IgMode : std::uint8_t { kStandby = 0, kOperate = 1, kDebug = 2 };
enum class EntityState : std::uint8_t { kInactive = 0, kActive = 1, kDestroyed = 2 };
enum class WeatherScope : std::uint8_t { kGlobal = 0, kRegional = 1, kEntity = 2 };
enum class RegionState : std::uint8_t { kInactive = 0, kActive = 1, kDestroyed = 2 };
enum class BreakerType : std::uint8_t { kPlunging = 0, kSpilling = 1, kSurging = 2 };
// Weather Control layer identifiers.
struct Layer {
  static constexpr std::uint8_t kGroundFog = 0, kCloud1 = 1, kCloud3 = 3, kRain = 4, kSnow = 5,
                                kSleet = 6, kHail = 7, kSand = 8, kDust = 9;
};
inline constexpr std::uint32_t kTimestampTicksPerSecond = 100000;  // 10 microsecond units

struct IgControl {
  std::int8_t database = 0;
  IgMode mode = IgMode::kOperate;
  bool timestamp_valid = false;
  bool extrapolation = false;
  std::uint8_t minor_version = kMinorVersion;
  std::uint32_t host_frame = 0;
  std::uint32_t timestamp = 0;  // 10 microsecond units
  std::uint32_t last_ig_frame = 0;
  bool operator==(const IgControl&) const = default;
};

struct EntityControl {
  std::uint16_t entity_id = 0;
  EntityState state = EntityState::kActive;
  bool attached = false;
  bool collision_detection = false;
  bool inherit_alpha = false;
  std::uint8_t clamp = 0;  // ground/ocean clamp, 0..2
  std::uint8_t alpha = 255;
  std::uint16_t type = 0;
  std::uint16_t parent_id = 0;
  float roll = 0, pitch = 0, yaw = 0;                // degrees
  double latitude = 0, longitude = 0, altitude = 0;  // or x, y, z offsets when attached
  bool operator==(const EntityControl&) const = default;
};

struct ViewControl {
  std::uint16_t view_id = 0;
  std::uint8_t group_id = 0;
  std::uint8_t enables = 0;  // bits: x, y, z, roll, pitch, yaw offset enable
  std::uint16_t entity_id = 0;
  float x = 0, y = 0, z = 0;           // metres in the entity's body frame (x fwd, y right, z down)
  float roll = 0, pitch = 0, yaw = 0;  // degrees
  bool operator==(const ViewControl&) const = default;
};

struct ViewDefinition {
  std::uint16_t view_id = 0;
  std::uint8_t group_id = 0;
  std::uint8_t enables = 0;  // bits: near, far, left, right, top, bottom enable
  std::uint8_t mirror_mode = 0;
  std::uint8_t pixel_replication = 0;
  bool orthographic = false;
  bool reorder = false;
  std::uint8_t view_type = 0;
  float near_m = 0, far_m = 0;
  float left = 0, right = 0, top = 0, bottom = 0;  // degrees from the view's axis
  bool operator==(const ViewDefinition&) const = default;
};

// A rectangle on the Earth that regional weather applies to: its centre, its extents along its
// own X axis (turned `rotation` degrees clockwise from true north) and Y axis, and the band
// outside it over which its weather blends into the global weather.
struct EnvironmentalRegionControl {
  std::uint16_t region_id = 0;
  RegionState state = RegionState::kInactive;
  bool merge_weather = false, merge_aerosol = false, merge_maritime = false,
       merge_terrestrial = false;
  double latitude = 0, longitude = 0;
  float size_x = 0, size_y = 0, corner_radius = 0, rotation = 0, transition_perimeter = 0;
  bool operator==(const EnvironmentalRegionControl&) const = default;
};

struct WeatherControl {
  std::uint16_t entity_region_id = 0;
  std::uint8_t layer = 0;
  std::uint8_t humidity = 0;  // percent
  bool enabled = false, scud = false, random_winds = false, random_lightning = false;
  std::uint8_t cloud_type = 0;  // 0..15 on the wire; 0..10 defined
  WeatherScope scope = WeatherScope::kGlobal;
  std::uint8_t severity = 0;
  float air_temperature = 0, visibility = 0, scud_frequency = 0, coverage = 0;
  float base = 0, thickness = 0, transition_band = 0;
  float wind_speed = 0, vertical_wind = 0, wind_direction = 0;
  float pressure = 0, aerosol = 0;
  bool operator==(const WeatherControl&) const = default;
};

// The sea's surface (global scope), or a region's or an entity's: its conditions, whitecaps,
// height above the database's Z = 0, water temperature and clarity.
struct MaritimeSurfaceConditionsControl {
  std::uint16_t entity_region_id = 0;
  bool surface_conditions_enabled = false, whitecaps = false;
  WeatherScope scope = WeatherScope::kGlobal;
  float sea_surface_height = 0;  // metres
  float water_temperature = 0;   // degrees Celsius
  float clarity = 0;             // percent: 0 turbid, 100 clear
  bool operator==(const MaritimeSurfaceConditionsControl&) const = default;
};

// One wave train: trough-to-crest height, wavelength, period, the direction it propagates in
// (degrees from true north), its phase offset and leading (crest asymmetry) in degrees.
struct WaveControl {
  std::uint16_t entity_region_id = 0;
  std::uint8_t wave_id = 0;
  bool enabled = false;
  WeatherScope scope = WeatherScope::kGlobal;
  BreakerType breaker = BreakerType::kPlunging;
  float height = 0, wavelength = 0, period = 0, direction = 0, phase_offset = 0, leading = 0;
  bool operator==(const WaveControl&) const = default;
};

struct AtmosphereControl {
  bool model_enabled = false;
  std::uint8_t humidity = 0;
  float air_temperature = 0, visibility = 0, wind_speed = 0, vertical_wind = 0, wind_direction = 0,
        pressure = 0;
  bool operator==(const AtmosphereControl&) const = default;
};

struct CelestialSphereControl {
  std::uint8_t hour = 0, minute = 0;
  bool ephemeris = false, sun = false, moon = false, stars = false, date_valid = false;
  std::uint32_t date = 0;  // MMDDYYYY as a decimal number
  float star_intensity = 0;
  bool operator==(const CelestialSphereControl&) const = default;
};

// Start of Frame's IG Status, which CIGI 3.3 leaves to the IG (docs/CIGI.md, "IG status"): what
// became of the host frame it answers.
struct IgStatus {
  static constexpr std::uint8_t kApplied = 0;         // every packet applied
  static constexpr std::uint8_t kPacketsRefused = 1;  // some packets refused, the rest applied
  static constexpr std::uint8_t kLate = 2;            // late or repeated: nothing applied
  static constexpr std::uint8_t kFrameJump = 3;       // a jump in numbering, awaiting the next
  static constexpr std::uint8_t kWorldRefused = 4;    // the world refused it: nothing applied
  static constexpr std::uint8_t kBusy = 5;  // the daemon's queue was full: nothing applied
};

struct StartOfFrame {
  std::int8_t database = 0;
  std::uint8_t ig_status = 0;
  IgMode mode = IgMode::kOperate;
  bool timestamp_valid = false;
  bool host_earth_model = false;  // 0: WGS 84, 1: host-defined
  std::uint8_t minor_version = kMinorVersion;
  std::uint32_t ig_frame = 0;
  std::uint32_t timestamp = 0;
  std::uint32_t last_host_frame = 0;
  bool operator==(const StartOfFrame&) const = default;
};

// A packet Nephele does not use: kept as its identifier and size (skipped, and counted).
struct OtherPacket {
  std::uint8_t id = 0;
  std::uint8_t size = 0;
  bool operator==(const OtherPacket&) const = default;
};

using Packet =
    std::variant<IgControl, EntityControl, ViewControl, ViewDefinition, WeatherControl,
                 EnvironmentalRegionControl, AtmosphereControl, CelestialSphereControl,
                 MaritimeSurfaceConditionsControl, WaveControl, StartOfFrame, OtherPacket>;

enum class ByteOrder { kBig, kLittle };

// One message (a datagram's payload): its packets in order.
struct Message {
  ByteOrder order = ByteOrder::kBig;
  std::vector<Packet> packets;
};

// Why a datagram was refused.
enum class Fault {
  kTruncated,   // shorter than its first packet, or a packet runs past the end
  kOversized,   // longer than kMaxMessageBytes
  kMalformed,   // a packet size of 0, not a multiple of 8, or wrong for its identifier
  kWrongFirst,  // the first packet is not IG Control (host) or Start of Frame (IG)
  kVersion,     // not CIGI 3
  kMagic,       // neither byte order gives the magic number
};
std::string_view faultName(Fault fault);

struct DecodeError {
  Fault fault;
  std::string message;  // what is wrong, where, and what is allowed
};

// A host-to-IG message: IG Control first, then any packets. Never throws.
std::variant<Message, DecodeError> decodeHostMessage(std::span<const std::uint8_t> bytes);
// An IG-to-host message: Start of Frame first.
std::variant<Message, DecodeError> decodeIgMessage(std::span<const std::uint8_t> bytes);

// Appends `packet` to `out` in `order` (the encoder of both ends: the daemon writes Start of
// Frame; tests and the benchmark write host messages).
void encode(const Packet& packet, ByteOrder order, std::vector<std::uint8_t>& out);

}  // namespace nephele::cigi
