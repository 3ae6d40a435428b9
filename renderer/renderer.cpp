#include "renderer/renderer.h"

#include <algorithm>
#include <limits>
#include <thread>

#include "renderer/gl/gl_renderer.h"
#include "renderer/reference/reference_renderer.h"

namespace nephele {
namespace {

class GlBackendRenderer final : public Renderer {
 public:
  // Shares `platform`, whose context stays current on this thread, with the renderers
  // another() makes.
  GlBackendRenderer(std::shared_ptr<const GlPlatform> platform, const RenderSettings& settings)
      : Renderer(settings), platform_(std::move(platform)), gl_(*platform_) {}
  Frame render(const Scene& scene, const RenderSettings& settings,
               const FrameRequest& request) override {
    return gl_.renderFrame(scene, settings, request);
  }
  FloatImage renderFloat(const Scene& scene, const RenderSettings& settings) override {
    return gl_.renderFloat(scene, settings);
  }
  Srgb8Image renderSrgb8(const Scene& scene, const RenderSettings& settings) override {
    return gl_.renderSrgb8(scene, settings);
  }
  Srgb8Image renderFloor(int width, int height) override { return gl_.renderFloor(width, height); }
  std::string reserve(int width, int height, bool linear, bool targets) override {
    return gl_.reserveTarget(width, height, linear, targets);
  }
  const FrameStats& lastFrameStats() const override { return gl_.lastFrameStats(); }
  std::string statsLine() const override { return gl_.lastFrameStats().line(); }
  void setContinuousView(std::string view) override { gl_.setContinuousView(std::move(view)); }
  void setCancel(const std::atomic<bool>* flag, std::function<void()> alive) override {
    gl_.setCancel(flag, std::move(alive));
  }
  bool lastFrameCancelled() const override { return gl_.lastFrameCancelled(); }
  RendererPlatform platform() const override {
    return {std::string(platform_->backendName()), platform_->version(), platform_->renderer()};
  }
  std::string description() const override {
    const RendererPlatform p = platform();
    return "gl: " + p.backend + ", OpenGL " + p.version + ", GL_RENDERER " + p.device;
  }
  std::unique_ptr<Renderer> another() const override {
    return std::make_unique<GlBackendRenderer>(platform_, settings_);
  }

 private:
  std::shared_ptr<const GlPlatform> platform_;
  GlRenderer gl_;
};

// The GL floor's colour (GlRenderer::renderFloor), premultiplied linear RGB and coverage.
constexpr float kFloorColour[4] = {0.25f, 0.3f, 0.4f, 0.5f};

class ReferenceBackendRenderer final : public Renderer {
 public:
  ReferenceBackendRenderer(int threads, const RenderSettings& settings)
      : Renderer(settings), threads_(threads) {}
  Frame render(const Scene& scene, const RenderSettings& settings,
               const FrameRequest& request) override {
    return trace(scene, settings, request);
  }
  FloatImage renderFloat(const Scene& scene, const RenderSettings& settings) override {
    return trace(scene, settings, {}).colour;
  }
  Srgb8Image renderSrgb8(const Scene& scene, const RenderSettings& settings) override {
    return toSrgb8(trace(scene, settings, {}).colour);
  }
  // The floor's colour filled and encoded as a frame's colour is: what any frame costs here
  // beside its tracing.
  Srgb8Image renderFloor(int width, int height) override {
    FloatImage image{width, height, std::vector<float>(std::size_t(width) * height * 4)};
    for (std::size_t i = 0; i < image.rgba.size(); ++i) image.rgba[i] = kFloorColour[i % 4];
    return toSrgb8(image);
  }
  std::string reserve(int, int, bool, bool) override { return ""; }
  const FrameStats& lastFrameStats() const override { return stats_; }
  void setCancel(const std::atomic<bool>* flag, std::function<void()> alive) override {
    cancel_ = {flag, std::move(alive)};
  }
  bool lastFrameCancelled() const override { return cancelled_; }
  RendererPlatform platform() const override {
    const int threads =
        threads_ > 0 ? threads_ : std::max(1, int(std::thread::hardware_concurrency()));
    return {"reference", "", "cpu, " + std::to_string(threads) + " threads"};
  }
  std::string description() const override {
    const std::string n = std::to_string(settings_.reference_samples);
    return "reference: " + n + "x" + n + " samples per pixel";
  }
  std::unique_ptr<Renderer> another() const override {
    return std::make_unique<ReferenceBackendRenderer>(threads_, settings_);
  }

 private:
  // This frame as `settings` asks for it, on the renderer's threads.
  Frame trace(const Scene& scene, const RenderSettings& settings, const FrameRequest& request) {
    ReferenceSettings drawn = referenceSettingsOf(settings);
    drawn.threads = threads_;
    return renderReferenceFrame(scene, drawn, request, progress_, cancel_, &cancelled_);
  }

  int threads_;
  ReferenceCancel cancel_;
  bool cancelled_ = false;
  FrameStats stats_;  // stays zero: the reference counts no passes
};

}  // namespace

std::unique_ptr<Renderer> createRenderer(const RendererOptions& options, std::string& error) {
  if (options.kind == RendererKind::kReference)
    return std::make_unique<ReferenceBackendRenderer>(options.reference_threads, options.render);
  std::shared_ptr<const GlPlatform> platform = createGlPlatform(options.gl_backend, error);
  if (!platform) return nullptr;
  return std::make_unique<GlBackendRenderer>(std::move(platform), options.render);
}

void dimVisibilityByPrecipitation(Frame& frame, const ViewPlan& view) {
  const Scene& scene = *view.scene;
  if (frame.visibility.empty() || !hasPrecipitation(scene)) return;
  const PrecipitationMedia media = precipitationMedia(scene);
  if (media.empty()) return;
  const Camera& camera = scene.camera;
  const ViewBasis basis = viewBasis(camera);
  const glm::dvec3 eye = camera.position;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      const glm::dvec3 d = glm::normalize(rayDirection(basis, camera, x + 0.5, y + 0.5));
      double opaque = d.z < 0.0 ? eye.z / -d.z : std::numeric_limits<double>::infinity();
      for (const Target& t : scene.targets)
        if (const auto hit = intersectTarget(t, eye, d)) opaque = std::min(opaque, hit->distance);
      frame.visibility[std::size_t(y) * camera.width + x] *=
          float(precipitationTransmittance(media.slabs, media.shafts, eye, d, opaque));
    }
}

}  // namespace nephele
