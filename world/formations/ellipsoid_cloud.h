#pragma once
// Gardner's cloud formations: clusters of textured, translucent ellipsoids sharing one colour,
// one texture and one set of thresholds (MODEL.md sections 4 and 5), and the in-cloud fog a
// camera sees when it flies into one.
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "world/formations/ellipsoid.h"
#include "world/shading.h"
#include "world/sky.h"
#include "world/textures/solid_texture.h"

namespace nephele {

struct EllipsoidCloud {
  std::string name;
  glm::dvec3 colour{1.0, 1.0, 1.0};  // linear RGB
  double threshold_centre = 0.25;    // Gardner's T1
  double threshold_limb = 0.6;       // Gardner's T2 (Elinas' "T2" is T2 - T1)
  double transition = 0.25;          // D, >= 0
  ShadingParams shading{0.35, 0.5, 0.0, 8.0};
  // Extinction per metre of the light passing through the cloud's ellipsoids (MODEL.md section
  // 14): lobes shadowed by others, dark bases, a silver lining. 0 is Gardner's eq. 8 alone.
  double light_extinction = 0.0;
  SolidTextureSpec texture;
  std::vector<Ellipsoid> ellipsoids;
  // The separately lit parts its ellipsoids fall into (MODEL.md section 14): ellipsoid i is in
  // part parts[i]. Empty (a scene file's clouds) groups them by overlap instead. Generated
  // heaps set it, one part per heap and one per cumulonimbus anvil; it is not saved.
  std::vector<std::uint32_t> parts;
  // How far the cloud has drifted since time 0. Its ellipsoid centres already include it; the
  // texture is looked up at (X - drift) so that it moves with the cloud.
  glm::dvec3 drift_m{0.0};
};

// `cloud` with `ellipsoids` and their `parts` in place of its own, the rest copied (and its
// own lobes not).
inline EllipsoidCloud withLobes(const EllipsoidCloud& cloud, std::vector<Ellipsoid> ellipsoids,
                                std::vector<std::uint32_t> parts) {
  // Every member by name: this stops compiling when EllipsoidCloud gains one.
  const auto& [name, colour, threshold_centre, threshold_limb, transition, shading,
               light_extinction, texture, own_ellipsoids, own_parts, drift_m] = cloud;
  static_cast<void>(own_ellipsoids), static_cast<void>(own_parts);
  return EllipsoidCloud{
      name,    colour,           threshold_centre, threshold_limb,        transition,
      shading, light_extinction, texture,          std::move(ellipsoids), std::move(parts),
      drift_m};
}

// An axis-aligned box holding every ellipsoid of the cloud (each taken as the ball of its
// longest semi-axis); one pass over the ellipsoids.
struct BoundingBox {
  glm::dvec3 lo{0.0}, hi{0.0};
};
BoundingBox boundingBox(const EllipsoidCloud& cloud);
// A sphere holding every ellipsoid of the cloud: the middle of that box, and the largest
// distance from it to a centre plus that ellipsoid's longest semi-axis.
struct BoundingSphere {
  glm::dvec3 centre{0.0};
  double radius = 0.0;
};
BoundingSphere boundingSphere(const EllipsoidCloud& cloud);

// The lowest and highest altitudes its ellipsoids reach.
std::pair<double, double> cloudVerticalExtent(const EllipsoidCloud& cloud);
// The middle of that extent: the altitude whose wind carries the cloud.
double cloudAltitude(const EllipsoidCloud& cloud);

// A cumulus heap of `count` ellipsoids over a base at `base_centre` (the middle of its flat
// bottom), about `width_m` across: a wide flat base row and smaller rounder lobes stacked
// towards the top. Deterministic in `seed`.
std::vector<Ellipsoid> cumulusEllipsoids(int count, glm::dvec3 base_centre, double width_m,
                                         std::uint64_t seed);

// In-cloud fog. The papers leave the view from inside an ellipsoid to the renderer; this model is
// shared by the GL renderer and the reference so both show the same thing.
//
// With rho = |W (eye - centre)| (1 on the surface, 0 at the centre) and a band
// w = kInCloudBand:
// - the ellipsoid's own surface fades out as the eye comes within w of it from outside:
//   its opacity is multiplied by surfaceFade(rho) = smoothstep(1, 1 + w, rho);
// - a veil at the eye takes over: opacity veilOpacity(rho) = 1 - smoothstep(1 - w, 1 + w, rho),
//   0 beyond 1 + w, 1/2 on the surface, 1 deeper than 1 - w.
// Both are continuous in the eye position, so entering or leaving a cloud has no jump.
// The veil's colour is Gardner eq. 8 for a horizontal surface lit from above (Id = max(0,
// L.z), no highlight) with It the cloud's texture at the eye, times cloud and sun colours.
// Several veils combine order-independently: opacity 1 - prod(1 - v_i), colour the
// opacity-weighted mean.
inline constexpr double kInCloudBand = 0.25;
double surfaceFade(double eye_radius);
double veilOpacity(double eye_radius);

// The combined veil over everything, straight (not premultiplied) colour and opacity;
// opacity 0 when the eye is far from every ellipsoid.
struct Veil {
  glm::dvec3 colour{0.0};
  double opacity = 0.0;
};
// `texture(i)` is cloud i's texture, asked for only when the eye is within the veil band of
// one of its ellipsoids (the caller keeps it built). Ellipsoids farther from the eye than
// (1 + kInCloudBand) times their longest semi-axis are passed over without a transform, so a
// world of many clouds costs a distance test per ellipsoid.
Veil inCloudVeil(std::span<const EllipsoidCloud* const> clouds,
                 const std::function<const SolidTexture&(std::size_t)>& texture, glm::dvec3 eye,
                 const Sun& sun);
Veil inCloudVeil(const std::vector<EllipsoidCloud>& clouds,
                 const std::function<const SolidTexture&(std::size_t)>& texture, glm::dvec3 eye,
                 const Sun& sun);

}  // namespace nephele
