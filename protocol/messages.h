#pragma once
// The socket protocol's messages (protocol/PROTOCOL.md): newline-delimited JSON requests
// become typed commands here, and replies become bytes. No sockets.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

#include <glm/glm.hpp>
#include <nlohmann/json.hpp>

#include "renderer/frame.h"

#include "image/video_stream.h"
#include "world/camera.h"
#include "world/formations/weather.h"
#include "world/solar.h"

namespace nephele {

struct ProtocolLimits {
  static constexpr std::size_t kMaxRequestBytes = 64 * 1024;  // one request line, newline included
  static constexpr int kMaxJsonDepth = 16;                    // nesting of arrays and objects
  static constexpr double kMaxSubscriptionHz = 60.0;
  static constexpr int kMaxStreams = 8;  // streamed views at once (ranges: VideoStreamLimits)
  static constexpr double kMaxTimeScale = 1000.0;
  static constexpr int kWeatherLayers = 3;  // CIGI cloud layers 1 to 3
  // set_weather's layers: the cloud layers, then CIGI's precipitation layers 4 to 9 (rain,
  // snow, sleet, hail, sand, dust), which hold precipitation and no clouds.
  static constexpr int kWeatherKeys = 9;
  static constexpr int kMaxViewsPerRender = 16;  // views captured from one tick by one render
  static constexpr int kMaxTargets = 4096;       // targets in the world at once
};

enum class ErrorCode {
  kBadJson,         // the line is not JSON, or not an object
  kBadField,        // a field is missing, of the wrong type or out of range
  kUnknownCommand,  // "cmd" names no command
  kTooLarge,        // a request line longer than kMaxRequestBytes
  kUnauthorized,    // a token is configured and this connection has not sent it
  kBusy,            // the daemon's work queue is full; try again
  kNotFound,        // no such view, cloud, subscription or snapshot
  kLimit,           // a configured limit (image size, subscriptions, clients)
  kFailed,          // the request was valid but could not be carried out (I/O, render)
};
std::string_view errorCodeName(ErrorCode code);

struct ProtocolError {
  ErrorCode code = ErrorCode::kBadField;
  std::string message;
};

enum class ImageFormat { kRaw, kPng, kJpeg, kExr };
inline constexpr std::string_view kImageFormatNames = "raw, png, jpeg, exr";
std::string_view imageFormatName(ImageFormat format);

// Without a "channels" field, raw and EXR images carry coverage and PNG and JPEG do not
// (a PNG whose sky is transparent surprises viewers).
inline bool defaultCoverage(ImageFormat format) {
  return format == ImageFormat::kRaw || format == ImageFormat::kExr;
}

// What an image carries: colour (RGB), coverage (A) or both, in that order.
struct ImageRequest {
  ImageFormat format = ImageFormat::kRaw;
  bool colour = true;
  bool coverage = true;
  // Ground-truth channels (depth, cloud_depth, object_id, visibility; renderer/frame.h), raw
  // or EXR only. With any of them a raw image is float32 planes, one per channel in the
  // order of `order`, colour as three linear planes.
  ChannelSet planes;
  std::vector<Channel> order;  // every asked channel as the request listed it
  int channelCount() const { return (colour ? 3 : 0) + (coverage ? 1 : 0); }
  bool floatPlanes() const { return !planes.empty(); }
  bool operator==(const ImageRequest& o) const {
    return format == o.format && colour == o.colour && coverage == o.coverage &&
           planes == o.planes && order == o.order;
  }
};

enum class TickMode {
  kRealtime,  // the daemon advances the world tick_rate times per real second
  kLockstep,  // the world advances only when the host sends tick requests
};

// Fields of a view; unset ones stay as they are.
struct ViewPatch {
  std::optional<glm::dvec3> position;
  std::optional<double> heading, pitch, roll, vfov;
  std::optional<int> width, height;
  std::optional<Frustum> frustum;     // an off-axis view; a later vfov makes it centred again
  std::optional<ImageRequest> image;  // the view's default format and channels
};

namespace command {
struct Hello {
  std::optional<std::string> token;
};
struct GetView {
  std::string view;  // empty: every view
};
struct SetView {
  std::string view;
  ViewPatch patch;
};
struct SetWeather {
  int layer = 1;  // 1 to kWeatherKeys
  WeatherLayer weather;
  // A CIGI Environmental Region's layer (0 to 65535), drawn beside the global layer of the
  // same number; unset: the global layer. Set by the CIGI session, not read from the socket.
  std::optional<int> region;
};
struct SetWind {
  glm::dvec2 velocity{0.0};  // east, north m/s, at every altitude
};
// The sun by direction, or by the date and time of day at the site's latitude and longitude
// (world/solar.h), not both.
struct SetSun {
  std::optional<double> azimuth, elevation;
  std::optional<CivilTime> utc;
  // Where on the Earth the date's sun is placed, latitude and longitude in degrees (a CIGI
  // ownship's); the config's [site] when unset.
  std::optional<glm::dvec2> place;
};
// Ground fog (McReynolds and Blythe): unset fields keep their value; `enabled` false removes it.
// Distance haze over everything (MODEL.md section 5): unset fields keep their value; `enabled`
// false removes it.
struct SetHaze {
  std::optional<bool> enabled;
  std::optional<double> visibility, scale_height;
};
struct SetFog {
  std::optional<bool> enabled;
  std::optional<double> top, visibility;
  std::optional<glm::dvec3> colour;
};
// One wave train of set_sea's `waves`, by its id: unset fields keep the train's value (a new
// train starts from WaveTrain's, world/sea.h); `enabled` false removes it.
struct WavePatch {
  int id = 0;  // 0 to Limits::kMaxWaveId
  std::optional<bool> enabled;
  std::optional<double> height, wavelength, period, direction, phase;
};
// The sea in place of the ground (world/sea.h): unset fields keep their value; `enabled` false
// removes it. A sea that was absent starts from Sea's defaults with the world's surface wind
// once a field (or an enabled wave train) is given; with none the sea is only read back.
struct SetSea {
  std::optional<bool> enabled;
  std::optional<double> fetch, temperature, clarity;  // m, Celsius, 0 turbid to 1 clear
  std::optional<bool> whitecaps;
  std::optional<std::uint64_t> seed;
  std::vector<WavePatch> waves;  // distinct ids
};
// Where the database lies on the Earth (MODEL.md section 13): a world placed nowhere takes
// the site; a placed one re-centres on it, its content keeping its place on the Earth. `grid`
// (degrees clockwise from true north) is the database's north at the site, by default the one
// that keeps the content's axes. With no fields the site is only read back.
struct SetSite {
  std::optional<double> latitude, longitude, grid;
};
struct SetTime {
  std::optional<double> time_scale;  // simulated seconds per real second
  std::optional<bool> paused;
  std::optional<double> advance;  // seconds to move on at once
  std::optional<TickMode> mode;
};
struct AddCloud {
  nlohmann::json cloud;  // the keys of a scene file's [[cloud]] table
};
struct ChangeCloud {
  std::string name;
  std::optional<glm::dvec3> move;  // metres to move by
  std::optional<double> threshold, limb_threshold, transition;
  std::optional<glm::dvec3> colour;
};
struct RemoveCloud {
  std::string name;
};
// A target of a configured entity type at a pose: what a CIGI entity becomes, typed, with no
// object to read (the session has checked the pose against world/limits.h).
struct EntityPlacement {
  std::string name, type;  // `type`: an [[entity_type]] name of the daemon config
  glm::dvec3 centre{0.0};
  Orientation orientation;
};
struct AddTarget {
  nlohmann::json target;  // the keys of a scene file's [[target]] table, or `type` (config)
  bool replace = false;   // an existing target of that name is replaced (CIGI entities)
  std::optional<EntityPlacement> entity;  // set instead of `target` by the CIGI session
};
// A target's new pose: unset fields keep their value.
struct MoveTarget {
  std::string name;
  std::optional<glm::dvec3> centre;
  std::optional<double> heading, pitch, roll;
};
struct RemoveTarget {
  std::string name;
};
struct ListTargets {};
struct Tick {
  double dt = 0.0;
};
// Renders one view, or several from the same tick (one image reply each, in order). `camera`
// overrides the one view's pose, field of view and size for this render alone.
struct Render {
  std::vector<std::string> views;
  std::optional<ViewPatch> camera;
  std::optional<ImageRequest> image;  // unset: each view's own
};
struct Subscribe {
  std::string view;
  double rate_hz = 10.0;
  std::optional<ImageRequest> image;
};
struct Unsubscribe {
  std::int64_t subscription = 0;
};
// A view as a live H.264 stream to an address (image/video_stream.h, docs/STREAMING.md), its
// frames following the world's ticks as a subscription's do; until unstream.
struct Stream {
  std::string view;
  VideoStreamSettings settings;
};
struct Unstream {
  std::int64_t stream = 0;
};
struct Snapshot {
  std::string name;
};
struct Restore {
  std::string name;
};
struct Stats {};
struct Hash {};
}  // namespace command

// The Command variant and the names, from the one list (protocol/commands.inc).
namespace detail {
template <typename Ignored, typename... Commands>
struct CommandVariant {
  using type = std::variant<Commands...>;
};
}  // namespace detail
#define NEPHELE_COMMAND(name, Type) , command::Type
using Command = detail::CommandVariant<void
#include "protocol/commands.inc"
                                       >::type;
#undef NEPHELE_COMMAND
std::string_view commandName(const Command& command);
// "hello, get_view, ...": every name, for messages that list what is allowed.
inline constexpr std::string_view kCommandNames = [] {
  constexpr std::string_view all =
#define NEPHELE_COMMAND(name, Type) #name ", "
#include "protocol/commands.inc"
#undef NEPHELE_COMMAND
      "";
  return all.substr(0, all.size() - 2);
}();

// The clock: its numbers are the Modbus status register's (protocol/MODBUS.md).
enum class RunState : std::uint16_t { kRunning = 1, kPaused = 2, kLockstep = 3 };

// What a host reads back, on any interface (the Modbus registers, stats): the view it steers,
// the weather and atmosphere it set, and the clock.
struct HostReadings {
  glm::dvec3 position{0.0};
  double heading = 0.0, pitch = 0.0, roll = 0.0, vfov = 60.0;
  int width = 640, height = 480;
  glm::dvec2 wind{0.0};
  double sun_azimuth = 0.0, sun_elevation = 45.0;
  double time_scale = 1.0;
  std::array<WeatherLayer, ProtocolLimits::kWeatherLayers> layers;
  double haze_visibility = 0.0;                      // 0: no haze
  double haze_scale_height = Haze{}.scale_height_m;  // the haze's, or a new haze's
  double fog_top = 0.0, fog_visibility = 0.0;        // visibility 0: no fog
  glm::dvec3 fog_colour = Fog{}.colour;              // the fog's, or what a new fog would have
  std::optional<CivilTime> sun_utc;
};

struct HostStatus {
  RunState status = RunState::kRunning;
  std::uint32_t frames = 0;
  double render_ms = 0.0;
  std::uint64_t ticks = 0;
  std::uint16_t last_error = 0;
  double time_s = 0.0;
};

struct Request {
  nlohmann::json id;  // echoed in the reply: a number, a string or null
  Command command;
};

// A request that could not be parsed, with the id if one was readable.
struct BadRequest {
  nlohmann::json id;
  ProtocolError error;
};

// One request line (without its newline). Never throws.
std::variant<Request, BadRequest> parseRequest(std::string_view line);

// Reply lines, each ending in a newline.
std::string okReply(const nlohmann::json& id, const nlohmann::json& result);
std::string errorReply(const nlohmann::json& id, const ProtocolError& error);
// An image reply's header line; `image` describes the bytes that follow it
// (format, width, height, channels, ...), and gets "bytes": byte_count.
std::string imageReplyHeader(const nlohmann::json& id, nlohmann::json image,
                             std::size_t byte_count);
// A frame pushed to a subscriber: an event header line, then the bytes.
std::string frameEventHeader(std::int64_t subscription, nlohmann::json image,
                             std::size_t byte_count);

// Channel names of an image request, e.g. ["colour", "coverage"].
nlohmann::json channelNames(const ImageRequest& image);
// The camera a frame was seen from, as frame headers and dataset records carry it: position,
// attitude, vertical field of view, focal length in pixels and principal point.
nlohmann::json cameraJson(const FrameInfo& info);
// An off-axis view's frustum, in degrees from the view's axis, as set_view takes it.
nlohmann::json frustumJson(const Frustum& f);

}  // namespace nephele
