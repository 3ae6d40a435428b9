// Streamed views (issue 49, item 2; docs/STREAMING.md): a view rendered by the GL renderer,
// streamed as H.264 in MPEG-TS over loopback UDP at the stream's rate, and decoded in this
// process as a player would (FFmpeg, low-delay flags). Prints
// - glass to glass: from the moment a frame's pixels are read back to the moment the decoder
//   hands out the picture that shows its tick (stamped in its corner), median, 95th percentile
//   and largest, in ms and in frame periods;
// - the encoder's CPU time per frame, as a multiple of the render's time of the same frame and
//   of the platform floor;
// - the decoded pictures' PSNR against the rendered frames (RGB, below the stamp).
// Frames are rendered first (a camera sweeping 30 degrees) and replayed at the rate, so that
// the stream runs at its rate on a machine whose render cannot.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <mutex>
#include <thread>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libswscale/swscale.h>
}

#include "bench/bench_common.h"
#include "config/scene_file.h"
#include "image/video_stream.h"
#include "renderer/frame_timing.h"
#include "renderer/renderer.h"

using namespace nephele;
using Clock = std::chrono::steady_clock;

namespace {

// What the receiver saw of each tick: when it was decoded, and its PSNR.
struct Decoded {
  Clock::time_point at;
  double psnr = 0.0;
};

// PSNR of a decoded RGBA picture against the frame it shows, over the rows below the stamp.
double psnr(const std::vector<std::uint8_t>& decoded, const Srgb8Image& frame) {
  double sum = 0.0;
  std::size_t n = 0;
  for (int y = kStampBlock; y < frame.height; ++y) {
    const int row = frame.bottom_up ? frame.height - 1 - y : y;
    for (int x = 0; x < frame.width; ++x)
      for (int c = 0; c < 3; ++c) {
        const double d = double(decoded[(std::size_t(y) * frame.width + x) * 4 + c]) -
                         double(frame.rgba[(std::size_t(row) * frame.width + x) * 4 + c]);
        sum += d * d;
        ++n;
      }
  }
  const double mse = sum / double(std::max<std::size_t>(n, 1));
  return mse > 0.0 ? 10.0 * std::log10(255.0 * 255.0 / mse) : 99.0;
}

using Frames = std::vector<std::shared_ptr<const Srgb8Image>>;

// The frames of a camera sweeping 30 degrees, and what each cost to render.
Frames renderSweep(Renderer& renderer, Scene scene, const RenderSettings& render, int distinct,
                   std::vector<double>& render_ms) {
  Frames frames;
  renderer.renderSrgb8(scene, render);  // warm-up: shaders, textures
  const double heading = scene.camera.orientation.heading_deg;
  for (int i = 0; i < distinct; ++i) {
    scene.camera.orientation.heading_deg = heading + 30.0 * i / distinct;
    const auto t0 = Clock::now();
    frames.push_back(std::make_shared<const Srgb8Image>(renderer.renderSrgb8(scene, render)));
    render_ms.push_back(millisecondsBetween(t0, Clock::now()));
  }
  return frames;
}

// What the player thread shares with the bench.
struct Player {
  std::mutex mutex;
  std::map<std::uint32_t, Decoded> decoded;  // by tick, under `mutex`
  std::atomic<bool> stop{false}, listening{false};
  std::string error;
};

// The player (FFmpeg, low-delay flags): decodes the stream at `address` until told to stop,
// noting when each tick's picture came out and its PSNR against the frame it shows.
void play(const std::string& address, int w, int h, const Frames& frames, Player& player) {
  AVFormatContext* input = nullptr;
  AVDictionary* options = nullptr;
  av_dict_set(&options, "fflags", "nobuffer", 0);
  av_dict_set(&options, "probesize", "32768", 0);
  av_dict_set(&options, "analyzeduration", "0", 0);
  av_dict_set(&options, "timeout", "3000000", 0);  // microseconds without data: give up
  const std::string url = address + "?fifo_size=100000&overrun_nonfatal=1";
  player.listening = true;
  if (avformat_open_input(&input, url.c_str(), av_find_input_format("mpegts"), &options) < 0) {
    player.error = "cannot open " + url;
    av_dict_free(&options);
    return;
  }
  av_dict_free(&options);
  const AVCodec* codec = avcodec_find_decoder(AV_CODEC_ID_H264);
  AVCodecContext* ctx = avcodec_alloc_context3(codec);
  ctx->flags |= AV_CODEC_FLAG_LOW_DELAY;
  ctx->thread_count = 1;  // frame threading would hold pictures back
  avcodec_open2(ctx, codec, nullptr);
  AVPacket* packet = av_packet_alloc();
  AVFrame* picture = av_frame_alloc();
  SwsContext* to_rgba = nullptr;
  std::vector<std::uint8_t> rgba(std::size_t(w) * h * 4);
  while (!player.stop && av_read_frame(input, packet) >= 0) {
    if (avcodec_send_packet(ctx, packet) >= 0) {
      while (avcodec_receive_frame(ctx, picture) >= 0) {
        const Clock::time_point at = Clock::now();
        const auto tick =
            readTickStamp(picture->data[0], picture->linesize[0], picture->width, picture->height);
        if (!tick || *tick >= std::uint32_t(frames.size() * 1000000)) continue;
        to_rgba = sws_getCachedContext(to_rgba, picture->width, picture->height,
                                       AVPixelFormat(picture->format), w, h, AV_PIX_FMT_RGBA,
                                       SWS_BILINEAR, nullptr, nullptr, nullptr);
        std::uint8_t* out[1] = {rgba.data()};
        const int stride[1] = {w * 4};
        sws_scale(to_rgba, picture->data, picture->linesize, 0, picture->height, out, stride);
        const double quality = psnr(rgba, *frames[*tick % frames.size()]);
        std::lock_guard lock(player.mutex);
        player.decoded[*tick] = {at, quality};
      }
    }
    av_packet_unref(packet);
  }
  sws_freeContext(to_rgba);
  av_frame_free(&picture);
  av_packet_free(&packet);
  avcodec_free_context(&ctx);
  avformat_close_input(&input);
}

// Pushes `count` frames in turn at `rate`: when each was ready (read back).
std::vector<Clock::time_point> pushAtRate(VideoStream& stream, const Frames& frames, int count,
                                          double rate) {
  std::vector<Clock::time_point> ready(static_cast<std::size_t>(count));
  const Clock::time_point start = Clock::now();
  for (int i = 0; i < count; ++i) {
    std::this_thread::sleep_until(start + std::chrono::duration_cast<Clock::duration>(
                                              std::chrono::duration<double>(i / rate)));
    ready[std::size_t(i)] = Clock::now();
    stream.push(frames[std::size_t(i) % frames.size()], std::uint64_t(i));
  }
  return ready;
}

struct StreamBenchOptions {
  std::string size = "1280x720", encoder = "auto";
  std::string scene_path = NEPHELE_SOURCE_DIR "/config/scenes/cumulus.toml";
  double rate = 30.0;
  int seconds = 6, bitrate = 4000, keyframes = 30, port = 5990, distinct = 24;
};

// The figures of a stream: what went through, glass to glass, the encoder's cost against the
// render's (`render` ms) and the floor's, and the decoded pictures' PSNR.
void printStreamFigures(const StreamBenchOptions& o, const VideoStreamSettings& settings, int w,
                        int h, const std::string& gl, int count, const VideoStreamStats& counts,
                        const std::vector<double>& latency, const std::vector<double>& quality,
                        double render, double floor) {
  const double period = 1000.0 / o.rate;
  const double encode_cpu = counts.encode_cpu_ms / double(std::max<std::uint64_t>(counts.sent, 1));
  std::printf(
      "\nStreamed view %dx%d at %.0f Hz, %d kbit/s, keyframe every %d, encoder %s, %s (%s)\n", w, h,
      o.rate, o.bitrate, o.keyframes, o.encoder.c_str(), settings.address.c_str(), gl.c_str());
  std::printf(
      "frames: %d pushed, %llu encoded, %llu dropped at the encoder, %zu decoded; %.0f "
      "kbit/s sent\n",
      count, (unsigned long long)counts.sent, (unsigned long long)counts.dropped, latency.size(),
      double(counts.bytes) * 8.0 / 1000.0 / o.seconds);
  std::printf(
      "glass to glass (read back -> decoded): median %.1f ms, p95 %.1f, largest %.1f "
      "(%.2f / %.2f / %.2f frame periods; aim: at most 50 ms + one period = %.1f ms)\n",
      percentile(latency, 0.5), percentile(latency, 0.95), percentile(latency, 1.0),
      percentile(latency, 0.5) / period, percentile(latency, 0.95) / period,
      percentile(latency, 1.0) / period, 50.0 + period);
  std::printf(
      "encoder CPU per frame %.1f ms: %.2f x the render (%.1f ms), %.1f x the floor "
      "(%.2f ms)\n",
      encode_cpu, encode_cpu / render, render, encode_cpu / floor, floor);
  std::printf(
      "PSNR of the decoded pictures against the rendered frames: median %.1f dB, "
      "lowest %.1f dB\n",
      percentile(quality, 0.5), percentile(quality, 0.0));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Streamed view: latency, encoder cost and PSNR"};
  StreamBenchOptions o;
  app.add_option("--size", o.size, "frame size WxH");
  app.add_option("--scene", o.scene_path, "scene file");
  app.add_option("--rate", o.rate, "stream rate, Hz");
  app.add_option("--seconds", o.seconds, "how long to stream");
  app.add_option("--bitrate", o.bitrate, "kbit/s");
  app.add_option("--keyframe-interval", o.keyframes, "frames between keyframes");
  app.add_option("--encoder", o.encoder, "auto, libx264 or h264_nvenc");
  app.add_option("--port", o.port, "loopback UDP port");
  app.add_option("--distinct", o.distinct, "frames rendered before streaming, replayed in turn");
  CLI11_PARSE(app, argc, argv);

  SceneFile file;
  if (std::string e = loadSceneFile(o.scene_path, file); !e.empty()) {
    std::fprintf(stderr, "%s\n", e.c_str());
    return 1;
  }
  Scene scene = file.scene;
  if (!bench::parseSize(o.size, scene.camera)) return 2;
  const std::unique_ptr<Renderer> gl = bench::openRenderer();
  if (!gl) return 1;
  Renderer& renderer = *gl;
  const int w = scene.camera.width, h = scene.camera.height;
  // The frames, and what one costs to render (the median of the sweep's).
  std::vector<double> render_ms;
  const Frames frames = renderSweep(renderer, scene, file.render, o.distinct, render_ms);
  const double render = percentile(render_ms, 0.5);
  const double floor = medianMilliseconds(9, [&] { renderer.renderFloor(w, h); });

  VideoStreamSettings settings;
  settings.address = "udp://127.0.0.1:" + std::to_string(o.port);
  settings.bitrate_kbps = o.bitrate;
  settings.rate_hz = o.rate;
  settings.keyframe_interval = o.keyframes;
  settings.encoder = o.encoder;
  settings.stamp = true;
  // The player: opened before the stream starts, as a viewer waiting for it.
  Player player;
  std::thread player_thread([&] { play(settings.address, w, h, frames, player); });
  while (!player.listening) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  auto opened = VideoStream::open(settings, w, h);
  if (auto* e = std::get_if<std::string>(&opened)) {
    std::fprintf(stderr, "stream: %s\n", e->c_str());
    player.stop = true;
    player_thread.join();
    return 1;
  }
  auto stream = std::move(std::get<std::unique_ptr<VideoStream>>(opened));
  const int count = int(std::lround(o.seconds * o.rate));
  const std::vector<Clock::time_point> ready = pushAtRate(*stream, frames, count, o.rate);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  const VideoStreamStats counts = stream->stats();
  stream.reset();
  player.stop = true;
  player_thread.join();
  if (!player.error.empty()) {
    std::fprintf(stderr, "%s\n", player.error.c_str());
    return 1;
  }
  std::vector<double> latency, quality;
  for (const auto& [tick, d] : player.decoded) {
    if (tick >= std::uint32_t(count)) continue;
    latency.push_back(millisecondsBetween(ready[tick], d.at));
    quality.push_back(d.psnr);
  }
  printStreamFigures(o, settings, w, h, renderer.platform().device, count, counts, latency, quality,
                     render, floor);
  return latency.empty() ? 1 : 0;
}
