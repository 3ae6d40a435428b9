#pragma once
// Light through a heap (MODEL.md section 14): how much sunlight and sky light reaches a point
// on a lobe through the heap it belongs to, the heap taken as its envelope (an ellipsoid
// holding its lobes, filled with their mean extinction), evaluated per surface point so that
// the light runs on smoothly from lobe to lobe and the heap has one terminator; and the
// forward-scattered light a thin edge gives off with the sun behind it (the silver lining).
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "world/formations/ellipsoid_cloud.h"

namespace nephele {

// The heap a lobe belongs to, as it is lit: an axis-aligned ellipsoid and the extinction per
// metre inside it. extinction 0 leaves Gardner's eq. 8 unchanged.
struct HeapEnvelope {
  glm::dvec3 centre{0.0};
  glm::dvec3 radii{1.0};
  double extinction = 0.0;
};

// One envelope per ellipsoid of `cloud`. The cloud's ellipsoids fall into heaps: its parts
// when it names them (EllipsoidCloud::parts), else groups joined pairwise where the centre of
// either ellipsoid lies within 1.25 times the other (lobes that sit on one another); a heap's
// envelope is the axis-aligned ellipsoid with the second moments of its ellipsoids taken as
// solids (semi-axes sqrt(5 variance) about their centroid, which is an ellipsoid itself when
// alone and axis-aligned), and its extinction the cloud's light_extinction times the share
// of the envelope its ellipsoids fill (the sum of their volumes over the envelope's, at most
// 1). All extinctions are 0 when the cloud's light_extinction is 0.
std::vector<HeapEnvelope> heapEnvelopes(const EllipsoidCloud& cloud);

// The heap each ellipsoid of `cloud` belongs to, as heapEnvelopes groups them: the index of
// one ellipsoid of its heap (the same for all of them).
std::vector<std::size_t> heapGroups(const EllipsoidCloud& cloud);

// Volume-weighted moments of solid ellipsoids, and the axis-aligned ellipsoid that has them
// (semi-axes sqrt(5 variance) about the centroid; none while nothing was added).
struct SecondMoments {
  double volume = 0.0;
  glm::dvec3 first{0.0}, second{0.0};  // sums of V c and V (diag(T T^T) / 5 + c^2)
  void add(const Ellipsoid& e);
  std::optional<Ellipsoid> ellipsoid() const;
};

// Whether point p lies inside the envelope (on its surface included).
inline bool insideEnvelope(const HeapEnvelope& envelope, glm::dvec3 p) {
  const glm::dvec3 o = (p - envelope.centre) / envelope.radii;
  return glm::dot(o, o) <= 1.0;
}

// Length of the ray p + s dir (dir unit, s >= 0) inside the envelope, metres.
double envelopeChord(const HeapEnvelope& envelope, glm::dvec3 p, glm::dvec3 dir);

// The share of the sun's and of the sky's light reaching point p, of outward unit normal n,
// through its heap: the two-stream transmittance (diffuseTransmittance) of the optical depth
// towards the sun (`to_sun`, unit), and half the sky's from overhead through the heap, half
// from the horizon and the ground, which it does not hide: sky = 1/2 + 1/2 T(depth straight
// up). The depth towards v is the envelope's extinction times its chord from p along v,
// times (1 - n.v) / 2: a face turned towards the light looks out of the heap, not through it.
// `direct`: the share of the unscattered sunbeam, exp(-depth towards the sun), which alone
// feeds the light a thin edge scatters forward (heapIntensity).
struct HeapLight {
  double sun = 1.0;
  double sky = 1.0;
  double direct = 1.0;
};
HeapLight heapLightAt(const HeapEnvelope& envelope, glm::dvec3 p, glm::dvec3 normal,
                      glm::dvec3 to_sun);

// Gardner eq. 8 with the heap's light at the surface point (MODEL.md section 14): the diffuse
// and highlight terms take the sunlight reaching it (the diffuse term through the skin,
// skinDiffuse), the ambient term the sky light, and light scattered forward through the
// surface's translucent part is added,
//   I = (1 - a){(1 - t)[(1 - s) S Id' + s S Is] + t It} + a K + S P(cos theta) / (4 pi) TR,
// P the Cornette-Shanks phase function with the droplets' asymmetry, cos theta = d . to_sun
// for the view direction d, TR the surface's translucence (Gardner eq. 11). With the cloud's
// light_extinction 0 it is eq. 8 with its sun terms times S (the sunlight the clouds above let
// through, MODEL.md section 16; 1 unshadowed).
double heapIntensity(const EllipsoidCloud& cloud, const HeapLight& light, double texture_value,
                     glm::dvec3 normal, glm::dvec3 to_sun, glm::dvec3 direction,
                     double translucence);

// The normal a heap-lit surface point takes its light with (MODEL.md section 14, "one mass"):
// the lobe's outward unit normal bent towards its heap envelope's at p by kHeapNormalBend,
// normalize((1 - b) n + b n_envelope), so that the heap, not each lobe, has the terminator
// and the lobes keep part of their relief. `normal` itself when the envelope has no
// extinction (eq. 8 unchanged) or p is at its centre.
inline constexpr double kHeapNormalBend = 0.6;
glm::dvec3 heapLitNormal(const HeapEnvelope& envelope, glm::dvec3 p, glm::dvec3 normal);

// Sunlight through a lobe's own skin (MODEL.md section 14): a heap-lit lobe takes the diffuse
// term as max(0, (N.L + w) / (1 + w)) instead of max(0, N.L), since light entering its sunlit
// face is scattered on round the lobe before it leaves, and the face turned from the sun is
// lit through the lobe's edge. w = kSkinWrap.
inline constexpr double kSkinWrap = 0.6;
double skinDiffuse(double n_dot_l);

// The light a surface standing for many heaps (the far deck) takes: over the surfaces of the
// cloud's ellipsoids, each weighted by its horizontal cross-section, the mean of S skinDiffuse
// as a multiple of the Lambertian mean max(0, n.L) (1/4), and the mean of K; each ellipsoid's
// surface sampled at 64 normals spread evenly over the sphere.
struct MeanHeapLight {
  double sun_over_lambert = 1.0;
  double sky = 1.0;
};
MeanHeapLight meanHeapLight(const EllipsoidCloud& cloud, glm::dvec3 to_sun);

// L.sun P(cos theta) / (4 pi): the forward-scattered term alone.
double forwardScattered(double sun, double cos_theta);

}  // namespace nephele
