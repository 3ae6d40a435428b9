#include "renderer/reference/reference_renderer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <thread>
#include <vector>

#include "renderer/frame_plan.h"
#include "renderer/renderer.h"
#include "world/automaton/cloud_density.h"
#include "world/camera.h"
#include "world/formations/cloud_shadow.h"
#include "world/formations/ellipsoid.h"
#include "world/formations/heap_light.h"
#include "world/sea.h"
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

// One translucent surface on a ray, already shaded and seen through the air.
struct Surface {
  double distance;
  glm::dvec3 colour;
  double alpha;  // 1 - TR
  // Where the surface's own opacity is reached: its distance, except for a volume, whose
  // march puts it where the volume's transmittance first falls to 1/2 (or, for a thinner
  // volume, to half its own opacity).
  double half_distance;
};

// What one ray's centre sample shows besides colour (renderer/frame.h).
struct RayLabels {
  double depth = kInfinity;
  double cloud_depth = kInfinity;
  int object_id = 0;
  double lwir = 0.0;   // with an infrared model
  double glint = 0.0;  // the sea's sun glint, luminance as seen
};

double luminance(glm::dvec3 c) {
  return 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
}

// The sea where a ray meets it (MODEL.md section 18).
struct SeaView {
  SeaShading shading;
  glm::dvec3 colour{0.0};  // its radiance, before the air
};

struct EllipsoidEntry {
  EllipsoidView view;
  std::size_t cloud;
  double fade;            // in-cloud model: the surface fades as the eye nears it
  HeapEnvelope envelope;  // MODEL.md section 14
  double top;             // its highest point's altitude
};

class ReferenceTracer {
 public:
  // `view`: what the camera sees (renderer/frame_plan.h); `probe`: what the sea mirrors, the
  // view's probe, or null for none; `shadows`: the ground's cloud shadows (MODEL.md section 16),
  // or null for none.
  ReferenceTracer(const ViewPlan& view, const ViewPlan* probe, const CloudShadows* shadows,
                  int sea_waves = kSeaComponents)
      : scene_(*view.scene),
        clouds_(view.clouds),
        sun_(sunDirection(scene_.sun)),
        shadows_(shadows) {
    const Scene& scene = scene_;
    textures_.reserve(scene.layers.size());
    for (const CloudLayer& layer : scene.layers) textures_.emplace_back(layer.texture);
    solid_textures_.reserve(clouds_.size());
    std::vector<const SolidTexture*> solid_pointers;
    for (std::size_t c = 0; c < clouds_.size(); ++c) {
      const EllipsoidCloud& cloud = view.cloud(c);
      solid_pointers.push_back(&solid_textures_.emplace_back(cloud.texture));
      const std::vector<HeapEnvelope> envelopes = heapEnvelopes(cloud);
      for (std::size_t i = 0; i < envelopes.size(); ++i) {
        EllipsoidView ellipsoid(cloud.ellipsoids[i], scene.camera.position);
        if (ellipsoid.eyeInside()) continue;  // MODEL.md section 4: no surface to show
        const double fade = surfaceFade(ellipsoid.eyeRadius());
        const Ellipsoid& e = cloud.ellipsoids[i];
        if (fade > 0.0)
          ellipsoids_.push_back(
              {ellipsoid, c, fade, envelopes[i], e.centre.z + verticalHalfExtent(e)});
      }
    }
    veil_ = inCloudVeil(
        clouds_, [&](std::size_t c) -> const SolidTexture& { return *solid_pointers[c]; },
        scene.camera.position, scene.sun);
    if (scene.sea) {
      sea_.emplace(*scene.sea, sea_waves);
      pixel_rad_ = seaPixelAngle(scene.camera.vfov_deg, scene.camera.height);
      if (probe) probe_ = std::make_unique<ReferenceTracer>(*probe, nullptr, shadows);
    }
  }

  // Colour and coverage along one ray (unit direction); the ray's labels if asked.
  // Surfaces beyond `max_distance` are left out.
  glm::dvec4 trace(glm::dvec3 direction, std::vector<Surface>& surfaces,
                   RayLabels* labels = nullptr, double max_distance = kInfinity,
                   const InfraredModel* infrared = nullptr) const {
    const glm::dvec3 eye = scene_.camera.position;
    const double ground_distance = direction.z < 0.0 ? eye.z / -direction.z : kInfinity;
    double nearest_opaque = std::min(ground_distance, max_distance);
    glm::dvec3 colour(0.0);
    int object_id = 0;
    for (std::size_t t = 0; t < scene_.targets.size(); ++t) {
      const Target& target = scene_.targets[t];
      const auto hit = intersectTarget(target, eye, direction);
      if (!hit || hit->distance >= nearest_opaque) continue;
      nearest_opaque = hit->distance;
      object_id = int(t) + 1;
      // In the clouds' shadows (MODEL.md section 16) where the ray meets it.
      colour = targetRadiance(target, hit->normal, sun_, -direction, scene_.sun,
                              sunlight_.at(eye + hit->distance * direction));
    }
    std::optional<SeaView> sea;
    if (object_id == 0) {
      if (sea_ && nearest_opaque == ground_distance && std::isfinite(ground_distance)) {
        sea = seaView(direction, ground_distance);
        colour = sea->colour;
      } else {
        colour = skyBackground(scene_.sky, direction);
        if (direction.z < 0.0 && !sunlight_.empty()) {
          const glm::dvec2 ground = formulas::planeCrossing(eye, 0.0, direction);
          colour *= groundLight(sunlight_.at({ground, 0.0}));
        }
      }
    }
    colour = withAir(colour, direction, nearest_opaque);

    surfacesAlong(direction, nearest_opaque, surfaces);

    double translucence_product = 1.0;
    for (const Surface& surface : surfaces) {                                    // back to front
      colour = surface.alpha * surface.colour + (1.0 - surface.alpha) * colour;  // "over"
      translucence_product *= 1.0 - surface.alpha;
    }
    // The in-cloud veil sits at the eye, in front of everything.
    colour = veil_.opacity * veil_.colour + (1.0 - veil_.opacity) * colour;
    translucence_product *= 1.0 - veil_.opacity;
    if (labels) {
      labels->depth = nearest_opaque;
      labels->object_id = sea ? int(kSeaObjectId) : object_id;
      // The glint as seen: through the air (throughAir is linear in the colour behind), the
      // clouds and the veil.
      labels->glint = 0.0;
      if (sea)
        labels->glint = luminance(withAir(sea->shading.glint, direction, nearest_opaque) -
                                  withAir(glm::dvec3(0.0), direction, nearest_opaque)) *
                        translucence_product;
      labels->cloud_depth = kInfinity;
      // Front to back: the first surface after which the cloud opacity is 1/2 or more.
      double transmittance = 1.0 - veil_.opacity;
      if (transmittance <= 0.5) labels->cloud_depth = 0.0;
      for (auto s = surfaces.rbegin(); s != surfaces.rend() && transmittance > 0.5; ++s) {
        transmittance *= 1.0 - s->alpha;
        if (transmittance <= 0.5) labels->cloud_depth = s->half_distance;
      }
      if (infrared)
        labels->lwir = infraredRadiance(*infrared, direction, surfaces, object_id, nearest_opaque,
                                        sea ? &*sea : nullptr);
    }
    return {colour, 1.0 - translucence_product};
  }

 private:
  // The surfaces the ray meets before `nearest_opaque`, back to front: layers, ellipsoids and
  // automaton clouds.
  void surfacesAlong(glm::dvec3 direction, double nearest_opaque,
                     std::vector<Surface>& surfaces) const {
    const glm::dvec3 eye = scene_.camera.position;
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
  }

  // MODEL.md section 12: the opaque surface or clear sky behind, then every cloud surface back
  // to front as a grey body at the air temperature of its altitude, emissivity its opacity.
  double infraredRadiance(const InfraredModel& model, glm::dvec3 direction,
                          const std::vector<Surface>& surfaces, int object_id,
                          double nearest_opaque, const SeaView* sea) const {
    const glm::dvec3 eye = scene_.camera.position;
    const double elevation = std::asin(std::clamp(direction.z, -1.0, 1.0));
    double radiance;
    if (object_id > 0) {
      radiance = bandRadiance(model, targetTemperature(model, object_id - 1));
    } else if (sea) {  // emissivity 1 - F by the angle on the resolved waves, the sky mirrored
      const double e = seaEmissivity(sea->shading.cos_incidence);
      const double mirrored = std::asin(std::clamp(sea->shading.reflect_dir.z, 0.0, 1.0));
      radiance = e * bandRadiance(model, scene_.sea->temperature_c + 273.15) +
                 (1.0 - e) * clearSkyRadiance(model, mirrored, 0.0);
    } else if (std::isfinite(nearest_opaque)) {  // the ground, reflecting the sky a little
      radiance = model.ground_emissivity * bandRadiance(model, model.ground_k) +
                 (1.0 - model.ground_emissivity) * clearSkyRadiance(model, -elevation, 0.0);
    } else {
      radiance = clearSkyRadiance(model, elevation, eye.z);
    }
    for (const Surface& s : surfaces) {  // back to front
      const double z = eye.z + s.half_distance * direction.z;
      radiance =
          s.alpha * bandRadiance(model, airTemperature(model, z)) + (1.0 - s.alpha) * radiance;
    }
    return veil_.opacity * bandRadiance(model, airTemperature(model, eye.z)) +
           (1.0 - veil_.opacity) * radiance;
  }

  Surface layerSurface(const CloudLayer& layer, const LayerTexture& texture, glm::dvec3 direction,
                       double s) const {
    const glm::dvec3 p = scene_.camera.position + s * direction;
    const double t = texture.value({p.x, p.y}, scene_.time_s);
    const double t1 = layerThreshold(layer, {p.x, p.y}, direction, scene_.time_s,
                                     glm::dvec2(scene_.camera.position));
    const double tr = skyPlaneTranslucence(t, t1, layer.transition);
    const double intensity =
        layer.far.side_ratio > 0.0
            ? gardnerIntensity(layer.shading, sphereDiffuse(glm::dot(sun_, -direction)), 0.0, t)
            : gardnerIntensity(layer.shading, t, {0.0, 0.0, 1.0}, sun_, -direction);
    // Shadows from the planes above, and from the heaps where every one lies above (MODEL.md
    // section 16, "planes under heaps").
    const glm::dvec3 at(p.x, p.y, layer.altitude_m);
    double sun = planes_.sunlight(at);
    const bool under_heaps =
        shadows_ && !shadows_->empty() && layer.altitude_m <= shadows_->floor();
    if (under_heaps) sun *= shadows_->sunlightAt(at);
    const double shadow = planes_.empty() && !under_heaps ? 1.0 : groundLight(sun);
    return {s, withAir(shadow * intensity * layer.colour * scene_.sun.colour, direction, s),
            1.0 - tr, s};
  }

  Surface ellipsoidSurface(const EllipsoidEntry& entry, glm::dvec3 direction, double s) const {
    const EllipsoidCloud& cloud = *clouds_[entry.cloud];
    const glm::dvec3 p = scene_.camera.position + s * direction;
    const double t = solid_textures_[entry.cloud].value(p - cloud.drift_m);
    const double tr = ellipsoidTranslucence(t, cloud.threshold_centre, cloud.threshold_limb,
                                            entry.view.limb(direction), cloud.transition);
    // Turned towards the viewer, then bent towards the heap's (MODEL.md section 14).
    glm::dvec3 normal = entry.view.normalAt(direction, s);
    normal = formulas::facingViewer(normal, direction);
    normal = heapLitNormal(entry.envelope, p, normal);
    // The heap's own light, and the sunlight the other clouds above let through (MODEL.md
    // sections 14 and 16).
    HeapLight light = heapLightAt(entry.envelope, p, normal, sun_);
    const double outside = sunlight_.at(p, &entry.envelope, entry.top);
    light.sun *= outside;
    light.direct *= outside;
    const double intensity = heapIntensity(cloud, light, t, normal, sun_, direction, tr);
    return {s, withAir(intensity * cloud.colour * scene_.sun.colour, direction, s),
            (1.0 - tr) * entry.fade, s};
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
    // Density, and the light the point scatters towards the eye (cloud_density.h scatteredLight).
    auto sample = [&](double s, double& rho, double& lit) {
      const glm::dvec3 p = eye + s * direction;
      rho = cloud.exactDensity(p);
      if (!(rho > 0.0)) {
        lit = 0.0;
        return;
      }
      const double tau_sun = opticalDepthTowards(cloud, p, sun_);
      const double tau_away = opticalDepthTowards(cloud, p, -sun_);
      lit = scatteredLight(phase, std::exp(-tau_sun), diffuseSunlight(tau_sun, tau_away),
                           cloud.ambient,
                           diffuseTransmittance(opticalDepthTowards(cloud, p, {0.0, 0.0, 1.0})));
    };
    double rho_a, lit_a;
    sample(enter, rho_a, lit_a);
    thread_local std::vector<std::pair<double, double>> profile;  // (distance, transmittance)
    profile.clear();
    for (int i = 1; i <= steps && transmittance > 1e-7; ++i) {
      double rho_b, lit_b;
      sample(enter + i * ds, rho_b, lit_b);
      const double segment = segmentTransmittance(rho_a, rho_b, ds);
      profile.emplace_back(enter + i * ds, transmittance * segment);
      // Source constant over the step (the mean of its ends); exact attenuation within it.
      radiance += formulas::stepScattered(transmittance, segment, lit_a, lit_b) * light;
      transmittance *= segment;
      rho_a = rho_b;
      lit_a = lit_b;
    }
    const double alpha = 1.0 - transmittance;
    if (alpha <= 0.0) return std::nullopt;
    double half = enter;
    for (const auto& [s, t] : profile)
      if (1.0 - t >= std::min(0.5, 0.5 * alpha)) {
        half = s;
        break;
      }
    return Surface{enter, withAir(radiance / alpha, direction, enter), alpha, half};
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

  // The sea along unit `direction` at `distance` (MODEL.md section 18): its waves filtered to
  // the pixel's footprint, the sky and clouds it mirrors seen from the sea below the camera
  // (the reflection probe, like the GL's), the water, foam and glint in the clouds' shadows.
  SeaView seaView(glm::dvec3 direction, double distance) const {
    const glm::dvec3 p = scene_.camera.position + distance * direction;
    const SeaSample s =
        sea_->sample({p.x, p.y}, scene_.time_s, seaFootprint(distance, direction.z, pixel_rad_));
    SeaView view;
    view.shading = shadeSea(*sea_, *scene_.sea, s, direction, sun_, scene_.sun.colour,
                            sunlight_.at({p.x, p.y, 0.0}));
    std::vector<Surface> hits;
    const glm::dvec3 mirrored = glm::dvec3(probe_->trace(view.shading.reflect_dir, hits));
    view.colour = view.shading.body_and_foam + view.shading.glint + view.shading.fresnel * mirrored;
    return view;
  }

  glm::dvec3 withAir(glm::dvec3 colour, glm::dvec3 direction, double distance) const {
    return throughAir(colour, scene_.fog, layer_veil_, scene_.haze, scene_.sky.horizon,
                      scene_.camera.position, direction, distance, precipitation_.slabs,
                      precipitation_.shafts);
  }

  const Scene& scene_;
  const std::vector<const EllipsoidCloud*>& clouds_;
  glm::dvec3 sun_;
  const CloudShadows* shadows_;
  std::vector<LayerTexture> textures_;
  std::vector<SolidTexture> solid_textures_;
  std::vector<EllipsoidEntry> ellipsoids_;
  Veil veil_;
  std::optional<Fog> layer_veil_ = inLayerVeil(scene_);  // the camera's, once per frame
  PlaneShadows planes_{scene_};
  SceneSunlight sunlight_{&planes_, shadows_};
  PrecipitationMedia precipitation_ = precipitationMedia(scene_);
  // The sea: its waves, the pixel's angle, and the tracer of what it mirrors.
  std::optional<SeaSurface> sea_;
  double pixel_rad_ = 0.0;
  std::unique_ptr<ReferenceTracer> probe_;
};

}  // namespace

namespace {

// What one frame of the reference asks of each pixel.
struct PixelWork {
  const ReferenceTracer& tracer;
  const Camera& camera;
  ViewBasis basis;
  int samples;  // per axis
  int divisor;  // labels: one in divisor x divisor pixels
  bool colour, labels;
  const InfraredModel* infrared;
};

// Pixel (x, y)'s supersampled colour and coverage.
void traceColour(const PixelWork& w, int x, int y, std::vector<Surface>& hits, Frame& frame) {
  const int n = w.samples;
  glm::dvec4 sum(0.0);
  for (int sy = 0; sy < n; ++sy)
    for (int sx = 0; sx < n; ++sx) {
      const glm::dvec3 d =
          glm::normalize(rayDirection(w.basis, w.camera, x + (sx + 0.5) / n, y + (sy + 0.5) / n));
      sum += w.tracer.trace(d, hits);
    }
  const glm::dvec4 mean = sum / double(n * n);
  const std::size_t i = std::size_t(y) * w.camera.width + x;
  for (int c = 0; c < 4; ++c) frame.colour.rgba[i * 4 + c] = float(mean[c]);
}

// Labels come from the pixel's centre ray, as a rasteriser samples them, or from the centre ray
// of a divisor x divisor block, copied to the block.
void traceLabels(const PixelWork& w, int x, int y, std::vector<Surface>& hits, Frame& frame) {
  const int divisor = w.divisor;
  RayLabels ray;
  w.tracer.trace(
      glm::normalize(rayDirection(w.basis, w.camera, x + 0.5 * divisor, y + 0.5 * divisor)), hits,
      &ray, kInfinity, w.infrared);
  for (int by = y; by < std::min(y + divisor, w.camera.height); ++by)
    for (int bx = x; bx < std::min(x + divisor, w.camera.width); ++bx) {
      const std::size_t i = std::size_t(by) * w.camera.width + bx;
      if (!frame.depth.empty()) frame.depth[i] = float(ray.depth);
      if (!frame.cloud_depth.empty()) frame.cloud_depth[i] = float(ray.cloud_depth);
      if (!frame.object_id.empty()) frame.object_id[i] = float(ray.object_id);
      if (!frame.lwir.empty()) frame.lwir[i] = float(ray.lwir);
      if (!frame.glint.empty()) frame.glint[i] = float(ray.glint);
    }
}

// How the threads of one frame share its rows: the next row to take, and whether a raised
// cancel flag stopped one of them.
struct RowQueue {
  std::atomic<int> next{0};
  std::atomic<bool> stopped{false};
  const ReferenceCancel& cancel;
};

// False, once the queue is marked stopped, when the frame's cancel flag is raised.
bool keepGoing(RowQueue& rows, bool calling_thread) {
  if (!rows.cancel.flag) return true;
  if (calling_thread && rows.cancel.alive) rows.cancel.alive();
  if (!rows.cancel.flag->load(std::memory_order_relaxed)) return true;
  rows.stopped.store(true, std::memory_order_relaxed);
  return false;
}

// The rows taken from `rows` until none is left or the frame is cancelled; `progress` (on the
// calling thread) told about every tenth.
void traceRows(const PixelWork& w, RowQueue& rows, Frame& frame, bool calling_thread,
               const std::function<void(double)>& progress) {
  std::vector<Surface> hits;
  int reported_tenths = 0;
  const int height = w.camera.height;
  for (int y; (y = rows.next.fetch_add(1)) < height;) {
    if (!w.colour && y % w.divisor != 0) continue;
    if (!keepGoing(rows, calling_thread)) return;
    if (calling_thread && progress && y * 10 / height > reported_tenths) {
      reported_tenths = y * 10 / height;
      progress(double(y) / height);
    }
    for (int x = 0; x < w.camera.width; ++x) {
      if (w.colour) traceColour(w, x, y, hits, frame);
      if (w.labels && x % w.divisor == 0 && y % w.divisor == 0) traceLabels(w, x, y, hits, frame);
    }
  }
}

}  // namespace

Frame renderReferenceFrame(const Scene& scene, const ReferenceSettings& settings,
                           const FrameRequest& request, const std::function<void(double)>& progress,
                           const ReferenceCancel& cancel, bool* cancelled) {
  FramePlanRequest plan_request;
  plan_request.heaps = settings.heaps;
  plan_request.sea_eye = true;
  plan_request.heap_shadows = true;
  const FramePlan plan(scene, plan_request);
  return renderReferenceFrame(plan, settings, request, progress, cancel, cancelled);
}

Frame renderReferenceFrame(const FramePlan& plan, const ReferenceSettings& settings,
                           const FrameRequest& request, const std::function<void(double)>& progress,
                           const ReferenceCancel& cancel, bool* cancelled) {
  const Scene& scene = *plan.view.scene;
  const Camera& camera = scene.camera;
  const std::size_t pixels = std::size_t(camera.width) * camera.height;
  const ChannelSet& asked = request.channels;
  Frame frame = frameFor(camera, scene.time_s, request);
  const bool colour = compositeAsked(asked);
  const bool labels = asked.has(Channel::kDepth) || asked.has(Channel::kCloudDepth) ||
                      asked.has(Channel::kObjectId) || asked.has(Channel::kLwir) ||
                      asked.has(Channel::kGlint);
  const InfraredModel* infrared = asked.has(Channel::kLwir) ? &request.infrared : nullptr;
  if (colour) frame.colour = {camera.width, camera.height, std::vector<float>(pixels * 4)};
  if (asked.has(Channel::kDepth)) frame.depth.resize(pixels);
  if (asked.has(Channel::kCloudDepth)) frame.cloud_depth.resize(pixels);
  if (asked.has(Channel::kObjectId)) frame.object_id.resize(pixels);
  if (infrared) frame.lwir.resize(pixels);
  if (asked.has(Channel::kGlint)) frame.glint.resize(pixels);

  const ReferenceTracer tracer(plan.view, plan.sea_eye ? &*plan.sea_eye : nullptr,
                               plan.heap_shadows ? &*plan.heap_shadows : nullptr,
                               settings.sea_waves);
  const PixelWork work{tracer,
                       camera,
                       viewBasis(camera),
                       std::max(1, settings.samples_per_axis),
                       std::max(1, settings.label_divisor),
                       colour,
                       labels,
                       infrared};
  RowQueue rows{.cancel = cancel};
  const int threads = settings.threads > 0 ? settings.threads
                                           : std::max(1, int(std::thread::hardware_concurrency()));
  std::vector<std::jthread> pool;
  for (int i = 1; i < threads; ++i)
    pool.emplace_back([&] { traceRows(work, rows, frame, false, progress); });
  traceRows(work, rows, frame, true, progress);
  pool.clear();  // join before the frame is handed out
  const bool stopped = rows.stopped.load();
  if (cancelled) *cancelled = stopped;
  if (asked.has(Channel::kVisibility) && !stopped) {
    frame.visibilityFromCoverage();
    dimVisibilityByPrecipitation(frame, plan.view);
  }
  return frame;
}

namespace {
FramePlanRequest drawingHeaps(const HeapDrawing& heaps) {
  FramePlanRequest request;
  request.heaps = heaps;
  request.sea_eye = true;
  return request;
}
Scene withoutTargets(Scene scene) {
  scene.targets.clear();
  return scene;
}
}  // namespace

// The probe's scene without its targets, planned once.
struct CloudProbe::State {
  Scene scene;
  FramePlan plan;
  ReferenceTracer tracer;
  State(const Scene& s, const HeapDrawing& heaps)
      : scene(withoutTargets(s)),
        plan(scene, drawingHeaps(heaps)),
        tracer(plan.view, plan.sea_eye ? &*plan.sea_eye : nullptr, nullptr) {}
};

CloudProbe::CloudProbe(const Scene& scene, const HeapDrawing& heaps)
    : state_(std::make_unique<State>(scene, heaps)) {}
CloudProbe::~CloudProbe() = default;

double CloudProbe::transmittance(glm::dvec3 direction, double distance) const {
  std::vector<Surface> surfaces;
  return 1.0 - state_->tracer.trace(glm::normalize(direction), surfaces, nullptr, distance).w;
}

FloatImage renderReference(const Scene& scene, const ReferenceSettings& settings,
                           const std::function<void(double)>& progress) {
  return renderReferenceFrame(scene, settings, {}, progress).colour;
}

}  // namespace nephele
