#include "renderer/renderer.h"

#include <algorithm>
#include <limits>

#include "renderer/gl/gl_renderer.h"
#include "renderer/reference/reference_renderer.h"

namespace nephele {
namespace {

class GlBackendRenderer final : public Renderer {
 public:
  GlBackendRenderer(std::unique_ptr<GlPlatform> platform, const RenderSettings& settings)
      : platform_(std::move(platform)), gl_(*platform_), settings_(settings) {}
  Frame render(const Scene& scene, const FrameRequest& request) override {
    return gl_.renderFrame(scene, settings_, request);
  }
  Srgb8Image renderSrgb8(const Scene& scene) override { return gl_.renderSrgb8(scene, settings_); }
  std::string reserve(int width, int height, bool linear, bool targets) override {
    return gl_.reserveTarget(width, height, linear, targets);
  }
  std::string statsLine() const override { return gl_.lastFrameStats().line(); }
  std::string description() const override {
    return "gl: " + std::string(platform_->backendName()) + ", OpenGL " + platform_->version() +
           ", GL_RENDERER " + platform_->renderer();
  }

 private:
  std::unique_ptr<GlPlatform> platform_;
  GlRenderer gl_;
  RenderSettings settings_;
};

class ReferenceBackendRenderer final : public Renderer {
 public:
  explicit ReferenceBackendRenderer(const ReferenceSettings& settings) : settings_(settings) {}
  Frame render(const Scene& scene, const FrameRequest& request) override {
    return renderReferenceFrame(scene, settings_, request, progress_);
  }
  Srgb8Image renderSrgb8(const Scene& scene) override {
    return toSrgb8(renderReferenceFrame(scene, settings_, {}, progress_).colour);
  }
  std::string reserve(int, int, bool, bool) override { return ""; }
  std::string description() const override {
    const std::string n = std::to_string(settings_.samples_per_axis);
    return "reference: " + n + "x" + n + " samples per pixel";
  }

 private:
  ReferenceSettings settings_;
};

}  // namespace

std::unique_ptr<Renderer> createRenderer(const RendererOptions& options, std::string& error) {
  if (options.kind == RendererKind::kReference)
    return std::make_unique<ReferenceBackendRenderer>(options.reference);
  std::unique_ptr<GlPlatform> platform = createGlPlatform(options.gl_backend, error);
  if (!platform) return nullptr;
  return std::make_unique<GlBackendRenderer>(std::move(platform), options.render);
}

void dimVisibilityByPrecipitation(Frame& frame, const Scene& scene, const HeapDrawing& heaps) {
  if (frame.visibility.empty() || !hasPrecipitation(scene)) return;
  const PrecipitationMedia media = precipitationMedia(scene, heaps);
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
