#include <spdlog/spdlog.h>

#include <filesystem>
#include <map>

#include "renderer/renderer.h"
#include "server/engine_state.h"

// Frames: rendering a view, encoding off the world thread, render replies, subscriptions and
// the Modbus render coil's files.
namespace nephele {

using namespace engine_detail;

namespace engine_detail {

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

}  // namespace engine_detail

void Engine::renderFrame(const ViewConfig& view, const ImageRequest& image, RenderedView& out,
                         bool continuous) {
  State& s = *state_;
  // A subscription's frames are one stream: its heaps reuse the last frame until the world is
  // edited (RenderSettings::heap_refresh); a request's frame is the exact one.
  s.renderer->setContinuousView(continuous ? view.name + "#" + std::to_string(s.world->edits())
                                           : std::string());
  Scene scene = s.world->scene();
  scene.camera = view.camera;
  // An off-axis view is cut from a centred render of the same focal length (exact: a pinhole
  // image moves its principal point when cropped).
  std::optional<OffAxisView> off_axis;
  if (view.frustum) {
    off_axis = offAxisView(view.camera, *view.frustum);
    scene.camera = off_axis->render;
  }
  const auto t0 = Clock::now();
  Frame& frame = out.frame;
  const Channels channels = channelsOf(image);
  if (channels.pixels == Channels::Pixels::kPlanes) {
    FrameRequest request;
    request.channels = image.planes;
    if (image.colour) request.channels.add(Channel::kColour);
    if (image.coverage) request.channels.add(Channel::kCoverage);
    request.tick = std::uint64_t(s.ticks);
    frame = s.renderer->renderFrame(scene, config_.scene.render, request);
  } else if (channels.pixels == Channels::Pixels::kLinear) {
    frame.colour = s.renderer->renderFloat(scene, config_.scene.render);
  } else {
    frame.srgb = s.renderer->renderSrgb8(scene, config_.scene.render);
  }
  // Stopping: the frame is incomplete and nothing is sent or counted (docs/RELIABILITY.md).
  if (s.renderer->lastFrameCancelled()) throw RenderCancelled{};
  FrameInfo info = frameInfo(view.camera, s.world->timeSeconds(), std::uint64_t(s.ticks));
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
  noteRender(msSince(t0));
  out.meta = {{"view", view.name},         {"width", info.width},
              {"height", info.height},     {"time", s.world->timeSeconds()},
              {"tick", s.ticks},           {"frame", s.frames},
              {"camera", cameraJson(info)}};
  if (view.frustum) out.meta["camera"]["frustum"] = frustumJson(*view.frustum);
}

void Engine::noteRender(double ms) {
  State& s = *state_;
  s.last_render_ms = ms;
  s.render_ms.push_back(ms);
  s.render_seconds.add(ms * 1e-3);
  if (s.render_ms.size() > kRenderHistory) s.render_ms.pop_front();
  ++s.frames;
}

namespace {

// The camera a view is rendered with: an off-axis view renders the centred view that holds it.
Camera renderedCamera(const ViewConfig& view) {
  return view.frustum ? offAxisView(view.camera, *view.frustum).render : view.camera;
}

}  // namespace

std::optional<ProtocolError> Engine::pixelLimit(const ViewConfig& view) const {
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

std::optional<ProtocolError> Engine::platformLimit(const ViewConfig& view,
                                                   const ImageRequest& image) const {
  const State& s = *state_;
  const Camera camera = renderedCamera(view);
  const bool linear = image.format == ImageFormat::kExr || image.floatPlanes();
  const bool targets = needsTargetLayers(!s.world->base().targets.empty(), image.planes);
  const std::string error = s.renderer->reserveTarget(camera.width, camera.height, linear, targets);
  if (error.empty()) return std::nullopt;
  return ProtocolError{ErrorCode::kLimit, "view " + view.name + ": " + error};
}

std::optional<Outcome> Engine::renderRequest(const command::Render& c, Job& job) {
  State& s = *state_;
  std::vector<ViewConfig> views;
  for (const std::string& name : c.views) {
    const ViewConfig* v = s.view(name);
    if (!v) return unknownView(s.views, name);
    views.push_back(*v);
  }
  if (c.camera) {  // for this render alone: the view itself stays as it is
    applyViewPatch(views.front(), *c.camera);
    if (auto error = pixelLimit(views.front())) return *error;
  }
  if (encoder_->depth() >= kEncoderQueue)
    return ProtocolError{ErrorCode::kBusy, "the image encoder is busy; try again"};
  for (const ViewConfig& v : views)
    if (auto error = platformLimit(v, c.image.value_or(v.image))) return *error;
  // Every view is rendered before anything else runs on this thread: one tick, one world.
  struct Part {
    std::shared_ptr<RenderedView> frame;
    ImageRequest image;
  };
  std::vector<Part> parts;
  bool all_raw = true;
  for (const ViewConfig& v : views) {
    Part part{std::make_shared<RenderedView>(), c.image.value_or(v.image)};
    renderFrame(v, part.image, *part.frame);
    all_raw = all_raw && part.image.format == ImageFormat::kRaw && !part.image.floatPlanes();
    parts.push_back(std::move(part));
  }
  auto send = [parts, id = job.request.id, reply = job.reply, options = config_.encode,
               encode_ms = &last_encode_ms_]() {
    std::vector<SharedReply> replies;
    for (std::size_t i = 0; i < parts.size(); ++i) {
      const auto t0 = Clock::now();
      auto encoded = encodeView(*parts[i].frame, parts[i].image, options);
      encode_ms->store(msSince(t0));
      if (auto* e = std::get_if<std::string>(&encoded)) {
        reply(makeReply(errorReply(id, {ErrorCode::kFailed, *e})));
        return;
      }
      auto bytes = std::make_shared<const std::vector<std::uint8_t>>(
          std::move(std::get<std::vector<std::uint8_t>>(encoded)));
      json meta = imageMeta(*parts[i].frame, parts[i].image);
      if (parts.size() > 1) {
        meta["part"] = i;
        meta["parts"] = parts.size();
      }
      replies.push_back(makeReply(imageReplyHeader(id, std::move(meta), bytes->size()), bytes));
    }
    reply(chainReplies(std::move(replies)));
  };
  publish();  // before the reply can go: a client's next stats is answered from it
  if (all_raw)
    send();  // nothing to encode: packing is a copy
  else
    encoder_->post(send);  // room was checked above, and only this thread posts
  return std::nullopt;
}

std::map<std::string, std::vector<Engine::Subscription*>> Engine::dueByView(
    Delivery which, const std::string& view_name) {
  State& s = *state_;
  const auto now = Clock::now();
  std::map<std::string, std::vector<Subscription*>> by_view;
  for (Subscription& sub : s.subscriptions) {
    const bool due = which == Delivery::kDue         ? now >= sub.next_due
                     : which == Delivery::kEveryTick ? sub.last_tick != s.ticks
                                                     : sub.view == view_name;
    if (!due) continue;
    if (which == Delivery::kDue) {
      sub.next_due += sub.period;
      if (sub.next_due < now) sub.next_due = now + sub.period;  // a slow render: skip, never burst
    }
    sub.last_tick = s.ticks;
    // A stream whose encoder is still busy drops this frame before it is rendered.
    if (sub.video && sub.video->full()) {
      sub.video->countDropped();
      continue;
    }
    by_view[sub.view].push_back(&sub);
  }
  return by_view;
}

void Engine::deliverFrames(Delivery which, const std::string& view_name) {
  State& s = *state_;
  if (std::erase_if(s.subscriptions, [](const Subscription& sub) { return sub.gone->load(); }))
    countSubscriptions();
  // The subscriptions that are due, grouped by view and by image request: one render per view
  // (and per kind of pixel), one encoding per request.
  for (auto& [name, subs] : dueByView(which, view_name)) {
    const ViewConfig* view = s.view(name);
    if (!view) continue;
    std::shared_ptr<RenderedView> frames[2];  // 8-bit and linear
    std::vector<std::pair<ImageRequest, std::vector<Subscription*>>> groups;
    for (Subscription* sub : subs) {
      auto it = std::find_if(groups.begin(), groups.end(),
                             [&](const auto& g) { return g.first == sub->image; });
      if (it == groups.end())
        groups.push_back({sub->image, {sub}});
      else
        it->second.push_back(sub);
    }
    for (auto& [image, members] : groups) {
      const bool linear = image.format == ImageFormat::kExr;
      std::shared_ptr<RenderedView> planes;  // ground-truth channels: rendered for this group
      std::shared_ptr<RenderedView>& frame = image.floatPlanes() ? planes : frames[linear ? 1 : 0];
      if (!frame) {
        if (auto error = platformLimit(*view, image)) {
          spdlog::error("event=frame_skipped view={} error=\"{}\"", view->name, error->message);
          frames_dropped += members.size();
          continue;
        }
        frame = std::make_shared<RenderedView>();
        renderFrame(*view, image, *frame, /*continuous=*/true);
      }
      sendToSubscribers(frame, image, members);
    }
  }
}

void Engine::sendToSubscribers(const std::shared_ptr<const RenderedView>& frame,
                               const ImageRequest& image,
                               const std::vector<Subscription*>& members) {
  std::vector<Subscription> sinks;  // copies: the encoder may run after a change
  for (Subscription* sub : members) {
    if (sub->video)  // to its own encoder thread, which drops what it cannot take
      sub->video->push(std::shared_ptr<const Srgb8Image>(frame, &frame->frame.srgb), state_->ticks);
    else
      sinks.push_back(*sub);
  }
  if (sinks.empty()) return;
  auto send = [frame, image, sinks, options = config_.encode, encode_ms = &last_encode_ms_]() {
    const auto t0 = Clock::now();
    auto encoded = encodeView(*frame, image, options);
    encode_ms->store(msSince(t0));
    if (auto* e = std::get_if<std::string>(&encoded)) {
      spdlog::error("event=encode_failed error=\"{}\"", *e);
      return;
    }
    auto bytes = std::make_shared<const std::vector<std::uint8_t>>(
        std::move(std::get<std::vector<std::uint8_t>>(encoded)));
    const json meta = imageMeta(*frame, image);
    for (const Subscription& sub : sinks)
      if (!sub.sink(makeReply(frameEventHeader(sub.id, meta, bytes->size()), bytes)))
        sub.gone->store(true);
  };
  if (image.format == ImageFormat::kRaw && !image.floatPlanes())
    send();
  else if (!encoder_->post(send))
    frames_dropped += sinks.size();
}

Outcome Engine::startStream(const command::Stream& c) {
  State& s = *state_;
  const ViewConfig* view = s.view(c.view);
  if (!view) return unknownView(s.views, c.view);
  const auto streams = std::count_if(s.subscriptions.begin(), s.subscriptions.end(),
                                     [](const Subscription& sub) { return sub.video != nullptr; });
  if (streams >= ProtocolLimits::kMaxStreams)
    return ProtocolError{ErrorCode::kLimit, "stream: the daemon streams " +
                                                std::to_string(ProtocolLimits::kMaxStreams) +
                                                " views already (at most)"};
  Subscription sub;
  sub.image = ImageRequest{};
  sub.image.coverage = false;
  if (auto error = platformLimit(*view, sub.image)) return *error;
  auto opened = VideoStream::open(c.settings, view->camera.width, view->camera.height);
  if (auto* error = std::get_if<std::string>(&opened))
    return ProtocolError{ErrorCode::kFailed, "stream: " + *error};
  sub.video = std::move(std::get<std::unique_ptr<VideoStream>>(opened));
  sub.id = s.next_subscription++;
  sub.client = 0;  // the daemon's: it outlives the connection that started it
  sub.view = c.view;
  sub.address = c.settings.address;
  sub.period = secondsToDuration(1.0 / c.settings.rate_hz);
  sub.next_due = Clock::now();
  sub.gone = std::make_shared<std::atomic<bool>>(false);
  s.subscriptions.push_back(sub);
  countSubscriptions();
  const VideoStream& video = *sub.video;
  spdlog::info("event=stream_started stream={} view={} address={} encoder={} size={}x{}", sub.id,
               sub.view, sub.address, video.encoderName(), video.width(), video.height());
  json out{{"stream", sub.id},
           {"view", sub.view},
           {"address", sub.address},
           {"encoder", video.encoderName()},
           {"width", video.width()},
           {"height", video.height()},
           {"rate", c.settings.rate_hz},
           {"bitrate", c.settings.bitrate_kbps},
           {"keyframe_interval", c.settings.keyframe_interval}};
  if (!video.sdp().empty()) out["sdp"] = video.sdp();
  return out;
}

Outcome Engine::stopStream(const command::Unstream& c) {
  State& s = *state_;
  const auto it =
      std::find_if(s.subscriptions.begin(), s.subscriptions.end(),
                   [&](const Subscription& sub) { return sub.video && sub.id == c.stream; });
  if (it == s.subscriptions.end())
    return ProtocolError{ErrorCode::kNotFound,
                         "stream: " + std::to_string(c.stream) + " is not a streamed view"};
  const VideoStreamStats counts = it->video->stats();
  s.subscriptions.erase(it);
  countSubscriptions();
  spdlog::info("event=stream_stopped stream={} sent={} dropped={}", c.stream, counts.sent,
               counts.dropped);
  return json{{"stream", c.stream}, {"sent", counts.sent}, {"dropped", counts.dropped}};
}

json Engine::streamsJson() const {
  json out = json::array();
  for (const Subscription& sub : state_->subscriptions) {
    if (!sub.video) continue;
    const VideoStreamStats counts = sub.video->stats();
    out.push_back({{"stream", sub.id},
                   {"view", sub.view},
                   {"address", sub.address},
                   {"encoder", sub.video->encoderName()},
                   {"sent", counts.sent},
                   {"dropped", counts.dropped},
                   {"bytes", counts.bytes},
                   {"encode_ms", counts.encode_ms},
                   {"encode_cpu_ms", counts.encode_cpu_ms}});
  }
  return out;
}

void Engine::renderTrigger() {
  State& s = *state_;
  const ViewConfig& view = *s.view(config_.modbus_view);
  const bool linear = config_.output_format == ImageFormat::kExr;
  auto frame = std::make_shared<RenderedView>();
  ImageRequest image;
  image.format = config_.output_format;
  if (auto error = platformLimit(view, image)) {
    spdlog::error("event=render_trigger_failed view={} error=\"{}\"", view.name, error->message);
    return;
  }
  renderFrame(view, image, *frame);
  const std::string extension = config_.output_format == ImageFormat::kPng    ? ".png"
                                : config_.output_format == ImageFormat::kJpeg ? ".jpg"
                                                                              : ".exr";
  // Named by the frame counter, which a snapshot restores; a name already taken (a restart
  // without a snapshot) gets a suffix, so an earlier frame is never overwritten.
  const std::filesystem::path directory(config_.output_directory);
  const std::string stem = view.name + "_" + std::to_string(s.frames);
  std::filesystem::path path = directory / (stem + extension);
  for (int n = 1; std::filesystem::exists(path) && n < 1000000; ++n)
    path = directory / (stem + "." + std::to_string(n) + extension);
  // The caller checked that the encoder has room, and only this thread feeds it; the
  // subscribers' frames come after.
  // 8-bit files are for viewing: colour only; EXR holds coverage as its alpha.
  const Channels channels =
      linear ? Channels{{Channel::kColour, Channel::kCoverage}, Channels::Pixels::kLinear}
             : Channels{{Channel::kColour}, Channels::Pixels::kSrgb8};
  encoder_->post([this, frame, channels, path, options = config_.encode]() {
    std::error_code ec;
    std::filesystem::create_directories(path.parent_path(), ec);
    // writeImage picks the format from the extension and renames into place.
    const std::string e = writeImage(path.string(), frame->frame, channels, options);
    if (!e.empty()) {  // counted before it is logged: whoever reads the log sees it in stats
      noteError(ErrorCode::kFailed);
      spdlog::error("event=render_trigger_failed error=\"{}\"", e);
    } else {
      spdlog::info("event=render_trigger path={}", path.string());
    }
    trigger_pending_ = false;
  });
  deliverFrames(Delivery::kView, view.name);
}

}  // namespace nephele
