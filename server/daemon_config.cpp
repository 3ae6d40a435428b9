#include "server/daemon_config.h"

#include <unistd.h>

#include <algorithm>
#include <filesystem>

#include "config/table_reader.h"

namespace nephele {
namespace {

using config_detail::SceneError;
using config_detail::TableReader;

void readListen(TableReader& t, ListenConfig& listen) {
  t.string("bind", listen.bind);
  t.integer("port", listen.port, 0, 65535);
}

void readTimeouts(TableReader& t, Timeouts& timeouts) {
  t.number("request_timeout", timeouts.request_s, DaemonLimits::kMinRequestTimeout,
           DaemonLimits::kMaxRequestTimeout);
  t.number("idle_timeout", timeouts.idle_s, 0.0, DaemonLimits::kMaxIdleTimeout);
}

void readView(TableReader& t, const Camera& scene_camera, ViewConfig& view) {
  t.allow({"name", "position", "heading", "pitch", "roll", "vfov", "width", "height", "format",
           "coverage"});
  view.camera = scene_camera;
  t.name("name", view.name);
  Camera& c = view.camera;
  config_detail::readCameraKeys(t, c);
  t.integer("width", c.width, 1, Limits::kMaxImageSide);
  t.integer("height", c.height, 1, Limits::kMaxImageSide);
  view.image.format =
      ImageFormat(t.choice("format", {"raw", "png", "jpeg", "exr"}, int(view.image.format)));
  view.image.coverage = defaultCoverage(view.image.format);
  t.boolean("coverage", view.image.coverage);
  if (view.image.format == ImageFormat::kJpeg) {
    if (t.has("coverage") && view.image.coverage)
      t.failAt("coverage", "jpeg holds colour only (allowed with jpeg: false)");
    view.image.coverage = false;
  }
  if (view.name.empty()) t.failHere("missing key name (a name for requests, e.g. \"front\")");
  t.finish();
}

// The scene file (relative to the config's directory), loaded.
void readSceneKey(TableReader& t, const std::string& file, DaemonConfig& out) {
  if (!t.has("scene")) t.failHere("missing key scene (the scene file to load)");
  t.string("scene", out.scene_path);
  const std::filesystem::path scene(out.scene_path);
  if (scene.is_relative())
    out.scene_path =
        (std::filesystem::path(file).parent_path() / scene).lexically_normal().string();
  if (std::string error = loadSceneFile(out.scene_path, out.scene); !error.empty())
    t.failAt("scene", error);
}

// [world], and the scene's clouds checked against its ellipsoid budget.
void readWorld(TableReader& t, DaemonConfig& out) {
  if (auto w = t.table("world")) {
    w->allow({"mode", "tick_rate", "time_scale", "threads", "max_ellipsoids", "prewarm"});
    out.mode = TickMode(w->choice("mode", {"realtime", "lockstep"}, int(out.mode)));
    w->number("tick_rate", out.tick_rate_hz, DaemonLimits::kMinTickRate,
              DaemonLimits::kMaxTickRate);
    w->number("time_scale", out.time_scale, 0.0, ProtocolLimits::kMaxTimeScale);
    w->integer("threads", out.world_threads, 1, 64);
    w->integer("max_ellipsoids", out.max_ellipsoids, 1, Limits::kMaxWorldEllipsoids);
    w->boolean("prewarm", out.prewarm);
    w->finish();
  }
  if (const std::size_t n = ellipsoidCount(out.scene.scene); n > std::size_t(out.max_ellipsoids))
    t.failAt("scene", "its clouds hold " + std::to_string(n) + " ellipsoids, more than the " +
                          "world's budget of " + std::to_string(out.max_ellipsoids) +
                          " ([world] max_ellipsoids)");
}

// [[view]]: at most kMaxViews, each named once; none: the scene's camera, named main.
void readViews(TableReader& t, DaemonConfig& out) {
  std::vector<TableReader> views = t.tables("view");
  if (views.size() > std::size_t(DaemonLimits::kMaxViews))
    t.failAt("view", "more than " + std::to_string(DaemonLimits::kMaxViews) + " views");
  for (TableReader& v : views) {
    ViewConfig& view = out.views.emplace_back();
    readView(v, out.scene.scene.camera, view);
    for (std::size_t i = 0; i + 1 < out.views.size(); ++i)
      if (out.views[i].name == view.name) v.failAt("name", "\"" + view.name + "\" names two views");
  }
  if (out.views.empty()) out.views.push_back({"main", out.scene.scene.camera, {}, {}});
}

void readSocket(TableReader& t, DaemonConfig& out) {
  if (auto s = t.table("socket")) {
    s->allow({"enabled", "bind", "port", "token", "max_clients", "max_subscriptions", "max_queue",
              "max_image_pixels", "max_pending_mb", "request_timeout", "idle_timeout"});
    s->boolean("enabled", out.socket_enabled);
    readListen(*s, out.socket);
    s->string("token", out.token);
    s->integer("max_clients", out.max_clients, 1, DaemonLimits::kMaxClients);
    s->integer("max_subscriptions", out.max_subscriptions, 0, 4096);
    s->integer("max_queue", out.max_queue, 1, 65536);
    // In mebipixels; a fraction bounds a small machine's frames tighter (the live fuzz runs
    // under 0.0625, so that a lockstep tick's renders fit its 5 s reply bound on two cores).
    double pixels_m = double(out.max_image_pixels) / double(1 << 20);
    s->number("max_image_pixels", pixels_m, 0.01, 256.0);
    out.max_image_pixels = std::int64_t(pixels_m * double(1 << 20));
    int pending_mb = int(out.max_pending_bytes >> 20);
    s->integer("max_pending_mb", pending_mb, 1, 4096);
    out.max_pending_bytes = std::size_t(pending_mb) << 20;
    readTimeouts(*s, out.socket_timeouts);
    s->finish();
  }
}

// [modbus], and the view its registers drive (the first, unless it names one).
void readModbus(TableReader& t, DaemonConfig& out) {
  if (auto m = t.table("modbus")) {
    m->allow({"enabled", "bind", "port", "allow", "view", "max_clients", "request_timeout",
              "idle_timeout"});
    m->boolean("enabled", out.modbus_enabled);
    readListen(*m, out.modbus);
    if (m->has("allow")) {
      out.modbus_allow.clear();
      m->strings("allow", out.modbus_allow, 256);
    }
    m->string("view", out.modbus_view);
    m->integer("max_clients", out.modbus_max_clients, 1, 256);
    readTimeouts(*m, out.modbus_timeouts);
    m->finish();
  }
  if (out.modbus_view.empty())
    out.modbus_view = out.views.front().name;
  else if (std::none_of(out.views.begin(), out.views.end(),
                        [&](const ViewConfig& v) { return v.name == out.modbus_view; }))
    t.failHere("modbus.view: \"" + out.modbus_view + "\" is not a view");
}

// [cigi]; the views a host's view ids index are every [[view]] unless it names them.
void readCigi(TableReader& t, DaemonConfig& out) {
  if (auto c = t.table("cigi")) {
    c->allow({"enabled", "bind", "ig_port", "host_port", "views", "recentre_distance"});
    c->boolean("enabled", out.cigi.enabled);
    c->number("recentre_distance", out.cigi.recentre_distance_m, Limits::kRecentreDistance);
    if (out.cigi.recentre_distance_m > 0.0 &&
        out.cigi.recentre_distance_m < Limits::kMinRecentreDistance)
      c->failAt("recentre_distance",
                "is below " + std::to_string(int(Limits::kMinRecentreDistance)) +
                    " m (allowed: 0 for never, or " +
                    std::to_string(int(Limits::kMinRecentreDistance)) + " to 1e6 m)");
    c->string("bind", out.cigi.bind);
    c->integer("ig_port", out.cigi.ig_port, 0, 65535);
    c->integer("host_port", out.cigi.host_port, 0, 65535);
    if (c->has("views")) {
      c->strings("views", out.cigi.views, DaemonLimits::kMaxViews);
      for (const std::string& name : out.cigi.views)
        if (std::none_of(out.views.begin(), out.views.end(),
                         [&](const ViewConfig& v) { return v.name == name; }))
          c->failAt("views", "\"" + name + "\" is not a [[view]]");
    }
    c->finish();
  }
  if (out.cigi.views.empty())
    for (const ViewConfig& v : out.views) out.cigi.views.push_back(v.name);
}

void readSite(TableReader& t, DaemonConfig& out) {
  if (auto s = t.table("site")) {
    s->allow({"latitude", "longitude"});
    Site& site = out.site.emplace();
    s->number("latitude", site.latitude_deg, Limits::kLatitude);
    s->number("longitude", site.longitude_deg, Limits::kLongitude);
    s->finish();
  }
}

// [[entity_type]]: the targets a CIGI entity type is drawn as, each id and name once.
void readEntityTypes(TableReader& t, const std::string& file, DaemonConfig& out) {
  for (TableReader& e : t.tables("entity_type")) {
    EntityType& type = out.entity_types.emplace_back();
    if (!e.has("id")) e.failHere("missing key id (the CIGI entity type, 0 to 65535)");
    e.integer("id", type.id, 0, 65535);
    readTarget(e, file, type.prototype, {"id"});
    type.name = type.prototype.name;
    if (type.name.empty()) e.failHere("missing key name (how requests name this type)");
    for (std::size_t i = 0; i + 1 < out.entity_types.size(); ++i)
      if (out.entity_types[i].id == type.id || out.entity_types[i].name == type.name)
        e.failAt("id", "entity type " + std::to_string(type.id) + " \"" + type.name +
                           "\" repeats an earlier id or name");
    e.finish();
  }
}

// [[stream]]: video of a [[view]], at most kMaxStreams.
void readStreams(TableReader& t, DaemonConfig& out) {
  for (TableReader& r : t.tables("stream")) {
    r.allow({"view", "address", "bitrate", "rate", "keyframe_interval", "encoder", "stamp"});
    command::Stream& c = out.streams.emplace_back();
    using L = VideoStreamLimits;
    if (!r.has("view")) r.failHere("missing key view (the [[view]] to stream)");
    if (!r.has("address")) r.failHere("missing key address (udp://host:port, srt:// or rtp://)");
    r.string("view", c.view);
    if (std::none_of(out.views.begin(), out.views.end(),
                     [&](const ViewConfig& v) { return v.name == c.view; }))
      r.failAt("view", "\"" + c.view + "\" is not a [[view]]");
    VideoStreamSettings& v = c.settings;
    r.string("address", v.address);
    r.integer("bitrate", v.bitrate_kbps, L::kMinKbps, L::kMaxKbps);
    r.number("rate", v.rate_hz, L::kMinRate, L::kMaxRate);
    r.integer("keyframe_interval", v.keyframe_interval, 1, L::kMaxKeyframeInterval);
    r.string("encoder", v.encoder);
    r.boolean("stamp", v.stamp);
    if (std::string e = videoStreamSettingsError(v); !e.empty())
      r.failAt(e.substr(0, e.find(':')), e.substr(e.find(':') + 2));
    if (out.streams.size() > std::size_t(ProtocolLimits::kMaxStreams))
      r.failHere("more than " + std::to_string(ProtocolLimits::kMaxStreams) + " streams");
    r.finish();
  }
}

void readSnapshot(TableReader& t, DaemonConfig& out) {
  if (auto s = t.table("snapshot")) {
    s->allow({"path", "interval", "restore", "directory", "on_error"});
    s->string("path", out.snapshot_path);
    s->number("interval", out.snapshot_interval_s, 0.0, 86400.0);
    s->boolean("restore", out.restore_on_start);
    out.snapshot_on_error = DaemonConfig::SnapshotOnError(
        s->choice("on_error", {"exit", "start_fresh"}, int(out.snapshot_on_error)));
    s->string("directory", out.snapshot_directory);
    s->finish();
  }
}

// [output]: where and how rendered files are written (raw frames are for the socket).
void readOutput(TableReader& t, DaemonConfig& out) {
  if (auto o = t.table("output")) {
    o->allow({"directory", "format", "png_compression", "jpeg_quality"});
    o->string("directory", out.output_directory);
    out.output_format =
        ImageFormat(o->choice("format", {"raw", "png", "jpeg", "exr"}, int(out.output_format)));
    if (out.output_format == ImageFormat::kRaw)
      o->failAt("format", "raw frames are for the socket (allowed here: png, jpeg, exr)");
    o->integer("png_compression", out.encode.png_compression, 0, 9);
    o->integer("jpeg_quality", out.encode.jpeg_quality, 1, 100);
    o->finish();
  }
}

void readDaemon(const toml::table& root, const std::string& file, DaemonConfig& out) {
  TableReader t(root, "", file);
  t.allow({"scene", "world", "view", "socket", "modbus", "metrics", "snapshot", "output", "cigi",
           "stream", "site", "entity_type"});
  readSceneKey(t, file, out);
  readWorld(t, out);
  readViews(t, out);
  readSocket(t, out);
  readModbus(t, out);
  readCigi(t, out);
  readSite(t, out);
  readEntityTypes(t, file, out);
  readStreams(t, out);
  if (auto m = t.table("metrics")) {
    m->allow({"enabled", "bind", "port"});
    m->boolean("enabled", out.metrics_enabled);
    readListen(*m, out.metrics);
    m->finish();
  }
  readSnapshot(t, out);
  readOutput(t, out);
  t.finish();
}

}  // namespace

std::string parseDaemonConfig(std::string_view text, const std::string& source_name,
                              DaemonConfig& out) {
  DaemonConfig parsed;
  parsed.config_path = source_name;
  try {
    const toml::table root = config_detail::parseToml(text, source_name);
    readDaemon(root, source_name, parsed);
  } catch (const SceneError& e) {
    return e.message;
  }
  out = std::move(parsed);
  return "";
}

int defaultMaxEllipsoids() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  const double bytes = pages > 0 && page > 0 ? double(pages) * double(page) : 4.0 * (1 << 30);
  return int(std::clamp(0.25 * bytes / Limits::kBytesPerEllipsoid, 65536.0,
                        double(Limits::kMaxWorldEllipsoids)));
}

std::string loadDaemonConfig(const std::string& path, DaemonConfig& out) {
  std::string text;
  if (std::string error = config_detail::readTextFile(path, "config file", text); !error.empty())
    return error;
  return parseDaemonConfig(text, path, out);
}

}  // namespace nephele
