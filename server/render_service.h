#pragma once
// The daemon's renderer: the GL back end of the Renderer interface on the world thread, the checks
// a view must pass before any work (the configured pixel limit, the platform's largest target), a
// view rendered at the world's time, and the encoder thread that turns frames into bytes off the
// world thread (PROTOCOL.md, "Images").
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "renderer/encode.h"
#include "renderer/frame.h"
#include "server/daemon_config.h"

namespace nephele {

class Renderer;
class Telemetry;
class World;

// A view as rendered, before encoding: its frame (8-bit, linear or float planes, as its
// ImageRequest asked) and the fields of its image header.
struct RenderedView {
  Frame frame;
  nlohmann::json meta;
};

// Thrown by RenderService::render when the daemon's stop cancelled the render in hand; the
// run loop answers the request "shutting down".
struct RenderCancelled {};

// The pixels an image request asks for: float planes with ground-truth channels, else colour
// and coverage, linear for EXR and 8-bit sRGB otherwise.
Channels channelsOf(const ImageRequest& image);
// The container of a protocol image format.
ImageFileFormat fileFormatOf(ImageFormat format);
// Encodes a rendered view as `image` asks; on failure returns the error.
Encoded encodeView(const RenderedView& view, const ImageRequest& image,
                   const EncodeOptions& options);
// An image header's fields: the frame's view, pose, time and tick, and how it is encoded.
nlohmann::json imageMeta(const RenderedView& view, const ImageRequest& image);

class RenderService {
 public:
  static constexpr std::size_t kEncoderQueue = 16;  // images waiting for the encoder thread

  RenderService(const DaemonConfig& config, Telemetry& telemetry);
  ~RenderService();

  // The encoder thread, started before the world thread (which posts to it).
  void startEncoder();
  // Sends what the encoder holds, then stops its thread; posts after this are refused.
  void finishEncoder();
  // World thread: the GL context and renderer; empty, or why there is none.
  std::string open();
  // World thread: the renderer and context go (GL objects while their context is current).
  void close();
  // Any thread: the render in hand ends at its next batch boundary (RenderCancelled).
  void cancel() { cancel_ = true; }
  // The GL renderer's name and its platform's (EGL, OSMesa), for the log.
  std::string glName() const;
  std::string backendName() const;

  // World thread, after each round of its work ([world] prewarm): one step of drawing every
  // view small once per genus as the scene's one weather layer, from below, inside and above
  // it, as a subscription's first two frames and as a single render, with the scene's air and
  // again with haze and with fog where it has none. The programs those frames use are compiled,
  // and llvmpipe's code for them generated, so that a weather change compiles nothing
  // (docs/ACCURACY.md, "Frame budget"). False once every step is done; logs
  // event=prewarm_started and event=prewarm.
  bool prewarmStep(const std::vector<ViewConfig>& views);

  // The configured pixel limit, on the centred view an off-axis view is cut from.
  std::optional<ProtocolError> pixelLimit(const ViewConfig& view) const;
  // Whether this GL can allocate the target `view` needs for `image` (a size within the
  // configured pixel limit may still be more than the platform holds); asked before any work.
  std::optional<ProtocolError> platformLimit(const ViewConfig& view, const ImageRequest& image,
                                             bool world_has_targets) const;

  // Renders `view` of the world now (float for EXR, else 8-bit; planes with ground truth),
  // numbered as the next frame. `continuous`: a frame of a subscription's stream, which may
  // reuse the view's last frame until the world is edited (RenderSettings::heap_refresh).
  void render(const World& world, const ViewConfig& view, const ImageRequest& image,
              std::uint64_t tick, bool continuous, RenderedView& out);
  // The last frame's passes and times (renderer/frame_stats.h) for stats.
  nlohmann::json lastFrameJson() const;

  // The encoder thread: false when it holds kEncoderQueue images, or has finished.
  bool post(std::function<void()> job);
  bool encoderFull() const { return encoderDepth() >= kEncoderQueue; }
  std::size_t encoderDepth() const;  // any thread

 private:
  class Encoder;
  struct Prewarm;

  const DaemonConfig& config_;
  Telemetry& telemetry_;
  std::unique_ptr<Renderer> renderer_;
  std::unique_ptr<Encoder> encoder_;
  std::unique_ptr<Prewarm> prewarm_;
  std::atomic<bool> cancel_{false};
};

}  // namespace nephele
