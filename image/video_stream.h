#pragma once
// A view as a live H.264 stream (issue 49; docs/STREAMING.md), built on FFmpeg's libraries:
// NVIDIA's encoder where the machine has one, x264 otherwise, tuned for latency (no B-frames,
// no look-ahead), muxed as MPEG-TS over UDP or SRT, or as RTP with an SDP description, so that
// ffplay, VLC and GStreamer play it. Frames go to an encoder thread through a queue of
// kStreamQueue: a slow encoder or network drops frames (counted), never the caller's time.
#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <variant>

#include "image/image.h"

namespace nephele {

struct VideoStreamSettings {
  // udp://host:port (MPEG-TS), srt://host:port (MPEG-TS over SRT, caller mode) or
  // rtp://host:port (RTP; sdp() describes it to the player).
  std::string address;
  int bitrate_kbps = 4000;
  double rate_hz = 30.0;         // the stream's nominal frame rate (its time stamps)
  int keyframe_interval = 30;    // frames between keyframes: how soon a new viewer sees a picture
  std::string encoder = "auto";  // auto: h264_nvenc where it opens, else libx264; or one of them
  bool stamp = false;            // each frame's tick in its top-left corner (stampTick)
};

// The ranges every reader of a stream's settings takes (the socket's stream, the config's
// [[stream]]).
struct VideoStreamLimits {
  static constexpr int kMinKbps = 100, kMaxKbps = 100000;
  static constexpr double kMinRate = 0.5, kMaxRate = 60.0;
  static constexpr int kMaxKeyframeInterval = 600;
};
// What is wrong with the address (its transport, a host, a port 1 to 65535) or the encoder's
// name, or empty: an address FFmpeg would open without a port, or with one it wraps
// (udp://host:99999 sends to 34463), is refused here rather than streaming nowhere.
inline std::string videoStreamSettingsError(const VideoStreamSettings& settings) {
  const std::string& address = settings.address;
  const std::size_t colon = address.find("://");
  const std::string scheme = address.substr(0, colon);
  const std::string allowed =
      " (allowed: udp://host:port for MPEG-TS over UDP, srt://host:port for MPEG-TS over SRT, "
      "rtp://host:port for RTP; port 1 to 65535)";
  if (colon == std::string::npos || (scheme != "udp" && scheme != "srt" && scheme != "rtp"))
    return "address: \"" + address + "\"" + allowed;
  const std::string rest = address.substr(colon + 3);
  const std::string host_port = rest.substr(0, rest.find('?'));  // FFmpeg's options may follow
  const std::size_t port_at = host_port.rfind(':');
  const std::string host = port_at == std::string::npos ? "" : host_port.substr(0, port_at);
  const std::string port = port_at == std::string::npos ? "" : host_port.substr(port_at + 1);
  const bool digits = !port.empty() && port.size() <= 5 &&
                      port.find_first_not_of("0123456789") == std::string::npos;
  if (host.empty() || host == "[]" || !digits || std::stoi(port) < 1 || std::stoi(port) > 65535)
    return "address: \"" + address + "\" needs a host and a port" + allowed;
  if (settings.encoder != "auto" && settings.encoder != "libx264" &&
      settings.encoder != "h264_nvenc")
    return "encoder: \"" + settings.encoder + "\" (allowed: auto, libx264, h264_nvenc)";
  return "";
}

// Frames a stream holds before it drops: one in encoding, one waiting.
inline constexpr std::size_t kStreamQueue = 2;

struct VideoStreamStats {
  std::uint64_t sent = 0;      // frames encoded and written
  std::uint64_t dropped = 0;   // frames refused with the queue full
  std::uint64_t bytes = 0;     // written to the transport
  double encode_ms = 0.0;      // the last frame's, wall clock (conversion, encoding, writing)
  double encode_cpu_ms = 0.0;  // the encoder thread's CPU time over all frames
};

class VideoStream {
 public:
  // Opens the encoder and the transport for `width` x `height` frames; what is wrong otherwise.
  static std::variant<std::unique_ptr<VideoStream>, std::string> open(
      const VideoStreamSettings& settings, int width, int height);
  ~VideoStream();  // sends what it holds, then closes
  VideoStream(const VideoStream&) = delete;
  VideoStream& operator=(const VideoStream&) = delete;

  // Whether push would drop: a caller can skip rendering a frame no one would see.
  bool full() const;
  // Hands a frame (any size: it is scaled to the stream's) to the encoder thread; false, and
  // counted, when the queue is full. A rendered frame's pixels are those encode's 8-bit
  // formats take (srgb8Pixels, renderer/encode.h); turning them into YUV 4:2:0 at the
  // stream's size is the encoder's own input stage.
  bool push(std::shared_ptr<const Srgb8Image> image, std::uint64_t tick);
  // A frame refused before it was rendered (full()), counted with the dropped.
  void countDropped() { ++dropped_; }

  VideoStreamStats stats() const;
  const std::string& encoderName() const { return encoder_name_; }
  const std::string& sdp() const { return sdp_; }  // RTP only
  int width() const { return width_; }
  int height() const { return height_; }

 private:
  struct Codec;  // FFmpeg's state, touched by the encoder thread alone once open
  struct Item {
    std::shared_ptr<const Srgb8Image> image;
    std::uint64_t tick = 0;
  };
  VideoStream() = default;
  void run();
  void encode(const Item& item);

  std::unique_ptr<Codec> codec_;
  std::string encoder_name_, sdp_;
  int width_ = 0, height_ = 0;
  bool stamp_ = false;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Item> queue_;
  bool stop_ = false;
  std::atomic<std::uint64_t> sent_{0}, dropped_{0}, bytes_{0};
  std::atomic<double> encode_ms_{0.0}, encode_cpu_ms_{0.0};
  std::thread thread_;
};

// The tick stamp: the low 32 bits of a tick as a row of 32 blocks of kStampBlock pixels from
// the top-left corner, white for 1 and black for 0, most significant first, in the luma plane
// (chroma neutral), so that a decoder can read which tick it shows after any sane encoding.
inline constexpr int kStampBlock = 16;
void stampTick(std::uint8_t* luma, int stride, int width, int height, std::uint32_t tick);
// The tick a stamped luma plane shows (each block's mean above or below mid-grey); none when
// the frame is too small to hold the stamp.
std::optional<std::uint32_t> readTickStamp(const std::uint8_t* luma, int stride, int width,
                                           int height);

}  // namespace nephele
