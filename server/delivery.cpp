#include <spdlog/spdlog.h>

#include <filesystem>
#include <map>

#include "image/video_stream.h"
#include "renderer/encode.h"
#include "server/engine_detail.h"

// Frames: rendering a view, encoding off the world thread, render replies, subscriptions and
// the Modbus render coil's files.
namespace nephele {

using namespace engine_detail;

void Engine::renderView(const ViewConfig& view, const ImageRequest& image, RenderedView& out,
                        bool continuous) {
  renders_->render(*world_, view, image, clock_.ticks(), continuous, out);
}

std::optional<ProtocolError> Engine::platformLimit(const ViewConfig& view,
                                                   const ImageRequest& image) const {
  return renders_->platformLimit(view, image, !world_->base().targets.empty());
}

std::optional<Outcome> Engine::renderRequest(const command::Render& c, Job& job) {
  std::vector<ViewConfig> views;
  for (const std::string& name : c.views) {
    const ViewConfig* v = views_.find(name);
    if (!v) return views_.unknown(name);
    views.push_back(*v);
  }
  if (c.camera) {  // for this render alone: the view itself stays as it is
    applyViewPatch(views.front(), *c.camera);
    if (auto error = renders_->pixelLimit(views.front())) return *error;
  }
  if (renders_->encoderFull())
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
  const auto rendering = Clock::now();
  for (const ViewConfig& v : views) {
    Part part{std::make_shared<RenderedView>(), c.image.value_or(v.image)};
    renderView(v, part.image, *part.frame);
    all_raw = all_raw && part.image.format == ImageFormat::kRaw && !part.image.floatPlanes();
    parts.push_back(std::move(part));
  }
  if (job.trace) job.trace->render_ms = msSince(rendering);
  auto send = [parts, id = job.request.id, reply = job.reply, options = config_.encode,
               telemetry = &telemetry_, trace = job.trace]() {
    std::vector<SharedReply> replies;
    for (std::size_t i = 0; i < parts.size(); ++i) {
      const auto t0 = Clock::now();
      auto encoded = encodeView(*parts[i].frame, parts[i].image, options);
      telemetry->noteEncode(msSince(t0));
      if (trace) trace->encode_ms += msSince(t0);
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
  if (job.trace) job.trace->applied = Clock::now();  // before the encoder has the trace
  if (all_raw)
    send();  // nothing to encode: packing is a copy
  else
    renders_->post(send);  // room was checked above, and only this thread posts
  return std::nullopt;
}

void Engine::deliverFrames(Delivery which, const std::string& view_name) {
  views_.dropGone();
  // The subscriptions that are due, grouped by view and by image request: one render per view
  // (and per kind of pixel), one encoding per request.
  const Clock::time_point now = Clock::now();
  bool rendered = false;
  for (auto& [name, due] : views_.due(which, view_name, clock_.ticks(), now)) {
    const ViewConfig* view = views_.find(name);
    if (!view) continue;
    std::shared_ptr<RenderedView> frames[2];  // 8-bit and linear
    std::vector<std::pair<ImageRequest, std::vector<Subscription*>>> groups;
    for (Subscription* sub : due) {
      auto it = std::find_if(groups.begin(), groups.end(),
                             [&](const auto& g) { return g.first == sub->image; });
      if (it == groups.end())
        groups.push_back({sub->image, {sub}});
      else
        it->second.push_back(sub);
    }
    for (auto& [image, candidates] : groups) {
      const bool linear = image.format == ImageFormat::kExr;
      std::shared_ptr<RenderedView> planes;  // ground-truth channels: rendered for this group
      std::shared_ptr<RenderedView>& frame = image.floatPlanes() ? planes : frames[linear ? 1 : 0];
      // Realtime frames yield to requests: once one render is done, requests waiting are
      // served before the next, so that none waits behind a whole round of subscriptions. The
      // subscriptions not served stay due, the most overdue first (docs/RELIABILITY.md).
      // Lockstep's frames are the tick's and are all rendered.
      if (which == Delivery::kDue && rendered && !frame && queue_.depth() > 0) return;
      const std::vector<Subscription*> members =
          views_.take(candidates, which, clock_.ticks(), now);
      if (members.empty()) continue;
      if (!frame) {
        if (auto error = platformLimit(*view, image)) {
          spdlog::error("event=frame_skipped view={} error=\"{}\"", view->name, error->message);
          telemetry_.frames_dropped += members.size();
          continue;
        }
        frame = std::make_shared<RenderedView>();
        renderView(*view, image, *frame, /*continuous=*/true);
        rendered = true;
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
      sub->video->push(srgb8Pixels(std::shared_ptr<const Frame>(frame, &frame->frame)),
                       clock_.ticks());
    else
      sinks.push_back(*sub);
  }
  if (sinks.empty()) return;
  auto send = [frame, image, sinks, options = config_.encode, telemetry = &telemetry_]() {
    const auto t0 = Clock::now();
    auto encoded = encodeView(*frame, image, options);
    telemetry->noteEncode(msSince(t0));
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
  else if (!renders_->post(send))
    telemetry_.frames_dropped += sinks.size();
}

Outcome Engine::startStream(const command::Stream& c) {
  const ViewConfig* view = views_.find(c.view);
  if (!view) return views_.unknown(c.view);
  if (views_.streams() >= ProtocolLimits::kMaxStreams)
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
  sub.client = 0;  // the daemon's: it outlives the connection that started it
  sub.view = c.view;
  sub.address = c.settings.address;
  sub.period = secondsToDuration(1.0 / c.settings.rate_hz);
  sub.next_due = Clock::now();
  sub.gone = std::make_shared<std::atomic<bool>>(false);
  sub.id = views_.subscribe(sub);
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
  const Subscription* stream = views_.stream(c.stream);
  if (!stream)
    return ProtocolError{ErrorCode::kNotFound,
                         "stream: " + std::to_string(c.stream) + " is not a streamed view"};
  const VideoStreamStats counts = stream->video->stats();
  views_.endStream(c.stream);
  spdlog::info("event=stream_stopped stream={} sent={} dropped={}", c.stream, counts.sent,
               counts.dropped);
  return json{{"stream", c.stream}, {"sent", counts.sent}, {"dropped", counts.dropped}};
}

void Engine::renderTrigger() {
  const ViewConfig& view = *views_.find(config_.modbus_view);
  const bool linear = config_.output_format == ImageFormat::kExr;
  auto frame = std::make_shared<RenderedView>();
  ImageRequest image;
  image.format = config_.output_format;
  if (auto error = platformLimit(view, image)) {
    spdlog::error("event=render_trigger_failed view={} error=\"{}\"", view.name, error->message);
    return;
  }
  renderView(view, image, *frame);
  // The frame counter it moved, published before the encoder can write the file and clear the
  // coil: a host that sees the coil at 0 reads the new count.
  publishReadings();
  const std::string extension = config_.output_format == ImageFormat::kPng    ? ".png"
                                : config_.output_format == ImageFormat::kJpeg ? ".jpg"
                                                                              : ".exr";
  // Named by the frame counter, which a snapshot restores; a name already taken (a restart
  // without a snapshot) gets a suffix, so an earlier frame is never overwritten.
  const std::filesystem::path directory(config_.output_directory);
  const std::string stem = view.name + "_" + std::to_string(telemetry_.frames());
  std::filesystem::path path = directory / (stem + extension);
  for (int n = 1; std::filesystem::exists(path) && n < 1000000; ++n)
    path = directory / (stem + "." + std::to_string(n) + extension);
  // The caller checked that the encoder has room, and only this thread feeds it; the
  // subscribers' frames come after.
  // 8-bit files are for viewing: colour only; EXR holds coverage as its alpha.
  const Channels channels =
      linear ? Channels{{Channel::kColour, Channel::kCoverage}, Channels::Pixels::kLinear}
             : Channels{{Channel::kColour}, Channels::Pixels::kSrgb8};
  renders_->post([this, frame, channels, path, options = config_.encode]() {
    std::error_code ec;
    std::filesystem::create_directories(path.parent_path(), ec);
    // writeImage picks the format from the extension and renames into place.
    const std::string e = writeImage(path.string(), frame->frame, channels, options);
    if (!e.empty()) {  // counted before it is logged: whoever reads the log sees it in stats
      telemetry_.noteError(ErrorCode::kFailed);
      spdlog::error("event=render_trigger_failed error=\"{}\"", e);
    } else {
      spdlog::info("event=render_trigger path={}", path.string());
    }
    trigger_pending_ = false;
  });
  deliverFrames(Delivery::kView, view.name);
}

}  // namespace nephele
