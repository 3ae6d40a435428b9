#pragma once
// Daemon configuration files (TOML, see deploy/nephele.toml) to typed settings, validated
// once here like scene files: every error names the file, the line, the key and what is
// allowed.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "config/scene_file.h"
#include "image/image_encoding.h"
#include "protocol/messages.h"
#include "world/geodesy.h"
#include "world/limits.h"

namespace nephele {

struct ViewConfig {
  std::string name;
  Camera camera;  // pose, field of view and size
  // An off-axis view (CIGI View Definition, set_view "frustum"): camera.vfov_deg is then its
  // vertical extent and camera.width follows from it (world/camera.h offAxisView).
  std::optional<Frustum> frustum;
  ImageRequest image;
};

struct ListenConfig {
  std::string bind = "127.0.0.1";
  int port = 0;  // 0: any free port (printed on the ready line)
};

// How long a listener waits on a client (docs/RELIABILITY.md).
struct Timeouts {
  double request_s;  // a request begun must be complete within this
  double idle_s;     // a connection with nothing to do is closed after this; 0: never
};

// CIGI 3.3 over UDP (protocol/cigi.h, docs/CIGI.md): the host sends to `ig_port`; Start of
// Frame goes back to the sender's address at `host_port`.
struct CigiConfig {
  bool enabled = false;
  std::string bind = "127.0.0.1";
  int ig_port = 8004;
  int host_port = 8005;
  std::vector<std::string> views;  // CIGI view id n is views[n]; default the config's views
  // The world re-centres on the ownship once it is this far from the database's origin
  // (MODEL.md section 13); 0: never.
  double recentre_distance_m = Limits::kDefaultRecentreDistance;
};

// A quarter of the machine's physical memory in ellipsoids of Limits::kBytesPerEllipsoid,
// within [2^16, Limits::kMaxWorldEllipsoids].
int defaultMaxEllipsoids();

struct DaemonConfig {
  std::string config_path;
  std::string scene_path;  // relative paths are relative to the config file
  SceneFile scene;

  TickMode mode = TickMode::kRealtime;
  double tick_rate_hz = 30.0;
  double time_scale = 1.0;
  int world_threads = 1;
  // Compile the shaders every genus asks for after ready, a step after each round of the world
  // thread's work (RenderService::prewarmStep), so that no weather change stalls a frame; false
  // compiles at each first use.
  bool prewarm = true;
  // The world budget: ellipsoids its clouds may hold (the scene's, add_cloud's, a restored
  // snapshot's); the default is what a quarter of this machine's memory holds.
  int max_ellipsoids = defaultMaxEllipsoids();
  std::vector<ViewConfig> views;  // at least one

  bool socket_enabled = true;
  ListenConfig socket{"127.0.0.1", 7600};
  std::string token;  // empty: no token needed
  int max_clients = 64;
  int max_subscriptions = 32;  // over all clients
  int max_queue = 64;          // requests waiting for the world thread
  std::int64_t max_image_pixels = 4096 * 4096;
  std::size_t max_pending_bytes = 64u << 20;  // unread output per client (docs/RELIABILITY.md)
  Timeouts socket_timeouts{10.0, 300.0};

  bool modbus_enabled = true;
  ListenConfig modbus{"127.0.0.1", 1502};
  std::vector<std::string> modbus_allow{"127.0.0.1"};  // client addresses; "*" allows all
  std::string modbus_view;  // the view the holding registers steer; default the first
  int modbus_max_clients = 16;
  Timeouts modbus_timeouts{2.0, 300.0};

  bool metrics_enabled = false;
  ListenConfig metrics{"127.0.0.1", 9464};

  std::string snapshot_path;          // empty: no snapshots
  double snapshot_interval_s = 60.0;  // 0: only at shutdown
  bool restore_on_start = true;
  // A snapshot at start that does not read: exit naming the file and the field (the default),
  // or move it aside (PATH.rejected) and start from the scene (`on_error = "start_fresh"`).
  enum class SnapshotOnError { kExit, kStartFresh } snapshot_on_error = SnapshotOnError::kExit;
  std::string snapshot_directory;  // for the snapshot/restore requests; empty: beside the path
  // Where named snapshots go: snapshot_directory, else the snapshot path's directory.
  std::string snapshotDirectory() const {
    return snapshot_directory.empty() ? std::filesystem::path(snapshot_path).parent_path().string()
                                      : snapshot_directory;
  }

  CigiConfig cigi;
  // [site]: where the database origin lies on the Earth. None: a CIGI host's first position sets
  // it, and the sun of a date given without a place is at 0 N 0 E.
  std::optional<Site> site;
  std::vector<EntityType> entity_types;  // [[entity_type]]: targets by CIGI type or name
  std::vector<command::Stream> streams;  // [[stream]]: views streamed from the start

  std::string output_directory = "frames";  // images written by the Modbus render coil
  ImageFormat output_format = ImageFormat::kPng;
  EncodeOptions encode;
};

struct DaemonLimits {
  static constexpr double kMinTickRate = 0.1, kMaxTickRate = 1000.0;
  static constexpr int kMaxViews = 64;
  static constexpr int kMaxClients = 4096;
  static constexpr double kMinRequestTimeout = 0.05, kMaxRequestTimeout = 3600.0;
  static constexpr double kMaxIdleTimeout = 7 * 86400.0;
};

std::string loadDaemonConfig(const std::string& path, DaemonConfig& out);
std::string parseDaemonConfig(std::string_view text, const std::string& source_name,
                              DaemonConfig& out);

}  // namespace nephele
