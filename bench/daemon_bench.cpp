// daemon_bench: starts the real `nephele serve` and measures what a host simulator sees.
//   1. request-to-last-byte latency of a 640x480 frame, raw RGBA and PNG;
//   2. Modbus write-to-visible latency: from a holding-register write (heading) to the first
//      subscribed frame that shows it;
//   3. frames per second delivered to 1, 4 and 16 subscribers at the 60 Hz maximum;
//   4. host frames in lockstep (issue 16): a CIGI host frame (IG Control and the ownship's
//      Entity Control) to Start of Frame and to every subscribed view's frame delivered, and
//      the same for the socket protocol's tick, with one and three 640x480 raw views; as
//      multiples of the render time alone (the daemon's own render p50 times the views) and
//      of the platform floor (one constant-colour pass and readback, timed here);
//   5. host frames in asynchronous (realtime) mode, where Start of Frame comes at the IG's own
//      rate: from a host frame to the first Start of Frame reporting it and to frames showing it;
//   6. the same lockstep host frames with a cumulus sky (genus_cumulus.toml) against a clear
//      sky, as multiples of the clear sky's (issue 27);
//   7. with --heavy, alone: worlds grown by legal requests to the world budget (issue 31):
//      render times at 64x48 and 640x480 as multiples of the clear frame, memory, `hello`
//      waits during the renders, and SIGTERM during the largest.
// Figures only; these machines are shared and noisy.
#include <arpa/inet.h>
#include <fcntl.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "protocol/cigi.h"
#include "renderer/frame_timing.h"
#include "renderer/renderer.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;
using nephele::millisecondsBetween;
using nephele::percentile;
using nlohmann::json;

// The daemon as a child process; the ports come from its ready line.
struct Daemon {
  pid_t pid = 0;
  int socket_port = 0, modbus_port = 0, metrics_port = 0, cigi_port = 0;

  explicit Daemon(const std::string& config) {
    int out[2];
    if (pipe(out)) throw std::runtime_error("pipe");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, out[1], STDOUT_FILENO);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
    std::string binary = NEPHELE_BINARY;
    char* argv[] = {binary.data(), const_cast<char*>("serve"), const_cast<char*>("-c"),
                    const_cast<char*>(config.c_str()), nullptr};
    if (posix_spawn(&pid, binary.c_str(), &actions, nullptr, argv, environ))
      throw std::runtime_error("cannot start " + binary);
    close(out[1]);
    std::string line;
    char c;
    while (read(out[0], &c, 1) == 1 && c != '\n') line += c;
    close(out[0]);
    if (std::sscanf(line.c_str(), "nephele ready socket=%d modbus=%d metrics=%d cigi=%d",
                    &socket_port, &modbus_port, &metrics_port, &cigi_port) != 4)
      throw std::runtime_error("the daemon did not start: " + line);
  }
  ~Daemon() {
    if (pid == 0) return;
    kill(pid, SIGTERM);
    waitpid(pid, nullptr, 0);
  }
};

// A blocking client of the socket protocol.
class Client {
 public:
  explicit Client(int port) {
    fd_ = socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(std::uint16_t(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a))
      throw std::runtime_error("connect");
    int one = 1;
    setsockopt(fd_, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  }
  ~Client() { close(fd_); }

  void send(const json& request) {
    const std::string line = request.dump() + "\n";
    if (write(fd_, line.data(), line.size()) != ssize_t(line.size()))
      throw std::runtime_error("write");
  }
  // One reply or event; image bytes go into `body`.
  json receive(std::vector<std::uint8_t>& body) {
    std::string line;
    for (;;) {
      const auto nl = std::find(buffer_.begin(), buffer_.end(), '\n');
      if (nl != buffer_.end()) {
        line.assign(buffer_.begin(), nl);
        buffer_.erase(buffer_.begin(), nl + 1);
        break;
      }
      fill();
    }
    json header = json::parse(line);
    const json* image = header.contains("image") ? &header["image"]
                        : header.contains("result") && header["result"].contains("image")
                            ? &header["result"]["image"]
                            : nullptr;
    body.clear();
    if (image) {
      const std::size_t n = (*image)["bytes"];
      while (buffer_.size() < n) fill();
      body.assign(buffer_.begin(), buffer_.begin() + std::ptrdiff_t(n));
      buffer_.erase(buffer_.begin(), buffer_.begin() + std::ptrdiff_t(n));
    }
    return header;
  }
  json request(const json& r, std::vector<std::uint8_t>& body) {
    send(r);
    return receive(body);
  }

 private:
  void fill() {
    char chunk[1 << 16];
    const ssize_t n = read(fd_, chunk, sizeof chunk);
    if (n <= 0) throw std::runtime_error("connection closed");
    buffer_.insert(buffer_.end(), chunk, chunk + n);
  }
  int fd_;
  std::vector<char> buffer_;
};

std::string writeConfig(const std::filesystem::path& dir) {
  const std::string path = (dir / "bench.toml").string();
  std::ofstream(path) << "scene = \"" << NEPHELE_SOURCE_DIR
                      << "/config/scenes/cumulus.toml\"\n"
                         "[world]\ntick_rate = 60\n"
                         "[[view]]\nname = \"front\"\nwidth = 640\nheight = 480\n"
                         "[socket]\nport = 0\nmax_subscriptions = 64\n"
                         "[modbus]\nport = 0\n"
                         "[output]\ndirectory = \""
                      << (dir / "frames").string() << "\"\n";
  return path;
}

void latency(Client& client, const char* format, int repeats) {
  std::vector<double> ms;
  std::vector<std::uint8_t> body;
  std::size_t bytes = 0;
  for (int i = 0; i < repeats + 3; ++i) {
    const auto t0 = Clock::now();
    json reply =
        client.request({{"id", i}, {"cmd", "render"}, {"view", "front"}, {"format", format}}, body);
    const auto t1 = Clock::now();
    if (!reply["ok"]) throw std::runtime_error(reply.dump());
    if (i >= 3) ms.push_back(millisecondsBetween(t0, t1));  // after the warm-up
    bytes = body.size();
  }
  std::printf("render %-4s 640x480: p50 %6.2f ms  p99 %6.2f ms  (%zu bytes, %d requests)\n", format,
              percentile(ms, 0.5), percentile(ms, 0.99), bytes, repeats);
}

// Mean coverage of a raw RGBA frame.
double meanCoverage(const std::vector<std::uint8_t>& rgba) {
  double sum = 0.0;
  for (std::size_t i = 3; i < rgba.size(); i += 4) sum += rgba[i];
  return sum / double(rgba.size() / 4) / 255.0;
}

void modbusLatency(const Daemon& daemon, int repeats) {
  modbus_t* mb = modbus_new_tcp("127.0.0.1", daemon.modbus_port);
  if (modbus_connect(mb)) throw std::runtime_error("modbus connect");
  Client sub(daemon.socket_port);
  std::vector<std::uint8_t> body;
  sub.request({{"cmd", "subscribe"}, {"view", "front"}, {"rate", 60}}, body);
  std::vector<double> ms;
  for (int i = 0; i < repeats; ++i) {
    const float heading = i % 2 ? 0.0f : 180.0f;  // towards the cloud, or away from it
    std::uint32_t bits;
    std::memcpy(&bits, &heading, 4);
    std::uint16_t words[2] = {std::uint16_t(bits >> 16), std::uint16_t(bits & 0xffff)};  // ABCD
    const auto t0 = Clock::now();
    if (modbus_write_registers(mb, 6, 2, words) != 2) throw std::runtime_error("modbus write");
    for (;;) {  // the first frame rendered after the write that shows the new heading
      json event = sub.receive(body);
      if (event.value("event", "") != "frame") continue;
      if ((meanCoverage(body) > 0.01) == (heading == 0.0f)) break;
    }
    ms.push_back(millisecondsBetween(t0, Clock::now()));
  }
  std::printf(
      "modbus write to visible frame (60 Hz subscription, 640x480 raw): p50 %.1f ms  "
      "p99 %.1f ms  (%d writes)\n",
      percentile(ms, 0.5), percentile(ms, 0.99), repeats);
  modbus_close(mb);
  modbus_free(mb);
}

void subscribers(const Daemon& daemon, int count, double seconds) {
  std::atomic<bool> stop{false};
  std::vector<int> frames(std::size_t(count), 0);
  std::vector<std::thread> threads;
  for (int i = 0; i < count; ++i)
    threads.emplace_back([&, i] {
      Client c(daemon.socket_port);
      std::vector<std::uint8_t> body;
      c.request({{"cmd", "subscribe"}, {"view", "front"}, {"rate", 60}}, body);
      while (!stop)
        if (c.receive(body).value("event", "") == "frame") ++frames[std::size_t(i)];
    });
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  stop = true;
  for (auto& t : threads) t.join();  // each sees one more frame within 1/60 s and stops
  double total = 0.0;
  for (int f : frames) total += f;
  std::printf(
      "%2d subscribers, 640x480 raw at 60 Hz asked: %5.1f fps each (mean), %6.1f fps "
      "delivered in all\n",
      count, total / count / seconds, total / seconds);
}

// A daemon (`mode` lockstep or realtime) on `scene` with three 640x480 raw views and CIGI
// answering to `host_port`.
std::string writeHostConfig(const std::filesystem::path& dir, int host_port,
                            const std::string& scene, const char* mode = "lockstep") {
  const std::string path = (dir / "host.toml").string();
  std::ofstream out(path);
  out << "scene = \"" << scene << "\"\n"
      << "[world]\nmode = \"" << mode << "\"\ntick_rate = 60\n";
  for (const auto& [name, heading] : {std::pair{"front", 0}, {"left", -60}, {"right", 60}})
    out << "[[view]]\nname = \"" << name << "\"\nheading = " << heading
        << "\nwidth = 640\nheight = 480\nformat = \"raw\"\n";
  out << "[socket]\nport = 0\n[modbus]\nenabled = false\n"
      << "[cigi]\nenabled = true\nig_port = 0\nhost_port = " << host_port
      << "\n"
      // The database origin (the default) stated: the host frames place the ownship by it.
      << "[site]\nlatitude = 0\nlongitude = 0\n"
      << "[output]\ndirectory = \"" << (dir / "frames").string() << "\"\n";
  return path;
}

double floorMs(int width, int height) {
  std::string error;
  const std::unique_ptr<nephele::Renderer> gl = nephele::createRenderer({}, error);
  if (!gl) throw std::runtime_error("no GL for the floor: " + error);
  return nephele::medianMilliseconds(9, [&] { gl->renderFloor(width, height); });
}

struct HostFrameFigures {
  double render = 0.0, to_sof = 0.0, cigi_frames = 0.0, to_reply = 0.0, socket_frames = 0.0;
};

// Host frames over CIGI and over the socket, each followed by one frame of every view, on
// `scene` (what it is called in the heading); the medians.
// A CIGI host's UDP socket on the loopback; its address in `host`.
int hostSocket(sockaddr_in& host) {
  const int udp = socket(AF_INET, SOCK_DGRAM, 0);
  host = {};
  host.sin_family = AF_INET;
  host.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t length = sizeof host;
  if (bind(udp, reinterpret_cast<sockaddr*>(&host), sizeof host) ||
      getsockname(udp, reinterpret_cast<sockaddr*>(&host), &length))
    throw std::runtime_error("udp bind");
  return udp;
}

// Host frame `n`: IG Control and the ownship 4.5 km south of the database origin (0 N 0 E) at
// 300 + n m, where the views look north at the scenes' clouds (cumulus.toml's camera).
std::vector<std::uint8_t> hostFrame(int n) {
  std::vector<std::uint8_t> message;
  nephele::cigi::IgControl igc;
  igc.host_frame = std::uint32_t(n);
  igc.timestamp = std::uint32_t(1667 * n);
  igc.timestamp_valid = true;
  nephele::cigi::EntityControl ownship;
  ownship.latitude = -4500.0 / 111320.0;
  ownship.altitude = 300.0 + n;  // moves every frame
  nephele::cigi::encode(igc, nephele::cigi::ByteOrder::kBig, message);
  nephele::cigi::encode(ownship, nephele::cigi::ByteOrder::kBig, message);
  return message;
}

HostFrameFigures hostFrames(const std::filesystem::path& dir, int views, int repeats,
                            double floor_ms, const std::string& scene, const char* what) {
  sockaddr_in host;
  const int udp = hostSocket(host);
  Daemon daemon(writeHostConfig(dir, ntohs(host.sin_port), scene));
  sockaddr_in ig = host;
  ig.sin_port = htons(std::uint16_t(daemon.cigi_port));
  Client sub(daemon.socket_port), control(daemon.socket_port);
  std::vector<std::uint8_t> body;
  const char* names[] = {"front", "left", "right"};
  for (int v = 0; v < views; ++v) {
    sub.request({{"cmd", "subscribe"}, {"view", names[v]}, {"rate", 60}}, body);
    sub.receive(body);  // its first frame
  }
  auto frames = [&] {
    for (int got = 0; got < views;)
      if (sub.receive(body).value("event", "") == "frame") ++got;
  };
  std::vector<double> to_sof, cigi_frames, to_reply, socket_frames;
  for (int i = 0; i < repeats + 3; ++i) {
    const std::vector<std::uint8_t> message = hostFrame(i + 1);
    const auto t0 = Clock::now();
    sendto(udp, message.data(), message.size(), 0, reinterpret_cast<sockaddr*>(&ig), sizeof ig);
    std::uint8_t reply[64];
    if (recv(udp, reply, sizeof reply, 0) < 24 || reply[0] != nephele::cigi::Id::kStartOfFrame)
      throw std::runtime_error("no Start of Frame");
    const auto t_sof = Clock::now();
    frames();
    const auto t_frames = Clock::now();
    if (i >= 3) {
      to_sof.push_back(millisecondsBetween(t0, t_sof));
      cigi_frames.push_back(millisecondsBetween(t0, t_frames));
    }
  }
  for (int i = 0; i < repeats + 3; ++i) {
    const auto t0 = Clock::now();
    json r = control.request({{"cmd", "tick"}, {"dt", 1.0 / 60.0}}, body);
    if (!r["ok"]) throw std::runtime_error(r.dump());
    const auto t_reply = Clock::now();
    frames();
    if (i >= 3) {
      to_reply.push_back(millisecondsBetween(t0, t_reply));
      socket_frames.push_back(millisecondsBetween(t0, Clock::now()));
    }
  }
  json stats = control.request({{"cmd", "stats"}}, body)["result"];
  const double render = stats["render_ms"]["p50"].get<double>() * views;
  close(udp);
  std::printf(
      "host frames, lockstep, %s, %d view%s of 640x480 raw (%d frames each; render alone "
      "%.1f ms = %.0f x floor %.2f ms):\n",
      what, views, views > 1 ? "s" : "", repeats, render, render / floor_ms, floor_ms);
  std::printf("  the last frame's budget (stats.last_frame.ms): %s\n",
              stats["last_frame"]["ms"].dump().c_str());
  auto row = [&](const char* what, const std::vector<double>& ms) {
    std::printf("  %-32s p50 %7.1f ms (%4.2f x render)  p99 %7.1f ms (%4.2f x render)\n", what,
                percentile(ms, 0.5), percentile(ms, 0.5) / render, percentile(ms, 0.99),
                percentile(ms, 0.99) / render);
  };
  row("CIGI host frame to Start of Frame", to_sof);
  row("CIGI host frame to frames", cigi_frames);
  row("socket tick to reply", to_reply);
  row("socket tick to frames", socket_frames);
  return {render, percentile(to_sof, 0.5), percentile(cigi_frames, 0.5), percentile(to_reply, 0.5),
          percentile(socket_frames, 0.5)};
}

// Host frames in asynchronous (realtime) mode, the IG ticking at 60 Hz and each view subscribed
// at 60 Hz: from a host frame to the first Start of Frame that reports it handled, and to a
// frame of every view that shows it (its camera at the frame's altitude); and the rate at which
// Start of Frame comes.
void asynchronousHostFrames(const std::filesystem::path& dir, int views, int repeats,
                            double floor_ms, const std::string& scene, const char* what) {
  sockaddr_in host;
  const int udp = hostSocket(host);
  Daemon daemon(writeHostConfig(dir, ntohs(host.sin_port), scene, "realtime"));
  sockaddr_in ig = host;
  ig.sin_port = htons(std::uint16_t(daemon.cigi_port));
  Client sub(daemon.socket_port), control(daemon.socket_port);
  std::vector<std::uint8_t> body;
  const char* names[] = {"front", "left", "right"};
  for (int v = 0; v < views; ++v)
    sub.request({{"cmd", "subscribe"}, {"view", names[v]}, {"rate", 60}}, body);
  std::vector<double> to_sof, to_frames;
  int sofs = 0;
  const auto start = Clock::now();
  for (int n = 1; n <= repeats + 3; ++n) {
    const std::vector<std::uint8_t> message = hostFrame(n);
    const auto t0 = Clock::now();
    sendto(udp, message.data(), message.size(), 0, reinterpret_cast<sockaddr*>(&ig), sizeof ig);
    for (;;) {
      std::uint8_t reply[64];
      if (recv(udp, reply, sizeof reply, 0) < 24 || reply[0] != nephele::cigi::Id::kStartOfFrame)
        throw std::runtime_error("no Start of Frame");
      ++sofs;
      std::uint32_t last_host;  // big-endian, as the host sent
      std::memcpy(&last_host, reply + 16, 4);
      if (ntohl(last_host) == std::uint32_t(n)) break;
    }
    const auto t_sof = Clock::now();
    for (int got = 0; got < views;) {
      const json event = sub.receive(body);
      if (event.value("event", "") == "frame" &&
          event["image"]["camera"]["position"][2].get<double>() == 300.0 + n)
        ++got;
    }
    if (n > 3) {
      to_sof.push_back(millisecondsBetween(t0, t_sof));
      to_frames.push_back(millisecondsBetween(t0, Clock::now()));
    }
  }
  const double seconds = millisecondsBetween(start, Clock::now()) / 1000.0;
  json stats = control.request({{"cmd", "stats"}}, body)["result"];
  const double render = stats["render_ms"]["p50"].get<double>() * views;
  close(udp);
  std::printf(
      "host frames, asynchronous (realtime, 60 Hz), %s, %d view%s of 640x480 raw (%d frames "
      "each; render alone %.1f ms = %.0f x floor %.2f ms; Start of Frame at %.1f Hz):\n",
      what, views, views > 1 ? "s" : "", repeats, render, render / floor_ms, floor_ms,
      sofs / seconds);
  std::printf("  the last frame's budget (stats.last_frame.ms): %s\n",
              stats["last_frame"]["ms"].dump().c_str());
  for (const auto& [row, ms] : {std::pair{"CIGI host frame to Start of Frame", &to_sof},
                                {"CIGI host frame to frames", &to_frames}})
    std::printf("  %-32s p50 %7.1f ms (%4.2f x render)  p99 %7.1f ms (%4.2f x render)\n", row,
                percentile(*ms, 0.5), percentile(*ms, 0.5) / render, percentile(*ms, 0.99),
                percentile(*ms, 0.99) / render);
}

// A cumulus sky (genus_cumulus.toml: the weather mapping's field at 35 %) against the same
// daemon with no cloud, one view each, as multiples of the clear sky's figures (issue 27).
void cumulusSky(const std::filesystem::path& dir, int repeats, double floor_ms) {
  const std::string clear_scene = (dir / "clear.toml").string();
  std::ofstream(clear_scene) << "# no cloud: the clear sky the cumulus sky is measured against\n";
  const HostFrameFigures clear = hostFrames(dir, 1, repeats, floor_ms, clear_scene, "clear sky");
  const HostFrameFigures cumulus =
      hostFrames(dir, 1, repeats, floor_ms, NEPHELE_SOURCE_DIR "/config/scenes/genus_cumulus.toml",
                 "cumulus sky 35 %");
  std::printf("cumulus sky over the clear sky, medians (x clear):\n");
  auto row = [](const char* what, double a, double b) {
    std::printf("  %-32s %7.1f ms over %6.1f ms = %5.1f x clear\n", what, a, b, a / b);
  };
  row("render alone", cumulus.render, clear.render);
  row("CIGI host frame to Start of Frame", cumulus.to_sof, clear.to_sof);
  row("CIGI host frame to frames", cumulus.cigi_frames, clear.cigi_frames);
  row("socket tick to reply", cumulus.to_reply, clear.to_reply);
  row("socket tick to frames", cumulus.socket_frames, clear.socket_frames);
}

// The resident memory of process `pid`, MiB.
double residentMiBOf(pid_t pid) {
  std::ifstream status("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(status, line);)
    if (line.rfind("VmRSS:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;
  return 0.0;
}

json renderRequest(int width, int height) {
  return json{{"cmd", "render"},
              {"view", "front"},
              {"format", "raw"},
              {"camera", {{"width", width}, {"height", height}}}};
}

// A render's time on `c`, and the longest hello `other` waited for meanwhile.
std::pair<double, double> renderWhileAsking(Client& c, Client& other, int width, int height) {
  std::vector<std::uint8_t> body;
  std::atomic<bool> done{false};
  double longest_hello = 0.0;
  std::thread asker([&] {
    std::vector<std::uint8_t> b;
    while (!done) {
      const auto t0 = Clock::now();
      other.request({{"cmd", "hello"}}, b);
      longest_hello = std::max(longest_hello, millisecondsBetween(t0, Clock::now()));
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  const auto t0 = Clock::now();
  const json reply = c.request(renderRequest(width, height), body);
  const double ms = millisecondsBetween(t0, Clock::now());
  done = true;
  asker.join();
  if (!reply["ok"]) throw std::runtime_error(reply.dump());
  return std::pair{ms, longest_hello};
}

// Issue 31, item 5: a lockstep daemon on cumulus.toml whose world grows by legal add_cloud
// requests (cumulus clouds of 4,096 ellipsoids stacked 4.5 km in front of the camera) up to
// the world budget set here; at each size a render at 64x48 and at 640x480 (as multiples of
// the same view with no cloud), the longest `hello` wait of a second client during them, the
// daemon's resident memory, and at the end the SIGTERM-to-exit time during a 640x480 render.
void heavyWorlds(const std::filesystem::path& dir) {
  constexpr long kWorldBudget = 2097152;  // [world] max_ellipsoids here
  const std::string config = (dir / "heavy.toml").string();
  std::ofstream(config) << "scene = \"" << NEPHELE_SOURCE_DIR
                        << "/config/scenes/cumulus.toml\"\n[world]\nmode = \"lockstep\"\n"
                        << "max_ellipsoids = " << kWorldBudget << "\n"
                        << "[[view]]\nname = \"front\"\nwidth = 64\nheight = 48\n"
                        << "[socket]\nport = 0\n[modbus]\nenabled = false\n"
                        << "[output]\ndirectory = \"" << (dir / "frames").string() << "\"\n";
  Daemon daemon(config);
  Client c(daemon.socket_port), other(daemon.socket_port);
  std::vector<std::uint8_t> body;
  auto rssMiB = [&] { return residentMiBOf(daemon.pid); };
  auto timedRender = [&](int width, int height) {
    return renderWhileAsking(c, other, width, height);
  };
  c.request({{"cmd", "remove_cloud"}, {"name", "cumulus"}}, body);
  timedRender(640, 480);  // warm: programs compiled
  const double clear_small = timedRender(64, 48).first, clear_large = timedRender(640, 480).first;
  std::printf(
      "heavy worlds (issue 31): cumulus clouds of 4,096 ellipsoids stacked in front of the "
      "camera, world budget %ld; clear frame %.1f ms at 64x48, %.1f ms at 640x480\n",
      kWorldBudget, clear_small, clear_large);
  std::printf("  %10s %9s %22s %22s %14s\n", "ellipsoids", "RSS MiB", "64x48 ms (x clear)",
              "640x480 ms (x clear)", "hello max ms");
  long ellipsoids = 0;
  int clouds = 0;
  for (long target : {8192L, 102400L, 1048576L, kWorldBudget}) {
    while (ellipsoids + 4096 <= target) {
      const json r =
          c.request({{"cmd", "add_cloud"},
                     {"cloud",
                      {{"name", "heavy" + std::to_string(clouds++)},
                       {"cumulus", {{"base", {0, 0, 1000}}, {"width", 3000}, {"count", 4096}}}}}},
                    body);
      if (!r["ok"]) throw std::runtime_error(r.dump());
      ellipsoids += 4096;
    }
    const auto [small, hello_small] = timedRender(64, 48);
    const auto [large, hello_large] = timedRender(640, 480);
    std::printf("  %10ld %9.0f %12.0f (%6.0f x) %12.0f (%6.0f x) %14.1f\n", ellipsoids, rssMiB(),
                small, small / clear_small, large, large / clear_large,
                std::max(hello_small, hello_large));
  }
  c.send(renderRequest(640, 480));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const auto t0 = Clock::now();
  kill(daemon.pid, SIGTERM);
  int status = 0;
  waitpid(daemon.pid, &status, 0);
  std::printf("  SIGTERM 0.3 s into a 640x480 render of %ld ellipsoids: exit %d after %.2f s\n",
              ellipsoids, WIFEXITED(status) ? WEXITSTATUS(status) : -1,
              millisecondsBetween(t0, Clock::now()) / 1000.0);
  daemon.pid = 0;  // already reaped
}

}  // namespace

int main(int argc, char** argv) {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  try {
    const auto dir =
        std::filesystem::temp_directory_path() / ("nephele-bench-" + std::to_string(getpid()));
    std::filesystem::create_directories(dir);
    if (argc > 1 && std::string(argv[1]) == "--heavy") {  // section 7 alone
      heavyWorlds(dir);
      std::filesystem::remove_all(dir);
      return 0;
    }
    {
      Daemon daemon(writeConfig(dir));
      Client client(daemon.socket_port);
      latency(client, "raw", 200);
      latency(client, "png", 100);
      modbusLatency(daemon, 20);
      for (int n : {1, 4, 16}) subscribers(daemon, n, 5.0);
    }
    const double floor_ms = floorMs(640, 480);
    for (int views : {1, 3})
      hostFrames(dir, views, 40, floor_ms, NEPHELE_SOURCE_DIR "/config/scenes/cumulus.toml",
                 "the 27-lobe cumulus");
    for (int views : {1, 3})
      asynchronousHostFrames(dir, views, 40, floor_ms,
                             NEPHELE_SOURCE_DIR "/config/scenes/cumulus.toml",
                             "the 27-lobe cumulus");
    cumulusSky(dir, 40, floor_ms);
    std::filesystem::remove_all(dir);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "daemon_bench: %s\n", e.what());
    return 1;
  }
  return 0;
}
