#include "server/render_service.h"

#include <spdlog/spdlog.h>

#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include "renderer/renderer.h"
#include "server/log_limiter.h"
#include "server/telemetry.h"
#include "world/formations/weather.h"
#include "world/limits.h"
#include "world/world.h"

namespace nephele {

using nlohmann::json;

Channels channelsOf(const ImageRequest& image) {
  if (image.floatPlanes()) return {image.order, Channels::Pixels::kPlanes};
  Channels out;
  if (image.colour) out.order.push_back(Channel::kColour);
  if (image.coverage) out.order.push_back(Channel::kCoverage);
  out.pixels =
      image.format == ImageFormat::kExr ? Channels::Pixels::kLinear : Channels::Pixels::kSrgb8;
  return out;
}

ImageFileFormat fileFormatOf(ImageFormat format) {
  switch (format) {
    case ImageFormat::kRaw:
      return ImageFileFormat::kRaw;
    case ImageFormat::kPng:
      return ImageFileFormat::kPng;
    case ImageFormat::kJpeg:
      return ImageFileFormat::kJpeg;
    case ImageFormat::kExr:
      return ImageFileFormat::kExr;
  }
  return ImageFileFormat::kRaw;
}

Encoded encodeView(const RenderedView& view, const ImageRequest& image,
                   const EncodeOptions& options) {
  return encode(view.frame, fileFormatOf(image.format), channelsOf(image), options);
}

json imageMeta(const RenderedView& view, const ImageRequest& image) {
  json meta = view.meta;
  meta["format"] = imageFormatName(image.format);
  meta["channels"] = channelNames(image);
  meta["rows"] = "top-down";
  meta["encoding"] = image.format == ImageFormat::kExr ? "linear"
                     : image.floatPlanes()             ? "float32-planes"
                                                       : "srgb";
  return meta;
}

// A thread that encodes images off the world thread, from a bounded queue.
class RenderService::Encoder {
 public:
  Encoder() : thread_([this] { run(); }) {}
  ~Encoder() { finish(); }
  // Sends what it holds, then stops its thread; posts after this are refused. The Encoder
  // itself stays, so a stats request on the socket thread may still ask its depth.
  void finish() {
    {
      std::lock_guard lock(mutex_);
      stop_ = true;
    }
    cv_.notify_all();
    if (thread_.joinable()) thread_.join();
  }
  bool post(std::function<void()> job) {
    {
      std::lock_guard lock(mutex_);
      if (stop_ || jobs_.size() >= kEncoderQueue) return false;
      jobs_.push_back(std::move(job));
    }
    cv_.notify_one();
    return true;
  }
  std::size_t depth() const {
    std::lock_guard lock(mutex_);
    return jobs_.size();
  }

 private:
  void run() {
    for (;;) {
      std::function<void()> job;
      {
        std::unique_lock lock(mutex_);
        cv_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
        if (jobs_.empty()) return;  // stopping, and every queued image is out
        job = std::move(jobs_.front());
        jobs_.pop_front();
      }
      job();
    }
  }
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<std::function<void()>> jobs_;
  bool stop_ = false;
  std::thread thread_;
};

RenderService::RenderService(const DaemonConfig& config, Telemetry& telemetry)
    : config_(config), telemetry_(telemetry) {}

RenderService::~RenderService() = default;

void RenderService::startEncoder() {
  encoder_ = std::make_unique<Encoder>();
}

void RenderService::finishEncoder() {
  if (encoder_) encoder_->finish();  // kept for stats' depth
}

std::string RenderService::open() {
  std::string error;
  renderer_ = createRenderer(RendererOptions{}, error);  // GL, EGL or OSMesa as found
  if (!renderer_) return "no OpenGL context: " + error;
  // A long render beats the heart at each point where it can be cancelled, so /healthz and the
  // systemd watchdog tell a render that makes progress from a stuck world thread.
  renderer_->setCancel(&cancel_, [this] { telemetry_.beat(); });
  return "";
}

void RenderService::close() {
  renderer_.reset();
}

std::string RenderService::glName() const {
  return renderer_->platform().device;
}

std::string RenderService::backendName() const {
  return renderer_->platform().backend;
}

namespace {

// A side of a prewarm frame: a few pixels, such that the side and its halvings to 1/32 (rounded
// up: the passes' reduced targets and bins) are powers of two exactly where the view's are.
// llvmpipe generates a shader's code anew for a texture that is a power of two where the last
// was not.
int prewarmSide(int side) {
  auto pattern = [](int n) {
    unsigned bits = 0;
    for (int k = 0; k < 6; ++k) {
      const int halved = (n + (1 << k) - 1) >> k;
      bits |= unsigned((halved & (halved - 1)) == 0) << k;
    }
    return bits;
  };
  for (int small = 48; small < side && small <= 512; ++small)
    if (pattern(small) == pattern(side)) return small;
  return side;
}

}  // namespace

// The catalogue: per air (the scene's, and haze and fog where it has neither), per genus as the
// one weather layer (none first), per view, the camera below, inside and above the layer.
struct RenderService::Prewarm {
  struct Air {
    std::optional<Haze> haze;
    std::optional<Fog> fog;
  };
  std::vector<Air> airs;
  std::size_t step = 0, steps = 0;
  std::unique_ptr<World> world;  // of the step's air and genus
  std::size_t world_of = std::size_t(-1);
  int frames = 0, programs = 0;
  double ms = 0.0;
};

bool RenderService::prewarmStep(const std::vector<ViewConfig>& views) {
  const Scene& base = config_.scene.scene;
  if (!prewarm_) {
    prewarm_ = std::make_unique<Prewarm>();
    Prewarm& p = *prewarm_;
    p.airs = {{base.haze, base.fog}};
    if (!base.haze) p.airs.push_back({Haze{}, base.fog});
    if (!base.fog) p.airs.push_back({base.haze, Fog{}});
    p.steps = p.airs.size() * kCloudTypeCount * views.size() * 3;
    spdlog::info("event=prewarm_started steps={}", p.steps);
  }
  Prewarm& p = *prewarm_;
  if (p.step >= p.steps) return false;
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t position = p.step % 3, view_index = p.step / 3 % views.size();
  const std::size_t sky = p.step / 3 / views.size();  // air * kCloudTypeCount + genus
  const int type = int(sky % kCloudTypeCount);
  ++p.step;
  const WeatherLayer layer = typicalWeatherLayer(CloudType(type), 0.5);
  if (p.world_of != sky) {
    p.world = std::make_unique<World>(base, config_.scene.dynamics);
    const Prewarm::Air& air = p.airs[sky / kCloudTypeCount];
    p.world->setHaze(air.haze);
    p.world->setFog(air.fog);
    if (type > 0) p.world->setWeather({}, layer);
    p.world_of = sky;
  }
  if (type == 0 && position > 0) return true;  // a clear sky looks the same from any height
  const double top = layer.base_m + layer.thickness_m;
  const std::pair<double, double> poses[] = {
      {2.0, 15.0}, {0.5 * (layer.base_m + top), 0.0}, {top + 1000.0, -20.0}};
  const ViewConfig& view = views[view_index];
  Camera camera = view.camera;  // its lens, at a few pixels
  camera.width = prewarmSide(camera.width);
  camera.height = prewarmSide(camera.height);
  camera.position.z = poses[position].first;
  camera.orientation.pitch_deg = poses[position].second;
  const Scene& scene = p.world->seenFrom(camera);
  // A new continuous view, whose second frame reuses its first, then a single render.
  std::string name = "prewarm ";  // appended, not summed: GCC 12 warns -Wrestrict on the sum
  name.append(view.name).append("/").append(std::to_string(p.step));
  for (int continuous : {1, 1, 0}) {
    renderer_->setContinuousView(continuous ? name : std::string());
    renderer_->renderSrgb8(scene, config_.scene.render);
    p.programs += renderer_->lastFrameStats().programs_compiled;
    ++p.frames;
  }
  renderer_->setContinuousView(std::string());
  p.ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  if (p.step == p.steps) {
    spdlog::info("event=prewarm frames={} programs={} ms={:.0f}", p.frames, p.programs, p.ms);
    p.world.reset();
  }
  return p.step < p.steps;
}

namespace {

// Frames slower than a second are logged with their stages, in full while rare.
LogLimiter& slowFrameLog() {
  static LogLimiter limiter;
  return limiter;
}

// The camera a view is rendered with: an off-axis view renders the centred view that holds it.
Camera renderedCamera(const ViewConfig& view) {
  return view.frustum ? offAxisView(view.camera, *view.frustum).render : view.camera;
}

}  // namespace

std::optional<ProtocolError> RenderService::pixelLimit(const ViewConfig& view) const {
  const Camera camera = renderedCamera(view);
  if (camera.width > Limits::kMaxImageSide || camera.height > Limits::kMaxImageSide)
    return ProtocolError{ErrorCode::kLimit, "frustum: the view it is cut from would be " +
                                                std::to_string(camera.width) + "x" +
                                                std::to_string(camera.height) +
                                                " pixels (allowed: at most " +
                                                std::to_string(Limits::kMaxImageSide) + " a side)"};
  const std::int64_t w = camera.width, h = camera.height;
  if (w * h <= config_.max_image_pixels) return std::nullopt;
  return ProtocolError{ErrorCode::kLimit, "width x height: " + std::to_string(w) + "x" +
                                              std::to_string(h) + " is above the limit of " +
                                              std::to_string(config_.max_image_pixels) + " pixels"};
}

std::optional<ProtocolError> RenderService::platformLimit(const ViewConfig& view,
                                                          const ImageRequest& image,
                                                          bool world_has_targets) const {
  const Camera camera = renderedCamera(view);
  const bool linear = image.format == ImageFormat::kExr || image.floatPlanes();
  const bool targets = needsTargetLayers(world_has_targets, image.planes);
  const std::string error = renderer_->reserve(camera.width, camera.height, linear, targets);
  if (error.empty()) return std::nullopt;
  return ProtocolError{ErrorCode::kLimit, "view " + view.name + ": " + error};
}

void RenderService::render(const World& world, const ViewConfig& view, const ImageRequest& image,
                           std::uint64_t tick, bool continuous, RenderedView& out) {
  renderer_->setContinuousView(continuous ? view.name + "#" + std::to_string(world.edits())
                                          : std::string());
  // An off-axis view is cut from a centred render of the same focal length (exact: a pinhole
  // image moves its principal point when cropped).
  std::optional<OffAxisView> off_axis;
  if (view.frustum) off_axis = offAxisView(view.camera, *view.frustum);
  const Scene& scene = world.seenFrom(off_axis ? off_axis->render : view.camera);
  const auto t0 = std::chrono::steady_clock::now();
  Frame& frame = out.frame;
  const Channels channels = channelsOf(image);
  const RenderSettings& settings = config_.scene.render;
  if (channels.pixels == Channels::Pixels::kPlanes) {
    FrameRequest request;
    request.channels = image.planes;
    if (image.colour) request.channels.add(Channel::kColour);
    if (image.coverage) request.channels.add(Channel::kCoverage);
    request.tick = tick;
    frame = renderer_->render(scene, settings, request);
  } else if (channels.pixels == Channels::Pixels::kLinear) {
    frame.colour = renderer_->renderFloat(scene, settings);
  } else {
    frame.srgb = renderer_->renderSrgb8(scene, settings);
  }
  // Stopping: the frame is incomplete and nothing is sent or counted (docs/RELIABILITY.md).
  if (renderer_->lastFrameCancelled()) throw RenderCancelled{};
  FrameInfo info = frameInfo(view.camera, world.timeSeconds(), tick);
  if (off_axis) {
    const OffAxisView& o = *off_axis;
    frame = frame.cropped(o.x0, o.y0, o.width, o.height);
    info.width = o.width;
    info.height = o.height;
    info.focal_px = o.focal_px;
    info.cx = o.cx;
    info.cy = o.cy;
  }
  if (channels.pixels == Channels::Pixels::kPlanes && off_axis) frame.info = info;
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  telemetry_.noteRender(ms);
  if (ms > 1000.0 && slowFrameLog().admit("slow_frame")) {  // where a slow frame's time went
    std::string stages;
    for (const auto& [stage, stage_ms] : renderer_->lastFrameStats().times.fields())
      if (stage_ms >= 1.0) {
        if (!stages.empty()) stages += ',';
        stages.append(stage).append(":").append(std::to_string(std::lround(stage_ms)));
      }
    spdlog::warn("event=slow_frame view={} width={} height={} pixels={} ms={:.0f} stages={}",
                 view.name, scene.camera.width, scene.camera.height, int(channels.pixels), ms,
                 stages.empty() ? "-" : stages);
  }
  out.meta = {{"view", view.name},           {"width", info.width}, {"height", info.height},
              {"time", world.timeSeconds()}, {"tick", tick},        {"frame", telemetry_.frames()},
              {"camera", cameraJson(info)}};
  if (view.frustum) out.meta["camera"]["frustum"] = frustumJson(*view.frustum);
}

json RenderService::lastFrameJson() const {
  const FrameStats& f = renderer_->lastFrameStats();
  json out = json::object();
  for (const auto& [name, value] : f.fields()) out[name] = value;
  json& ms = out["ms"] = json::object();  // where its time went (FrameTimes)
  for (const auto& [name, value] : f.times.fields()) ms[name] = value;
  return out;
}

bool RenderService::post(std::function<void()> job) {
  return encoder_->post(std::move(job));
}

std::size_t RenderService::encoderDepth() const {
  return encoder_ ? encoder_->depth() : 0;
}

}  // namespace nephele
