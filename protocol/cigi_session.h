#pragma once
// What a CIGI host's packets mean to Nephele (docs/CIGI.md): each host message becomes the
// socket protocol's commands, applied as one batch, so that CIGI, the socket and Modbus
// share every check. A session remembers what the host has set (entities, view offsets and
// frusta, weather, sun) so that a packet repeated every frame, as hosts do, changes nothing
// and costs nothing. No sockets.
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "protocol/cigi.h"
#include "protocol/messages.h"
#include "world/geodesy.h"
#include "world/limits.h"

namespace nephele::cigi {

struct SessionSettings {
  // The database origin ([site]); none: the host's first position sets it (Session::next).
  std::optional<Site> site;
  std::vector<std::string> views;                         // view id n is views[n]
  std::vector<std::pair<int, std::string>> entity_types;  // CIGI entity type -> [[entity_type]]
  double default_frame_s = 1.0 / 60.0;  // host frame time when the timestamps do not tell
  // The origin moves to the ownship once it is this far from it (MODEL.md section 13); 0: never.
  double recentre_m = Limits::kDefaultRecentreDistance;
};

// A host message mapped for the daemon: the commands of one host frame.
struct MappedMessage {
  IgControl control;
  std::vector<Command> commands;     // in order
  double dt_s = 0.0;                 // the host's frame time, by which a lockstep world advances
  std::vector<std::string> ignored;  // packets or fields not supported, with why
  std::vector<std::string> refused;  // packets refused for a value out of range, with why
  // The database origin this message took from the host, with no [site] configured: once per
  // session.
  std::optional<Site> site_adopted;
  // The origin this message re-centred the world on (the ownship's place, SessionSettings).
  std::optional<Site> recentred;
};

// A message the session refuses as a whole (nothing of it is applied): "out_of_order" (late or
// repeated) or "frame_jump" (numbering that jumped, followed once the next frame confirms it).
struct Refusal {
  std::string reason;
  std::string message;
  IgControl control;                      // the message's IG Control, which Start of Frame answers
  std::uint8_t status = IgStatus::kLate;  // Start of Frame's IG status for it
  int run = 0;  // frame numbers refused: consecutive ones in a row, this one included
};

// Host frame numbering (docs/CIGI.md, "Frame numbers"), in 32-bit serial order. A frame that
// is not 1 to kMaxFrameJump ahead of the last one applied is refused: up to kReorderWindow
// behind it, as late or repeated; elsewhere, as a jump (a restart of the host, or a corrupted
// number). Consecutive refused numbers (n, n + 1, ...) are a new run of the host, which is
// followed at the kRestartRunBehind-th of them within the window (two late datagrams in a row
// are refused) and at the kRestartRunElsewhere-th elsewhere.
inline constexpr std::int32_t kReorderWindow = 16;
inline constexpr std::int32_t kMaxFrameJump = 3000;
inline constexpr int kRestartRunBehind = 3, kRestartRunElsewhere = 2;

class Session {
 public:
  explicit Session(SessionSettings settings) : settings_(std::move(settings)) {
    if (settings_.site) state_.site = *settings_.site;
  }

  // Turns a decoded host message into commands, and keeps the state they lead to. The session
  // takes that state only once the daemon has applied the frame (commit), so that a refused
  // batch is sent again in full.
  std::variant<MappedMessage, Refusal> map(const Message& message);
  void commit();
  // After the daemon refused a frame (a target removed over the socket, say): what the session
  // believed applied is forgotten, so that the next packets place targets and set the wind,
  // the sun and the sea afresh (global weather is always passed on: the world ignores a layer
  // set again as it is). Frame numbers, the ownship and the views stay. The frame mapped last
  // is dropped. Packets refused for their values (MappedMessage::refused) leave the rest of the
  // frame applied.
  void forget();

  std::uint32_t lastHostFrame() const { return state_.last_host_frame.value_or(0); }

 private:
  struct Pose {
    glm::dvec3 position{0.0};
    glm::dmat3 attitude{1.0};  // body to world (Nephele's body axes: right, forward, up)
  };
  struct Entity {
    EntityControl packet;
    bool target = false;  // in the world as a target (not the ownship)
  };
  struct RegionalKey {
    std::uint16_t region = 0;
    std::uint8_t layer = 0;
    auto operator<=>(const RegionalKey&) const = default;
  };
  struct ViewState {
    std::optional<ViewControl> control;
    std::optional<ViewDefinition> definition;
  };
  // The state after a message, computed without changing this one.
  struct State {
    std::optional<std::uint32_t> last_host_frame;
    std::optional<std::uint32_t> jumped_to;  // the last frame number refused, and how many
    int jump_run = 0;                        // consecutive numbers were refused up to it
    std::optional<std::uint32_t> last_timestamp;
    std::map<std::uint16_t, Entity> entities;
    std::map<std::uint16_t, ViewState> views;
    // Regional weather (Weather Control of regional scope), by region and layer, as last
    // accepted, and the active regions it is drawn in (Environmental Region Control).
    std::map<RegionalKey, WeatherControl> regional_weather;
    std::map<std::uint16_t, EnvironmentalRegionControl> regions;
    std::optional<AtmosphereControl> atmosphere;
    // The sea as the host last set it (global scope): its surface conditions, and its wave
    // trains by wave id, disabled ones included (a host repeats its packets every frame).
    std::optional<MaritimeSurfaceConditionsControl> maritime;
    std::map<std::uint8_t, WaveControl> waves;
    std::optional<CelestialSphereControl> celestial;
    std::optional<glm::dvec2> sun_place;  // latitude, longitude the sun was last placed for
    // The database origin: [site], or the host's first position, re-centred as the ownship flies.
    std::optional<Site> site;
  };
  class Mapping;  // one message's packets onto the state and commands they lead to

  std::variant<State, Refusal> next(const Message& message, MappedMessage& mapped) const;
  std::optional<Refusal> takeFrameNumber(const IgControl& control, State& s,
                                         MappedMessage& mapped) const;
  std::optional<Site> recentredSite(const State& s, const EntityControl* ownship) const;
  std::optional<Pose> poseOf(const State& state, std::uint16_t entity, int depth = 0) const;

  // Geodetic positions to the database's east, north, up metres about the state's site (MODEL.md
  // section 13); about 0 N 0 E while it has none, when nothing geodetic has come yet.
  static LocalFrame databaseOf(const State& state);

  SessionSettings settings_;
  State state_;
  std::optional<State> pending_;  // after the last frame mapped, until commit
};

}  // namespace nephele::cigi
