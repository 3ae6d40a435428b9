#pragma once
// What the files that make up the Engine share (engine.cpp, dispatch.cpp, delivery.cpp,
// atmosphere.cpp, snapshots.cpp): reply fields and small helpers. Transports include engine.h
// only.
#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdio>
#include <optional>
#include <string>
#include <variant>

#include "server/engine.h"
#include "server/render_service.h"
#include "world/solar.h"
#include "world/world.h"

namespace nephele {
namespace engine_detail {

using Clock = std::chrono::steady_clock;
using nlohmann::json;
using Outcome = std::variant<json, ProtocolError>;

constexpr int kProtocolVersion = 1;
constexpr std::size_t kMaxClouds = 4096;

inline double msSince(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

inline std::string hexHash(std::uint64_t h) {
  char text[17];
  std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(h));
  return text;
}

inline ProtocolError badField(std::string message) {
  return {ErrorCode::kBadField, std::move(message)};
}

inline json viewJson(const ViewConfig& v) {
  const Camera& c = v.camera;
  json out{{"name", v.name},
           {"position", {c.position.x, c.position.y, c.position.z}},
           {"heading", c.orientation.heading_deg},
           {"pitch", c.orientation.pitch_deg},
           {"roll", c.orientation.roll_deg},
           {"vfov", c.vfov_deg},
           {"width", c.width},
           {"height", c.height},
           {"format", imageFormatName(v.image.format)},
           {"channels", channelNames(v.image)}};
  if (v.frustum) out["frustum"] = frustumJson(*v.frustum);
  return out;
}

// The fields a patch sets; the others stay.
inline void applyViewPatch(ViewConfig& v, const ViewPatch& p) {
  Camera& cam = v.camera;
  if (p.position) cam.position = *p.position;
  if (p.heading) cam.orientation.heading_deg = *p.heading;
  if (p.pitch) cam.orientation.pitch_deg = *p.pitch;
  if (p.roll) cam.orientation.roll_deg = *p.roll;
  if (p.vfov) {
    cam.vfov_deg = *p.vfov;
    v.frustum.reset();
  }
  if (p.width) cam.width = *p.width;
  if (p.height) cam.height = *p.height;
  if (p.frustum) v.frustum = *p.frustum;
  if (v.frustum) {  // the vertical extent, and the width at this height with square pixels
    cam.vfov_deg = v.frustum->top - v.frustum->bottom;
    cam.width = offAxisView(cam, *v.frustum).width;
  }
  if (p.image) v.image = *p.image;
}

// The sea (atmosphere.cpp): the wind a new sea takes, the world's at altitude 0 (Sea's default
// in a world without wind); the sea after a set_sea, or the error naming the field and what is
// allowed; and the reply that describes it.
glm::dvec2 surfaceWind(const World& world);
std::variant<std::optional<Sea>, ProtocolError> seaAfter(const std::optional<Sea>& sea,
                                                         const command::SetSea& c,
                                                         glm::dvec2 surface_wind);
json seaJson(const std::optional<Sea>& sea);
// Where the world's database lies on the Earth (set_site's reply, stats' "site").
json siteJson(const World& world);
// The site a set_site with a position asks for, from where the world is placed now: a placed
// world re-centres and keeps its grid unless one is given (MODEL.md section 13).
Site siteAfter(const World& world, const command::SetSite& c);

// Beside a snapshot at PATH, the daemon's part of it (snapshots.cpp).
inline std::string daemonStatePath(const std::string& snapshot) {
  return snapshot + ".daemon.json";
}

}  // namespace engine_detail
}  // namespace nephele
