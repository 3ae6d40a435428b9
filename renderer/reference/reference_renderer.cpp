#include "renderer/reference/reference_renderer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <optional>
#include <thread>
#include <vector>

#include "world/automaton/cloud_density.h"
#include "world/formations/ellipsoid.h"
#include "world/frames.h"
#include "world/textures/layer_texture.h"

namespace nephele {
namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Entry and exit distances of origin + s * direction through an axis-aligned box (empty when
// exit <= entry).
std::pair<double, double> boxSpan(glm::dvec3 lo, glm::dvec3 hi, glm::dvec3 origin,
                                  glm::dvec3 direction) {
  double enter = -kInfinity, leave = kInfinity;
  for (int a = 0; a < 3; ++a) {
    if (direction[a] == 0.0) {
      if (origin[a] < lo[a] || origin[a] > hi[a]) return {0.0, -1.0};
      continue;
    }
    const double s0 = (lo[a] - origin[a]) / direction[a], s1 = (hi[a] - origin[a]) / direction[a];
    enter = std::max(enter, std::min(s0, s1));
    leave = std::min(leave, std::max(s0, s1));
  }
  return {enter, leave};
}

// One translucent surface on a ray, already shaded and fogged.
struct Surface {
  double distance;
  glm::dvec3 colour;
  double alpha;  // 1 - TR
};

struct EllipsoidEntry {
  EllipsoidView view;
  std::size_t cloud;
  double fade;  // in-cloud model: the surface fades as the eye nears it
};

class ReferenceTracer {
 public:
  explicit ReferenceTracer(const Scene& scene) : scene_(scene), sun_(sunDirection(scene.sun)) {
    textures_.reserve(scene.layers.size());
    for (const CloudLayer& layer : scene.layers) textures_.emplace_back(layer.texture);
    solid_textures_.reserve(scene.clouds.size());
    std::vector<const SolidTexture*> solid_pointers;
    for (std::size_t c = 0; c < scene.clouds.size(); ++c) {
      solid_pointers.push_back(&solid_textures_.emplace_back(scene.clouds[c].texture));
      for (const Ellipsoid& e : scene.clouds[c].ellipsoids) {
        EllipsoidView view(e, scene.camera.position);
        if (view.eyeInside()) continue;  // MODEL.md section 4: no surface to show
        const double fade = surfaceFade(view.eyeRadius());
        if (fade > 0.0) ellipsoids_.push_back({view, c, fade});
      }
    }
    veil_ = inCloudVeil(
        scene.clouds, [&](std::size_t c) -> const SolidTexture& { return *solid_pointers[c]; },
        scene.camera.position, scene.sun);
  }

  // Colour and coverage along one ray (unit direction).
  glm::dvec4 trace(glm::dvec3 direction, std::vector<Surface>& surfaces) const {
    const glm::dvec3 eye = scene_.camera.position;
    double nearest_opaque = direction.z < 0.0 ? eye.z / -direction.z : kInfinity;
    glm::dvec3 colour = skyBackground(scene_.sky, direction);
    for (const Target& target : scene_.targets) {
      const auto hit = intersectTarget(target, eye, direction);
      if (!hit || hit->distance >= nearest_opaque) continue;
      nearest_opaque = hit->distance;
      colour = targetRadiance(target, hit->normal, sun_, -direction, scene_.sun);
    }
    colour = withFog(colour, direction, nearest_opaque);

    surfaces.clear();
    for (std::size_t i = 0; i < scene_.layers.size(); ++i) {
      const double s = (scene_.layers[i].altitude_m - eye.z) / direction.z;
      if (s > 0.0 && s <= nearest_opaque && std::isfinite(s))
        surfaces.push_back(layerSurface(scene_.layers[i], textures_[i], direction, s));
    }
    for (const EllipsoidEntry& entry : ellipsoids_) {
      const auto span = entry.view.intersect(direction);
      if (span && span->near > 0.0 && span->near <= nearest_opaque)
        surfaces.push_back(ellipsoidSurface(entry, direction, span->near));
    }
    for (const AutomatonCloudView& cloud : scene_.automata)
      if (const auto surface = volumeSurface(cloud, direction, nearest_opaque))
        surfaces.push_back(*surface);
    std::sort(surfaces.begin(), surfaces.end(),
              [](const Surface& a, const Surface& b) { return a.distance > b.distance; });

    double translucence_product = 1.0;
    for (const Surface& surface : surfaces) {                                    // back to front
      colour = surface.alpha * surface.colour + (1.0 - surface.alpha) * colour;  // "over"
      translucence_product *= 1.0 - surface.alpha;
    }
    // The in-cloud veil sits at the eye, in front of everything.
    colour = veil_.opacity * veil_.colour + (1.0 - veil_.opacity) * colour;
    translucence_product *= 1.0 - veil_.opacity;
    return {colour, 1.0 - translucence_product};
  }

 private:
  Surface layerSurface(const CloudLayer& layer, const LayerTexture& texture, glm::dvec3 direction,
                       double s) const {
    const glm::dvec3 p = scene_.camera.position + s * direction;
    const double t = texture.value({p.x, p.y}, scene_.time_s);
    const double base =
        layer.far.side_ratio > 0.0 ? farThreshold(layer.far, direction) : layer.threshold;
    const double t1 = regionThreshold(base, layerRegionWeight(layer, {p.x, p.y}, scene_.time_s,
                                                              glm::dvec2(scene_.camera.position)));
    const double tr = skyPlaneTranslucence(t, t1, layer.transition);
    const double intensity =
        layer.far.side_ratio > 0.0
            ? gardnerIntensity(layer.shading, sphereDiffuse(glm::dot(sun_, -direction)), 0.0, t)
            : gardnerIntensity(layer.shading, t, {0.0, 0.0, 1.0}, sun_, -direction);
    return {s, withFog(intensity * layer.colour * scene_.sun.colour, direction, s), 1.0 - tr};
  }

  Surface ellipsoidSurface(const EllipsoidEntry& entry, glm::dvec3 direction, double s) const {
    const EllipsoidCloud& cloud = scene_.clouds[entry.cloud];
    const glm::dvec3 p = scene_.camera.position + s * direction;
    const double t = solid_textures_[entry.cloud].value(p - scene_.clouds[entry.cloud].drift_m);
    const double tr = ellipsoidTranslucence(t, cloud.threshold_centre, cloud.threshold_limb,
                                            entry.view.limb(direction), cloud.transition);
    const double intensity =
        gardnerIntensity(cloud.shading, t, entry.view.normalAt(direction, s), sun_, -direction);
    return {s, withFog(intensity * cloud.colour * scene_.sun.colour, direction, s),
            (1.0 - tr) * entry.fade};
  }

  // An automaton cloud along the ray, as one surface at the ray's entry into its box: MODEL.md
  // section 6's single scattering with the exact metaball density, marched in steps of l/8 with the
  // exact exponential per step; sunlight marched towards the sun, and sky light straight up, in
  // steps of l/4 the same way.
  std::optional<Surface> volumeSurface(const AutomatonCloudView& cloud, glm::dvec3 direction,
                                       double nearest_opaque) const {
    const glm::dvec3 eye = scene_.camera.position;
    auto [enter, leave] = boxSpan(cloud.lowerBound(), cloud.upperBound(), eye, direction);
    enter = std::max(enter, 0.0);
    leave = std::min(leave, nearest_opaque);
    if (!(leave > enter)) return std::nullopt;
    const double step = cloud.cell_size_m / 8.0;
    const int steps = int(std::ceil((leave - enter) / step));
    const double ds = (leave - enter) / steps;
    const glm::dvec3 light = cloud.colour * scene_.sun.colour;
    const double phase = cloud.phaseValue(glm::dot(sun_, direction));
    glm::dvec3 radiance(0.0);
    double transmittance = 1.0;
    // Density, and the light reaching the point: sun (times the phase function) and sky.
    auto sample = [&](double s, double& rho, double& lit) {
      const glm::dvec3 p = eye + s * direction;
      rho = cloud.exactDensity(p);
      lit = rho > 0.0 ? phase * std::exp(-opticalDepthTowards(cloud, p, sun_)) +
                            cloud.ambient *
                                diffuseTransmittance(opticalDepthTowards(cloud, p, {0.0, 0.0, 1.0}))
                      : 0.0;
    };
    double rho_a, lit_a;
    sample(enter, rho_a, lit_a);
    for (int i = 1; i <= steps && transmittance > 1e-7; ++i) {
      double rho_b, lit_b;
      sample(enter + i * ds, rho_b, lit_b);
      const double segment = segmentTransmittance(rho_a, rho_b, ds);
      // Source constant over the step (the mean of its ends); exact attenuation within it.
      const double source = 0.5 * (lit_a + lit_b);
      radiance += transmittance * (1.0 - segment) * source * light;
      transmittance *= segment;
      rho_a = rho_b;
      lit_a = lit_b;
    }
    const double alpha = 1.0 - transmittance;
    if (alpha <= 0.0) return std::nullopt;
    return Surface{enter, withFog(radiance / alpha, direction, enter), alpha};
  }

  // Optical depth from p out of the cloud's box along the unit direction `towards`.
  double opticalDepthTowards(const AutomatonCloudView& cloud, glm::dvec3 p,
                             glm::dvec3 towards) const {
    const double leave = boxSpan(cloud.lowerBound(), cloud.upperBound(), p, towards).second;
    if (!(leave > 0.0)) return 0.0;
    const int steps = int(std::ceil(leave / (cloud.cell_size_m / 4.0)));
    const double ds = leave / steps;
    double tau = 0.0, rho_a = cloud.exactDensity(p);
    for (int i = 1; i <= steps; ++i) {
      const double rho_b = cloud.exactDensity(p + (i * ds) * towards);
      tau += kCloudExtinctionPerMetre * 0.5 * (rho_a + rho_b) * ds;
      rho_a = rho_b;
    }
    return tau;
  }

  glm::dvec3 withFog(glm::dvec3 colour, glm::dvec3 direction, double distance) const {
    if (!scene_.fog) return colour;
    const double length = fogPathLength(*scene_.fog, scene_.camera.position, direction, distance);
    const double transmittance = std::exp(-fogExtinction(*scene_.fog) * length);
    return transmittance * colour + (1.0 - transmittance) * scene_.fog->colour;
  }

  const Scene& scene_;
  glm::dvec3 sun_;
  std::vector<LayerTexture> textures_;
  std::vector<SolidTexture> solid_textures_;
  std::vector<EllipsoidEntry> ellipsoids_;
  Veil veil_;
};

}  // namespace

FloatImage renderReference(const Scene& scene, const ReferenceSettings& settings,
                           const std::function<void(double)>& progress) {
  const Camera& camera = scene.camera;
  FloatImage image{camera.width, camera.height,
                   std::vector<float>(std::size_t(camera.width) * camera.height * 4)};
  const Scene with_fields =
      scene.fields.empty() ? Scene{} : withFieldClouds(scene, settings.heap_range_m);
  const ReferenceTracer tracer(scene.fields.empty() ? scene : with_fields);
  const ViewBasis basis = viewBasis(camera);
  const int n = std::max(1, settings.samples_per_axis);

  std::atomic<int> next_row{0};
  auto work = [&](bool report) {
    std::vector<Surface> hits;
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
