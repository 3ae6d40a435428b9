#include "image/video_stream.h"

#include <time.h>

#include <chrono>
#include <cstring>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/imgutils.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

namespace nephele {
namespace {

std::string avError(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, text, sizeof text);
  return text;
}

double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return double(t.tv_sec) * 1e3 + double(t.tv_nsec) * 1e-6;
}

// An H.264 access unit delimiter in start-code framing.
constexpr std::uint8_t kDelimiter[] = {0, 0, 0, 1, 9, 0xF0};

// Luma of studio-swing black and white, and neutral chroma.
constexpr std::uint8_t kBlack = 16, kWhite = 235, kNeutral = 128;

}  // namespace

struct VideoStream::Codec {
  AVFormatContext* format = nullptr;
  AVCodecContext* context = nullptr;
  AVStream* stream = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  SwsContext* scale = nullptr;
  bool annex_b = true;  // start-code framing (MPEG-TS); RTP packs NAL units itself
  int source_width = 0, source_height = 0;
  std::int64_t next_pts = 0;

  ~Codec() {
    sws_freeContext(scale);
    av_packet_free(&packet);
    av_frame_free(&frame);
    avcodec_free_context(&context);
    if (format) {
      if (format->pb) avio_closep(&format->pb);
      avformat_free_context(format);
    }
  }

  // Writes every packet the encoder has ready; the bytes written, or a negative error.
  std::int64_t drain() {
    std::int64_t written = 0;
    while (true) {
      const int r = avcodec_receive_packet(context, packet);
      if (r == AVERROR(EAGAIN) || r == AVERROR_EOF) return written;
      if (r < 0) return r;
      // The next access unit's delimiter (nal_unit_type 9, any picture type) ends this one:
      // a player's parser then closes the frame at once instead of waiting for the next.
      if (annex_b) {
        const int at = packet->size;
        if (av_grow_packet(packet, int(sizeof kDelimiter)) < 0) return AVERROR(ENOMEM);
        std::memcpy(packet->data + at, kDelimiter, sizeof kDelimiter);
      }
      av_packet_rescale_ts(packet, context->time_base, stream->time_base);
      packet->stream_index = stream->index;
      written += packet->size;
      // One stream: written as it comes, with no interleaving queue to wait in.
      const int w = av_write_frame(format, packet);
      av_packet_unref(packet);
      if (w < 0) return w;
    }
  }
};

namespace {

// Opens the first of the settings' encoders that this FFmpeg has and accepts (auto: NVENC,
// then x264), set for low latency: no B-frames, constant bit rate. Empty on success.
std::string openEncoder(const VideoStreamSettings& settings, int width, int height,
                        AVCodecContext*& context, std::string& opened) {
  std::vector<std::string> names;
  if (settings.encoder == "auto")
    names = {"h264_nvenc", "libx264"};
  else
    names = {settings.encoder};
  std::string why;
  for (const std::string& name : names) {
    const AVCodec* codec = avcodec_find_encoder_by_name(name.c_str());
    if (!codec) {
      why += name + ": not in this FFmpeg; ";
      continue;
    }
    AVCodecContext* ctx = avcodec_alloc_context3(codec);
    ctx->width = width;
    ctx->height = height;
    ctx->pix_fmt = AV_PIX_FMT_YUV420P;
    ctx->time_base = av_d2q(1.0 / settings.rate_hz, 1000000);
    ctx->framerate = av_d2q(settings.rate_hz, 1000000);
    ctx->bit_rate = std::int64_t(settings.bitrate_kbps) * 1000;
    ctx->rc_max_rate = ctx->bit_rate;
    ctx->rc_buffer_size = int(ctx->bit_rate / std::max(settings.rate_hz, 1.0)) * 2;
    ctx->gop_size = settings.keyframe_interval;
    ctx->max_b_frames = 0;  // every frame leaves as soon as it is encoded
    if (name == "libx264") {
      av_opt_set(ctx->priv_data, "preset", "veryfast", 0);
      av_opt_set(ctx->priv_data, "tune", "zerolatency", 0);
      av_opt_set(ctx->priv_data, "x264-params", "repeat-headers=1", 0);
    } else {
      av_opt_set(ctx->priv_data, "preset", "p2", 0);
      av_opt_set(ctx->priv_data, "tune", "ull", 0);
      av_opt_set(ctx->priv_data, "zerolatency", "1", 0);
      av_opt_set(ctx->priv_data, "delay", "0", 0);
    }
    const int r = avcodec_open2(ctx, codec, nullptr);
    if (r < 0) {
      why += name + ": " + avError(r) + "; ";
      avcodec_free_context(&ctx);
      continue;
    }
    context = ctx;
    opened = name;
    return "";
  }
  return "encoder: none opened (" + why.substr(0, why.size() - 2) + ")";
}

}  // namespace

std::variant<std::unique_ptr<VideoStream>, std::string> VideoStream::open(
    const VideoStreamSettings& settings, int width, int height) {
  if (std::string e = videoStreamSettingsError(settings); !e.empty()) return e;
  const std::string& address = settings.address;
  const std::string scheme = address.substr(0, address.find("://"));
  if (width < 16 || height < 16) return "the view is smaller than 16 x 16 pixels";
  std::unique_ptr<VideoStream> out(new VideoStream);
  // H.264 wants even sizes for 4:2:0; an odd view loses its last row or column.
  out->width_ = width & ~1;
  out->height_ = height & ~1;
  out->stamp_ = settings.stamp;
  out->codec_ = std::make_unique<Codec>();
  Codec& c = *out->codec_;

  if (std::string e =
          openEncoder(settings, out->width_, out->height_, c.context, out->encoder_name_);
      !e.empty())
    return e;

  const char* muxer = scheme == "rtp" ? "rtp" : "mpegts";
  if (const int r = avformat_alloc_output_context2(&c.format, nullptr, muxer, address.c_str());
      r < 0 || !c.format)
    return "address: \"" + address + "\": " + avError(r);
  c.stream = avformat_new_stream(c.format, nullptr);
  avcodec_parameters_from_context(c.stream->codecpar, c.context);
  c.stream->time_base = c.context->time_base;
  std::string url = address;
  const std::string join = url.find('?') == std::string::npos ? "?" : "&";
  if (scheme == "udp") url += join + "pkt_size=1316";
  // An SRT caller waits for its listener on the caller's thread: at most a second.
  if (scheme == "srt" && url.find("connect_timeout") == std::string::npos)
    url += join + "connect_timeout=1000";
  if (const int r = avio_open(&c.format->pb, url.c_str(), AVIO_FLAG_WRITE); r < 0)
    return "address: \"" + address + "\": " + avError(r);
  AVDictionary* options = nullptr;
  av_dict_set(&options, "flush_packets", "1", 0);  // each packet leaves as it is written
  av_dict_set(&options, "muxdelay", "0", 0);
  av_dict_set(&options, "muxpreload", "0", 0);
  // Each PES carries its length, so a demuxer hands a frame on without waiting for the next.
  av_dict_set(&options, "omit_video_pes_length", "0", 0);
  const int r = avformat_write_header(c.format, &options);
  av_dict_free(&options);
  if (r < 0) return "address: \"" + address + "\": " + avError(r);
  c.annex_b = scheme != "rtp";
  if (scheme == "rtp") {
    char sdp[4096] = {};
    av_sdp_create(&c.format, 1, sdp, sizeof sdp);
    out->sdp_ = sdp;
  }
  c.frame = av_frame_alloc();
  c.frame->format = AV_PIX_FMT_YUV420P;
  c.frame->width = out->width_;
  c.frame->height = out->height_;
  if (av_frame_get_buffer(c.frame, 0) < 0) return "out of memory for a frame";
  c.packet = av_packet_alloc();
  out->thread_ = std::thread([s = out.get()] { s->run(); });
  return out;
}

VideoStream::~VideoStream() {
  {
    std::lock_guard lock(mutex_);
    stop_ = true;
  }
  cv_.notify_all();
  const bool started = thread_.joinable();
  if (started) thread_.join();
  if (started) {  // the header is written: flush the encoder, end the stream
    avcodec_send_frame(codec_->context, nullptr);  // flush
    codec_->drain();
    av_write_trailer(codec_->format);
  }
}

bool VideoStream::full() const {
  std::lock_guard lock(mutex_);
  return queue_.size() >= kStreamQueue;
}

bool VideoStream::push(std::shared_ptr<const Srgb8Image> image, std::uint64_t tick) {
  {
    std::lock_guard lock(mutex_);
    if (stop_ || queue_.size() >= kStreamQueue) {
      ++dropped_;
      return false;
    }
    queue_.push_back({std::move(image), tick});
  }
  cv_.notify_one();
  return true;
}

VideoStreamStats VideoStream::stats() const {
  return {sent_.load(), dropped_.load(), bytes_.load(), encode_ms_.load(), encode_cpu_ms_.load()};
}

void VideoStream::run() {
  while (true) {
    Item item;
    {
      std::unique_lock lock(mutex_);
      cv_.wait(lock, [&] { return stop_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stopped, with nothing left to send
      item = queue_.front();
    }
    const auto t0 = std::chrono::steady_clock::now();
    const double cpu0 = threadCpuMs();
    encode(item);
    encode_cpu_ms_.store(encode_cpu_ms_.load() + threadCpuMs() - cpu0);
    encode_ms_.store(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
    std::lock_guard lock(mutex_);
    queue_.pop_front();  // only now is there room: one frame in encoding counts as held
  }
}

void VideoStream::encode(const Item& item) {
  Codec& c = *codec_;
  const Srgb8Image& image = *item.image;
  if (!c.scale || c.source_width != image.width || c.source_height != image.height) {
    sws_freeContext(c.scale);
    c.scale = sws_getContext(image.width, image.height, AV_PIX_FMT_RGBA, width_, height_,
                             AV_PIX_FMT_YUV420P, SWS_BILINEAR, nullptr, nullptr, nullptr);
    c.source_width = image.width;
    c.source_height = image.height;
  }
  if (!c.scale || av_frame_make_writable(c.frame) < 0) return;
  // GL's bottom-up rows are read top down by starting at the last row with a negative stride.
  const int row = image.width * 4;
  const std::uint8_t* first =
      image.bottom_up ? image.rgba.data() + std::size_t(image.height - 1) * row : image.rgba.data();
  const std::uint8_t* source[1] = {first};
  const int stride[1] = {image.bottom_up ? -row : row};
  sws_scale(c.scale, source, stride, 0, image.height, c.frame->data, c.frame->linesize);
  if (stamp_) {
    stampTick(c.frame->data[0], c.frame->linesize[0], width_, height_, std::uint32_t(item.tick));
    // The stamp's chroma neutral, so its blocks stay grey through 4:2:0.
    const int blocks = std::min(32, width_ / kStampBlock);
    for (int y = 0; y < std::min(kStampBlock, height_) / 2; ++y)
      for (int p = 1; p <= 2; ++p)
        std::memset(c.frame->data[p] + std::ptrdiff_t(y) * c.frame->linesize[p], kNeutral,
                    std::size_t(blocks * kStampBlock / 2));
  }
  c.frame->pts = c.next_pts++;
  if (avcodec_send_frame(c.context, c.frame) < 0) return;
  const std::int64_t written = c.drain();
  if (written < 0) return;  // a transport error: the frame is lost, the stream goes on
  bytes_ += std::uint64_t(written);
  ++sent_;
}

void stampTick(std::uint8_t* luma, int stride, int width, int height, std::uint32_t tick) {
  if (width < 32 * kStampBlock || height < kStampBlock) return;
  for (int bit = 0; bit < 32; ++bit) {
    const std::uint8_t v = (tick >> (31 - bit)) & 1u ? kWhite : kBlack;
    for (int y = 0; y < kStampBlock; ++y)
      std::memset(luma + std::ptrdiff_t(y) * stride + bit * kStampBlock, v, kStampBlock);
  }
}

std::optional<std::uint32_t> readTickStamp(const std::uint8_t* luma, int stride, int width,
                                           int height) {
  if (width < 32 * kStampBlock || height < kStampBlock) return std::nullopt;
  std::uint32_t tick = 0;
  for (int bit = 0; bit < 32; ++bit) {
    int sum = 0;
    // The block's middle, away from the edges the encoding softens.
    for (int y = kStampBlock / 4; y < 3 * kStampBlock / 4; ++y)
      for (int x = kStampBlock / 4; x < 3 * kStampBlock / 4; ++x)
        sum += luma[std::ptrdiff_t(y) * stride + bit * kStampBlock + x];
    const int mean = sum / (kStampBlock * kStampBlock / 4);
    tick = (tick << 1) | (mean > (kBlack + kWhite) / 2 ? 1u : 0u);
  }
  return tick;
}

}  // namespace nephele
