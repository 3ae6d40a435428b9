// World snapshots: a header (magic, format version, payload length, XXH3 of the payload)
// and a payload holding the scene at time 0, the dynamics, the time and each automaton's last
// two states. Numbers are stored as their little-endian bytes (bit-exact doubles).
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <bit>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <type_traits>

#include <xxhash.h>

#include "world/file_output.h"
#include "world/formations/cloud_field.h"
#include "world/limits.h"
#include "world/world.h"

namespace nephele {
namespace {

static_assert(std::endian::native == std::endian::little, "snapshots assume a little-endian host");

constexpr char kMagic[8] = {'N', 'E', 'P', 'H', 'S', 'N', 'A', 'P'};
constexpr std::uint32_t kFormatVersion = 13;
constexpr std::size_t kHeaderBytes = sizeof kMagic + 4 + 8 + 8;

class Writer {
 public:
  std::vector<std::uint8_t> bytes;
  template <class T>
  void raw(T& v) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
    bytes.insert(bytes.end(), p, p + sizeof(T));
  }
  // Writes the count; the caller then visits `count` elements.
  std::size_t count(std::size_t n, std::size_t /*min_bytes*/) {
    std::uint64_t v = n;
    raw(v);
    return n;
  }
  void fail(const std::string&) {}
  static constexpr bool kReading = false;
};

class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> data) : data_(data) {}
  bool ok() const { return error_.empty(); }
  const std::string& error() const { return error_; }
  std::size_t remaining() const { return data_.size() - pos_; }
  template <class T>
  void raw(T& v) {
    if (!ok()) return;
    if (remaining() < sizeof(T)) return fail("payload ends early");
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
  }
  // Reads a count and refuses one that cannot fit in what is left.
  std::size_t count(std::size_t /*n*/, std::size_t min_bytes) {
    std::uint64_t v = 0;
    raw(v);
    if (ok() && v > remaining() / std::max<std::size_t>(min_bytes, 1))
      fail("a list claims " + std::to_string(v) + " entries, more than the payload holds");
    return ok() ? std::size_t(v) : 0;
  }
  void fail(const std::string& message) {
    if (error_.empty()) error_ = message;
  }
  static constexpr bool kReading = true;

 private:
  std::span<const std::uint8_t> data_;
  std::size_t pos_ = 0;
  std::string error_;
};

template <class A, class T>
requires std::is_arithmetic_v<T>
void io(A& a, T& v) {
  a.raw(v);
}
template <class A>
void io(A& a, bool& v) {
  std::uint8_t b = v;
  a.raw(b);
  if (b > 1) a.fail("a flag holds " + std::to_string(b));
  v = b != 0;
}
template <class A, class E>
requires std::is_enum_v<E>
void ioEnum(A& a, E& e, int count) {
  std::int32_t v = std::int32_t(e);
  a.raw(v);
  if (v < 0 || v >= count) a.fail("an enumeration holds " + std::to_string(v));
  e = E(v);
}
template <class A>
void io(A& a, std::string& s) {
  const std::size_t n = a.count(s.size(), 1);
  if (A::kReading) s.assign(n, '\0');
  for (char& c : s) a.raw(c);
}
template <class A, int N, class T>
void io(A& a, glm::vec<N, T, glm::defaultp>& v) {
  for (int i = 0; i < N; ++i) a.raw(v[i]);
}
template <class A, class T>
void io(A& a, std::vector<T>& list, std::size_t min_bytes = 1) {
  const std::size_t n = a.count(list.size(), min_bytes);
  if (A::kReading) list.resize(n);
  for (T& item : list) io(a, item);
}
template <class A>
void io(A& a, Orientation& o) {
  io(a, o.heading_deg), io(a, o.pitch_deg), io(a, o.roll_deg);
}
template <class A>
void io(A& a, Camera& c) {
  io(a, c.position), io(a, c.orientation), io(a, c.vfov_deg), io(a, c.width), io(a, c.height);
}
template <class A>
void io(A& a, Sun& s) {
  io(a, s.azimuth_deg), io(a, s.elevation_deg), io(a, s.colour);
}
template <class A>
void io(A& a, Sky& s) {
  io(a, s.zenith), io(a, s.horizon), io(a, s.ground);
}
template <class A>
void io(A& a, std::optional<Fog>& fog) {
  bool present = fog.has_value();
  io(a, present);
  if (!present) return fog.reset();
  if (!fog) fog.emplace();
  io(a, fog->top_m), io(a, fog->visibility_m), io(a, fog->colour);
}
template <class A>
void io(A& a, std::optional<Haze>& haze) {
  bool present = haze.has_value();
  io(a, present);
  if (!present) return haze.reset();
  if (!haze) haze.emplace();
  io(a, haze->visibility_m), io(a, haze->scale_height_m);
  if (!Limits::kHazeVisibility.contains(haze->visibility_m) ||
      !Limits::kHazeScaleHeight.contains(haze->scale_height_m))
    a.fail("haze out of range");
}
template <class A>
void io(A& a, WaveTrain& t) {
  io(a, t.id), io(a, t.height_m), io(a, t.wavelength_m), io(a, t.period_s), io(a, t.direction_deg);
  io(a, t.phase_deg);
}
template <class A>
void io(A& a, std::optional<Sea>& sea) {
  bool present = sea.has_value();
  io(a, present);
  if (!present) return sea.reset();
  if (!sea) sea.emplace();
  io(a, sea->wind), io(a, sea->fetch_m), io(a, sea->temperature_c), io(a, sea->clarity);
  io(a, sea->whitecaps), io(a, sea->trains, 44), io(a, sea->seed), io(a, sea->origin_m);
  if (std::string e = seaError(*sea); !e.empty()) a.fail("sea: " + e);
}
template <class A>
void io(A& a, ShadingParams& s) {
  io(a, s.ambient), io(a, s.texture_fraction), io(a, s.specular), io(a, s.shininess);
}
template <class A>
void io(A& a, GardnerTextureParams& g) {
  io(a, g.terms), io(a, g.fx1), io(a, g.fy1), io(a, g.t0), io(a, g.seeded_phases), io(a, g.seed);
  io(a, g.rotation_deg), io(a, g.jitter_octaves), io(a, g.amplitude_ratio);
  if (g.terms < 1 || g.terms > GardnerTextureParams::kMaxTerms)
    a.fail("texture terms out of range");
  if (!Limits::kAmplitudeRatio.contains(g.amplitude_ratio))
    a.fail("texture amplitude ratio out of range");
}
template <class A>
void io(A& a, LayerTextureSpec& t) {
  ioEnum(a, t.source, 3);
  io(a, t.gardner);
  NoiseTableParams& n = t.table;
  io(a, n.tile_size_m), io(a, n.size_log2), io(a, n.roughness), io(a, n.cells), io(a, n.octaves);
  io(a, n.persistence), io(a, t.seed), io(a, t.drift_velocity), io(a, t.drift_offset_m);
}
template <class A>
void io(A& a, Region& r) {
  io(a, r.centre), io(a, r.half_size), io(a, r.heading_deg), io(a, r.edge_m), io(a, r.side);
  io(a, r.transition_m);
}
template <class A>
void io(A& a, ClusterVariation& v) {
  io(a, v.spacing_m), io(a, v.amount);
}
// A layer's or field's region lies in the frame its texture or heaps drift in, which the wind
// carries without bound (MODEL.md section 11): its centre there may be any finite number, and
// the rest of the region is checked as a request's is.
Region checkedInDriftingFrame(Region r) {
  if (std::isfinite(r.centre.x) && std::isfinite(r.centre.y)) r.centre = glm::dvec2(0.0);
  return r;
}

template <class A>
void io(A& a, CloudLayer& l) {
  io(a, l.name), io(a, l.altitude_m), io(a, l.colour), io(a, l.threshold), io(a, l.transition);
  io(a, l.shading), io(a, l.texture), io(a, l.region);
  io(a, l.in_layer.top_m), io(a, l.in_layer.band_m), io(a, l.in_layer.visibility_m);
  if (std::string e = regionError(checkedInDriftingFrame(l.region)); !e.empty())
    a.fail("layer " + l.name + ": " + e);
}
template <class A>
void io(A& a, SolidTextureSpec& t) {
  ioEnum(a, t.source, 2);
  io(a, t.gardner), io(a, t.perlin_period_m), io(a, t.perlin_size_log2), io(a, t.perlin_cells);
  io(a, t.perlin_octaves), io(a, t.perlin_persistence), io(a, t.seed);
}
template <class A>
void io(A& a, Ellipsoid& e) {
  io(a, e.radii), io(a, e.centre), io(a, e.orientation);
}
template <class A>
void io(A& a, EllipsoidCloud& c) {
  io(a, c.name), io(a, c.colour), io(a, c.threshold_centre), io(a, c.threshold_limb);
  io(a, c.transition), io(a, c.shading), io(a, c.light_extinction), io(a, c.texture),
      io(a, c.ellipsoids, 72), io(a, c.drift_m);
  if (!Limits::kLightExtinction.contains(c.light_extinction))
    a.fail("cloud " + c.name + ": light_extinction out of range");
}
template <class A>
void io(A& a, std::array<std::uint32_t, 3>& triangle) {
  for (std::uint32_t& v : triangle) a.raw(v);
}
template <class A>
void io(A& a, Target& t) {
  io(a, t.name);
  ioEnum(a, t.shape, 3);
  io(a, t.centre), io(a, t.orientation), io(a, t.size), io(a, t.colour);
  bool has_mesh = t.mesh != nullptr;
  io(a, has_mesh);
  if (!has_mesh) return t.mesh.reset();
  TriangleMesh mesh = t.mesh ? *t.mesh : TriangleMesh{};
  io(a, mesh.vertices, 24), io(a, mesh.triangles, 12);
  for (const auto& triangle : mesh.triangles)
    for (std::uint32_t v : triangle)
      if (v >= mesh.vertices.size())
        a.fail("target " + t.name + ": a triangle names a missing vertex");
  if (A::kReading) t.mesh = std::make_shared<const TriangleMesh>(std::move(mesh));
}
template <class A>
void io(A& a, CloudField& f) {
  io(a, f.name);
  ioEnum(a, f.type, kCloudTypeCount);
  io(a, f.base_m), io(a, f.thickness_m), io(a, f.coverage), io(a, f.seed), io(a, f.drift_m);
  io(a, f.region), io(a, f.clusters);
  if (f.type != CloudType::kCumulus && f.type != CloudType::kCumulonimbus)
    a.fail("field " + f.name + ": not a convective cloud type");
  const WeatherLayer w{f.type,     f.base_m, f.thickness_m,
                       f.coverage, {},       checkedInDriftingFrame(f.region),
                       f.clusters};
  if (std::string e = weatherLayerError(w); !e.empty()) a.fail("field " + f.name + ": " + e);
}
// The weather layers as set: their clouds are written with the rest of the scene.
template <class A>
void io(A& a, std::map<WeatherKey, WeatherLayer>& weather) {
  const std::size_t n = a.count(weather.size(), 64);
  auto put = [&](WeatherKey key, WeatherLayer w) {
    io(a, key.layer);
    bool regional = key.region.has_value();
    std::uint16_t region = key.region.value_or(0);
    io(a, regional), io(a, region);
    if (regional) key.region = region;
    ioEnum(a, w.type, kCloudTypeCount);
    io(a, w.base_m), io(a, w.thickness_m), io(a, w.coverage);
    bool windy = w.wind.has_value();
    glm::dvec2 wind = w.wind.value_or(glm::dvec2(0.0));
    io(a, windy), io(a, wind);
    if (windy) w.wind = wind;
    io(a, w.region), io(a, w.clusters);
    io(a, w.visibility_m), io(a, w.transition_band_m), io(a, w.scud);
    ioEnum(a, w.precipitation.kind, kPrecipitationKindCount);
    io(a, w.precipitation.rate_mm_h), io(a, w.precipitation.visibility_m);
    if constexpr (!A::kReading) return;
    if (w.type == CloudType::kNone && w.precipitation.kind == PrecipitationKind::kNone)
      return a.fail("a weather layer of no type and no precipitation");
    if (std::string e = weatherLayerError(w); !e.empty()) return a.fail("weather layer: " + e);
    weather[key] = w;
  };
  if constexpr (A::kReading) {
    weather.clear();
    for (std::size_t i = 0; i < n && a.ok(); ++i) put({}, {});
  } else {
    for (const auto& [key, w] : weather) put(key, w);
  }
}
template <class A>
void io(A& a, Scene& s) {
  io(a, s.seed), io(a, s.camera), io(a, s.sun), io(a, s.sky), io(a, s.fog), io(a, s.haze);
  io(a, s.layers, 64), io(a, s.clouds, 64), io(a, s.targets, 64), io(a, s.fields, 64);
  io(a, s.weather), io(a, s.sea);
  bool placed = s.site.has_value();
  Site site = s.site.value_or(Site{});
  io(a, placed), io(a, site.latitude_deg), io(a, site.longitude_deg), io(a, site.grid_deg);
  io(a, s.content_origin);
  if constexpr (!A::kReading) return;
  if (!placed) return s.site.reset();
  if (std::string e = siteError(site); !e.empty()) return a.fail(e);
  if (!std::isfinite(s.content_origin.x) || !std::isfinite(s.content_origin.y))
    return a.fail("site: the content origin is not finite");
  s.site = site;
}
template <class A>
void io(A& a, Schedule& s) {
  io(a, s.times_s, 8), io(a, s.values, 8);
}
template <class A>
void io(A& a, WindSample& w) {
  io(a, w.altitude_m), io(a, w.velocity);
}
template <class A>
void io(A& a, LayerDevelopment& d) {
  io(a, d.threshold), io(a, d.transition), io(a, d.t0);
}
template <class A>
void io(A& a, CloudDevelopment& d) {
  io(a, d.threshold_centre), io(a, d.threshold_limb), io(a, d.transition);
}
template <class A>
void io(A& a, GridSize& g) {
  io(a, g.nx), io(a, g.ny), io(a, g.nz);
}
template <class A>
void io(A& a, ShapeEllipsoid& e) {
  io(a, e.centre), io(a, e.radii);
}
template <class A>
void io(A& a, AutomatonCloudSpec& s) {
  io(a, s.name), io(a, s.cells), io(a, s.cell_size_m), io(a, s.position), io(a, s.seed);
  io(a, s.step_interval_s), io(a, s.warmup_steps), io(a, s.humidity), io(a, s.activation);
  io(a, s.extinction), io(a, s.humidity_schedule), io(a, s.activation_schedule);
  io(a, s.extinction_schedule), io(a, s.shape, 48), io(a, s.colour), io(a, s.ambient);
  ioEnum(a, s.phase, 2);
  io(a, s.phase_u), io(a, s.samples_per_cell);
}
template <class A>
void io(A& a, WorldDynamics& d) {
  io(a, d.wind.samples, 24), io(a, d.layers, 48), io(a, d.clouds, 48), io(a, d.automata, 64);
}

// One automaton's last two states.
struct AutomatonState {
  std::uint64_t previous_steps = 0;
  std::vector<std::uint64_t> previous[3], current[3];
};
template <class A>
void io(A& a, AutomatonState& s) {
  io(a, s.previous_steps);
  for (auto& bits : s.previous) io(a, bits, 8);
  for (auto& bits : s.current) io(a, bits, 8);
}

std::uint64_t payloadHash(std::span<const std::uint8_t> payload) {
  return XXH3_64bits(payload.data(), payload.size());
}

}  // namespace

std::vector<std::uint8_t> World::snapshot() const {
  Writer w;
  Scene scene = base_;
  WorldDynamics dynamics = dynamics_;
  std::int64_t time_ns = time_ns_;
  io(w, scene), io(w, dynamics), io(w, time_ns);
  for (const AutomatonCloud& cloud : automata_) {
    AutomatonState state;
    state.previous_steps = cloud.previous().steps();
    for (int b = 0; b < 3; ++b) {
      state.previous[b] = cloud.previous().words(CellBit(b));
      state.current[b] = cloud.automaton().words(CellBit(b));
    }
    io(w, state);
  }
  std::vector<std::uint8_t> out(kMagic, kMagic + sizeof kMagic);
  auto append = [&out](auto v) {
    const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
    out.insert(out.end(), p, p + sizeof v);
  };
  append(kFormatVersion);
  append(std::uint64_t(w.bytes.size()));
  append(payloadHash(w.bytes));
  out.insert(out.end(), w.bytes.begin(), w.bytes.end());
  return out;
}

std::uint64_t World::hash() const {
  const std::vector<std::uint8_t> bytes = snapshot();
  return payloadHash(std::span(bytes).subspan(kHeaderBytes));
}

std::string World::restore(std::span<const std::uint8_t> bytes, std::size_t max_ellipsoids) {
  if (bytes.size() < kHeaderBytes || std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    return "snapshot: not a Nephele snapshot (bad magic or shorter than its header)";
  std::uint32_t version = 0;
  std::uint64_t length = 0, hash = 0;
  std::memcpy(&version, bytes.data() + 8, 4);
  std::memcpy(&length, bytes.data() + 12, 8);
  std::memcpy(&hash, bytes.data() + 20, 8);
  if (version != kFormatVersion)
    return "snapshot: format version " + std::to_string(version) + " (this build reads " +
           std::to_string(kFormatVersion) + ")";
  const std::span<const std::uint8_t> payload = bytes.subspan(kHeaderBytes);
  if (payload.size() != length)
    return "snapshot: truncated or padded: payload of " + std::to_string(payload.size()) +
           " bytes, header says " + std::to_string(length);
  if (payloadHash(payload) != hash) return "snapshot: corrupt (checksum mismatch)";

  Reader r(payload);
  Scene scene;
  WorldDynamics dynamics;
  std::int64_t time_ns = 0;
  io(r, scene), io(r, dynamics), io(r, time_ns);
  if (!r.ok()) return "snapshot: " + r.error();
  if (const std::size_t n = ellipsoidCount(scene); n > max_ellipsoids)
    return std::string(kOverBudget) + "its clouds hold " + std::to_string(n) +
           " ellipsoids, more than the " + std::to_string(max_ellipsoids) +
           " this world may hold ([world] max_ellipsoids)";
  if (std::string e = worldDynamicsError(scene, dynamics); !e.empty()) return "snapshot: " + e;
  for (const EllipsoidCloud& cloud : scene.clouds)
    for (const Ellipsoid& e : cloud.ellipsoids)
      if (std::string error = ellipsoidError(e); !error.empty())
        return "snapshot: cloud " + cloud.name + ": " + error;
  for (const Target& t : scene.targets)
    if (std::string e = placementError("target " + t.name, t.centre.x, t.centre.y, t.centre.z);
        !e.empty())
      return "snapshot: " + e;
  if (time_ns < 0) return "snapshot: negative time";

  World restored(scene, dynamics, threads_, false);
  restored.time_ns_ = time_ns;
  for (AutomatonCloud& cloud : restored.automata_) {
    AutomatonState s;
    io(r, s);
    if (!r.ok()) return "snapshot: " + r.error();
    const GridSize size = cloud.spec().cells;
    CellularAutomaton previous(size, cloud.spec().seed), current(size, cloud.spec().seed);
    if (!previous.restore(s.previous_steps, s.previous[0], s.previous[1], s.previous[2]) ||
        !current.restore(s.previous_steps + 1, s.current[0], s.current[1], s.current[2]) ||
        !cloud.restore(s.previous_steps, previous, current))
      return "snapshot: automaton " + cloud.spec().name + ": states do not fit its grid";
    if (std::int64_t(cloud.stepsSinceStart()) != time_ns / cloud.stepIntervalNs() + 1)
      return "snapshot: automaton " + cloud.spec().name + ": state does not match the time";
  }
  if (r.remaining() != 0) return "snapshot: " + std::to_string(r.remaining()) + " bytes left over";
  *this = std::move(restored);
  return {};
}

std::string World::saveSnapshot(const std::string& path, std::size_t max_ellipsoids) const {
  // Proven before it replaces the last one: the file written is read back by restore's own
  // reader, into a world of its own, and renamed into place only if it reads.
  return writeFileAtomically(path, snapshot(), "snapshot", [&](const std::string& written) {
    World probe(Scene{}, WorldDynamics{}, 1, false);
    return probe.restoreSnapshot(written, max_ellipsoids);
  });
}

std::string World::restoreSnapshot(const std::string& path, std::size_t max_ellipsoids) {
  // Opened without blocking (a FIFO would wait for a writer forever) and checked to be a
  // regular file (a directory, device or FIFO is refused), then read only as far as its
  // header promises: a large file of anything else costs one header read.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return "snapshot: cannot read " + path + ": " + std::strerror(errno);
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat info {};
  if (::fstat(fd, &info) != 0 || !S_ISREG(info.st_mode))
    return "snapshot: " + path + " is not a regular file";
  auto readFully = [&](std::uint8_t* out, std::size_t count) {
    while (count > 0) {
      const ssize_t got = ::read(fd, out, count);
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) return false;
      out += got, count -= std::size_t(got);
    }
    return true;
  };
  std::vector<std::uint8_t> bytes(kHeaderBytes);
  if (std::uint64_t(info.st_size) < kHeaderBytes || !readFully(bytes.data(), kHeaderBytes) ||
      std::memcmp(bytes.data(), kMagic, sizeof kMagic) != 0)
    return "snapshot: " + path +
           " is not a Nephele snapshot (bad magic or shorter than its header)";
  std::uint64_t length = 0;
  std::memcpy(&length, bytes.data() + 12, 8);
  if (length != std::uint64_t(info.st_size) - kHeaderBytes)
    return "snapshot: " + path + " is " + std::to_string(info.st_size) +
           " bytes, its header promises " + std::to_string(length + kHeaderBytes);
  bytes.resize(kHeaderBytes + length);
  if (!readFully(bytes.data() + kHeaderBytes, length))
    return "snapshot: cannot read " + path + ": " + std::strerror(errno);
  return restore(bytes, max_ellipsoids);
}

}  // namespace nephele
