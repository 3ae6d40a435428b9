#include "renderer/reference_renderer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <thread>
#include <vector>

#include "world/frames.h"
#include "world/layer_texture.h"

namespace nephele {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

struct LayerHit {
  double distance;
  const CloudLayer* layer;
  const LayerTexture* texture;
};

class ReferenceTracer {
 public:
  explicit ReferenceTracer(const Scene& scene) : scene_(scene), sun_(sunDirection(scene.sun)) {
    textures_.reserve(scene.layers.size());
    for (const CloudLayer& layer : scene.layers) textures_.emplace_back(layer.texture);
  }

  // Colour and coverage along one ray (unit direction).
  glm::dvec4 trace(glm::dvec3 direction, std::vector<LayerHit>& hits) const {
    const glm::dvec3 eye = scene_.camera.position;
    const double ground = direction.z < 0.0 ? eye.z / -direction.z : kInfinity;
    glm::dvec3 colour = withFog(skyBackground(scene_.sky, direction), direction, ground);

    hits.clear();
    for (std::size_t i = 0; i < scene_.layers.size(); ++i) {
      const double s = (scene_.layers[i].altitude_m - eye.z) / direction.z;
      if (s > 0.0 && s <= ground && std::isfinite(s))
        hits.push_back({s, &scene_.layers[i], &textures_[i]});
    }
    std::sort(hits.begin(), hits.end(),
              [](const LayerHit& a, const LayerHit& b) { return a.distance > b.distance; });

    double translucence_product = 1.0;
    for (const LayerHit& hit : hits) {  // back to front
      const glm::dvec3 p = eye + hit.distance * direction;
      const double t = hit.texture->value({p.x, p.y}, scene_.time_s);
      const CloudLayer& layer = *hit.layer;
      const double tr = skyPlaneTranslucence(t, layer.threshold, layer.transition);
      const double intensity =
          gardnerIntensity(layer.shading, t, {0.0, 0.0, 1.0}, sun_, -direction);
      const glm::dvec3 surface =
          withFog(intensity * layer.colour * scene_.sun.colour, direction, hit.distance);
      colour = (1.0 - tr) * surface + tr * colour;  // "over", alpha = 1 - TR
      translucence_product *= tr;
    }
    return {colour, 1.0 - translucence_product};
  }

 private:
  glm::dvec3 withFog(glm::dvec3 colour, glm::dvec3 direction, double distance) const {
    if (!scene_.fog) return colour;
    const double length = fogPathLength(*scene_.fog, scene_.camera.position, direction, distance);
    const double transmittance = std::exp(-fogExtinction(*scene_.fog) * length);
    return transmittance * colour + (1.0 - transmittance) * scene_.fog->colour;
  }

  const Scene& scene_;
  glm::dvec3 sun_;
  std::vector<LayerTexture> textures_;
};

}  // namespace

FloatImage renderReference(const Scene& scene, const ReferenceSettings& settings,
                           const std::function<void(double)>& progress) {
  const Camera& camera = scene.camera;
  FloatImage image{camera.width, camera.height,
                   std::vector<float>(std::size_t(camera.width) * camera.height * 4)};
  const ReferenceTracer tracer(scene);
  const ViewBasis basis = viewBasis(camera);
  const int n = std::max(1, settings.samples_per_axis);

  std::atomic<int> next_row{0};
  auto work = [&](bool report) {
    std::vector<LayerHit> hits;
    int reported_tenths = 0;
    for (int y; (y = next_row.fetch_add(1)) < camera.height;) {
      if (report && progress && y * 10 / camera.height > reported_tenths) {
        reported_tenths = y * 10 / camera.height;
        progress(double(y) / camera.height);
      }
      for (int x = 0; x < camera.width; ++x) {
        glm::dvec4 sum(0.0);
        for (int sy = 0; sy < n; ++sy)
          for (int sx = 0; sx < n; ++sx) {
            const glm::dvec3 d =
                glm::normalize(rayDirection(basis, camera, x + (sx + 0.5) / n, y + (sy + 0.5) / n));
            sum += tracer.trace(d, hits);
          }
        const glm::dvec4 mean = sum / double(n * n);
        float* out = image.pixel(x, y);
        for (int c = 0; c < 4; ++c) out[c] = float(mean[c]);
      }
    }
  };
  const int threads = settings.threads > 0 ? settings.threads
                                           : std::max(1, int(std::thread::hardware_concurrency()));
  std::vector<std::jthread> pool;
  for (int i = 1; i < threads; ++i) pool.emplace_back(work, false);
  work(true);
  pool.clear();  // join before the image is handed out
  return image;
}

}  // namespace nephele
