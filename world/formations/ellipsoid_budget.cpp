#include "world/scene.h"

#include <algorithm>
#include <cmath>
#include <optional>
#include <span>
#include <vector>

#include "world/camera.h"
#include "world/formations/cloud_field.h"
#include "world/formations/heap_light.h"

// The frame's work budget (MODEL.md section 15): the ellipsoids a frame draws at most, those of
// largest projected size, with the heaps beyond it merged into bodies or left out.
namespace nephele {

double ellipsoidFootprint(const Ellipsoid& e, const Camera& camera, const ViewBasis& basis) {
  const double reach = std::max({e.radii.x, e.radii.y, e.radii.z});
  const glm::dvec3 to = e.centre - camera.position;
  const double ahead = glm::dot(to, basis.forward);
  if (ahead < -reach) return 0.0;
  if (ahead <= reach) return 1.0;  // its bounding sphere reaches the eye's plane
  // The sphere's outline on the image plane at unit distance: centre (x, y), angular radius
  // tan = reach / sqrt(ahead^2 - reach^2); the view spans [-w, w] x [-h, h] there.
  const double h = basis.tan_half_vfov, w = h * basis.aspect;
  const double x = glm::dot(to, basis.right) / ahead, y = glm::dot(to, basis.up) / ahead;
  const double r = reach / std::sqrt(ahead * ahead - reach * reach);
  const double across = std::max(0.0, std::min(x + r, w) - std::max(x - r, -w));
  const double down = std::max(0.0, std::min(y + r, h) - std::max(y - r, -h));
  return across * down / (4.0 * w * h);
}

namespace {

// The budget's order of ellipsoids: the largest radius over the centre's distance along the
// view (at most 1), none for an ellipsoid wholly behind the eye.
double projectedSize(const Ellipsoid& e, const Camera& camera, const ViewBasis& basis) {
  const double reach = std::max({e.radii.x, e.radii.y, e.radii.z});
  const double ahead = glm::dot(e.centre - camera.position, basis.forward);
  return ahead < -reach ? 0.0 : reach / std::max(ahead, reach);
}

// The lobes a budget drops, merged into one body per heap (a cloud's part, or the whole
// cloud when it names none): the ellipsoid of their second moments (heap_light.h), standing
// for their cover (MODEL.md section 15). A heap that lost one lobe loses it unmerged. More
// bodies than `most` would have: one per cloud instead.
constexpr double kBodyScale = 1.5;
constexpr std::size_t kMomentSamples = 512;
// The share of the footprint budget the bodies may take (the largest body always).
constexpr double kBodyShare = 0.25;
struct Body {
  std::uint32_t cloud, part;
  Ellipsoid ellipsoid;
};
std::vector<Body> mergedBodies(std::span<const EllipsoidCloud* const> clouds,
                               const std::vector<std::vector<char>>& kept, std::size_t most) {
  for (bool per_cloud : {false, true}) {
    std::vector<Body> bodies;
    for (std::size_t c = 0; c < clouds.size(); ++c) {
      const EllipsoidCloud& cloud = *clouds[c];
      const std::vector<char>& flags = kept[c];
      const std::size_t lost = std::size_t(std::count(flags.begin(), flags.end(), char(0)));
      if (lost < 2) continue;
      // The moments of a cloud's dropped lobes from at most about kMomentSamples of them, every
      // stride-th in order: a body needs their spread, not each of a million lobes (the 64x48
      // frame of a world at its budget stays within a second).
      const std::size_t stride = std::max<std::size_t>(1, lost / kMomentSamples);
      const bool parts = !per_cloud && cloud.parts.size() == cloud.ellipsoids.size();
      std::map<std::uint32_t, std::pair<SecondMoments, std::size_t>> dropped;  // by part
      std::size_t seen = 0;
      for (std::size_t i = 0; i < cloud.ellipsoids.size(); ++i) {
        if (flags[i] != 0) continue;  // kept (1), or out of the view (2)
        auto& [moments, count] = dropped[parts ? cloud.parts[i] : 0u];
        if (seen++ % stride == 0 || count == 0) moments.add(cloud.ellipsoids[i]);
        ++count;
      }
      for (const auto& [part, merged] : dropped)
        if (merged.second >= 2)
          if (std::optional<Ellipsoid> e = merged.first.ellipsoid()) {
            e->radii *= kBodyScale;
            bodies.push_back({std::uint32_t(c), part, *e});
          }
    }
    if (bodies.size() <= most || per_cloud) return bodies;
  }
  return {};
}

// Every lobe of the clouds ranked for the budget: its projected size (its largest radius over
// its distance along the view; behind the camera, none) and its footprint.
struct LobeSize {
  double size, footprint;
  std::uint32_t cloud, lobe;
};
bool larger(const LobeSize& a, const LobeSize& b) {
  if (a.size != b.size) return a.size > b.size;
  return a.cloud != b.cloud ? a.cloud < b.cloud : a.lobe < b.lobe;
}

// The lobes a budget keeps: the largest while at most `most` and, when `covered`, their
// footprints within `room` (the largest always); sizes[0, keep) holds them.
class LobeChoice {
 public:
  LobeChoice(std::vector<LobeSize> sizes, bool covered)
      : sizes_(std::move(sizes)), keep_(sizes_.size()), covered_(covered) {}

  void choose(std::size_t most, double room) {
    if (most < keep_) {
      std::nth_element(sizes_.begin(), sizes_.begin() + std::ptrdiff_t(most),
                       sizes_.begin() + std::ptrdiff_t(keep_), larger);
      keep_ = most;
    }
    if (!covered_) return;
    if (!sorted_) std::sort(sizes_.begin(), sizes_.begin() + std::ptrdiff_t(keep_), larger);
    sorted_ = true;
    double sum = 0.0;
    std::size_t fit = 0;
    while (fit < keep_ && (fit == 0 || sum + sizes_[fit].footprint <= room))
      sum += sizes_[fit++].footprint;
    keep_ = fit;
  }
  // Per cloud and lobe: 1 kept, 0 dropped, 2 dropped out of the view (left unmerged:
  // mergedBodies merges flags of 0).
  std::vector<std::vector<char>> keptFlags(std::span<const EllipsoidCloud* const> clouds) const {
    std::vector<std::vector<char>> kept(clouds.size());
    for (std::size_t c = 0; c < clouds.size(); ++c) kept[c].assign(clouds[c]->ellipsoids.size(), 0);
    for (std::size_t k = 0; k < keep_; ++k) kept[sizes_[k].cloud][sizes_[k].lobe] = 1;
    for (std::size_t k = keep_; k < sizes_.size(); ++k)
      if (!(sizes_[k].footprint > 0.0)) kept[sizes_[k].cloud][sizes_[k].lobe] = 2;
    return kept;
  }
  std::size_t kept() const { return keep_; }

 private:
  std::vector<LobeSize> sizes_;
  std::size_t keep_;
  bool sorted_ = false;
  bool covered_;
};

std::vector<LobeSize> lobeSizes(std::span<const EllipsoidCloud* const> clouds, std::size_t total,
                                const Camera& camera, const ViewBasis& basis, double& footprint) {
  std::vector<LobeSize> sizes;
  sizes.reserve(total);
  footprint = 0.0;
  for (std::size_t c = 0; c < clouds.size(); ++c) {
    const std::vector<Ellipsoid>& lobes = clouds[c]->ellipsoids;
    for (std::size_t i = 0; i < lobes.size(); ++i) {
      const double f = ellipsoidFootprint(lobes[i], camera, basis);
      footprint += f;
      sizes.push_back(
          {projectedSize(lobes[i], camera, basis), f, std::uint32_t(c), std::uint32_t(i)});
    }
  }
  return sizes;
}

// Of the dropped lobes' bodies, the largest while they number at most `most` and, when
// `covered`, cover at most kBodyShare of the footprint budget `overdraw` (the largest always);
// `footprint` is what the chosen cover.
std::vector<Body> largestBodies(const std::vector<Body>& bodies, const Camera& camera,
                                const ViewBasis& basis, std::size_t most, bool covered,
                                double overdraw, double& footprint) {
  std::vector<std::pair<LobeSize, std::size_t>> ranked;  // bodies by projected size
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    const Ellipsoid& e = bodies[k].ellipsoid;
    ranked.push_back({{projectedSize(e, camera, basis), ellipsoidFootprint(e, camera, basis),
                       bodies[k].cloud, bodies[k].part},
                      k});
  }
  std::sort(ranked.begin(), ranked.end(),
            [&](const auto& a, const auto& b) { return larger(a.first, b.first); });
  std::vector<Body> chosen;
  footprint = 0.0;
  for (const auto& [size, k] : ranked) {
    if (chosen.size() >= most) break;
    if (covered && !chosen.empty() && footprint + size.footprint > kBodyShare * overdraw) break;
    footprint += size.footprint;
    chosen.push_back(bodies[k]);
  }
  return chosen;
}

// The kept lobes copied, not the world's (a world at its budget holds millions), with the bodies
// added; clouds left empty are dropped.
std::vector<EllipsoidCloud> keptClouds(std::span<const EllipsoidCloud* const> from_clouds,
                                       const std::vector<std::vector<char>>& kept,
                                       const std::vector<Body>& bodies) {
  std::vector<EllipsoidCloud> clouds;
  clouds.reserve(from_clouds.size());
  for (std::size_t c = 0; c < from_clouds.size(); ++c) {
    const EllipsoidCloud& from = *from_clouds[c];
    const bool parts = !from.parts.empty();
    std::vector<Ellipsoid> lobes;
    std::vector<std::uint32_t> lobe_parts;
    for (std::size_t i = 0; i < from.ellipsoids.size(); ++i) {
      if (kept[c][i] != 1) continue;
      lobes.push_back(from.ellipsoids[i]);
      if (parts) lobe_parts.push_back(from.parts[i]);
    }
    const bool thinned = lobes.size() < from.ellipsoids.size();
    clouds.push_back(withLobes(from, std::move(lobes), std::move(lobe_parts)));
    // Thinned clouds share one texture seed: clouds that differ only in it then share one
    // baked texture and one batch (a hundred clouds of their own seeds baked a hundred 128^3
    // tables, most of a heavy frame's time).
    if (thinned) clouds.back().texture.seed = clouds.back().texture.gardner.seed = 0;
  }
  for (const Body& b : bodies) {
    const EllipsoidCloud& from = *from_clouds[b.cloud];
    EllipsoidCloud& cloud = clouds[b.cloud];
    cloud.ellipsoids.push_back(b.ellipsoid);
    if (!from.parts.empty() && from.parts.size() == from.ellipsoids.size())
      cloud.parts.push_back(b.part);  // lit with the heap it stands in
  }
  std::erase_if(clouds, [](const EllipsoidCloud& c) { return c.ellipsoids.empty(); });
  return clouds;
}

}  // namespace

std::optional<std::vector<EllipsoidCloud>> cloudsWithinBudget(
    std::span<const EllipsoidCloud* const> clouds, const Camera& camera, double budget,
    double overdraw) {
  std::size_t total = 0;
  for (const EllipsoidCloud* cloud : clouds) total += cloud->ellipsoids.size();
  const bool counted = budget > 0.0 && double(total) > budget;
  if (!counted && !(overdraw > 0.0)) return std::nullopt;
  const ViewBasis basis = viewBasis(camera);
  double footprint = 0.0;
  std::vector<LobeSize> sizes = lobeSizes(clouds, total, camera, basis, footprint);
  const bool covered = overdraw > 0.0 && footprint > overdraw;
  if (!counted && !covered) return std::nullopt;
  // The dropped lobes' bodies count against both parts of the budget. They are made once, from
  // the first choice, and kept largest first while they number at most a quarter of the count
  // and cover at most kBodyShare of the footprint budget (a pile of clouds stacked in one place
  // gives a body per cloud, each over the whole view); the lobes are then chosen again in the room
  // the bodies leave, those dropped by this second choice going unmerged.
  LobeChoice choice(std::move(sizes), covered);
  choice.choose(counted ? std::size_t(budget) : total, overdraw);
  std::vector<std::vector<char>> kept = choice.keptFlags(clouds);
  const std::size_t most_bodies =
      counted ? std::max<std::size_t>(std::size_t(budget) / 4, 1) : total;
  std::vector<Body> bodies = mergedBodies(clouds, kept, most_bodies);
  if (!bodies.empty()) {
    double body_footprint = 0.0;
    bodies = largestBodies(bodies, camera, basis, most_bodies, covered, overdraw, body_footprint);
    const std::size_t room =
        counted ? std::size_t(budget) - std::min(bodies.size(), choice.kept() - 1) : total;
    choice.choose(room, overdraw - body_footprint);
    kept = choice.keptFlags(clouds);
  }
  return keptClouds(clouds, kept, bodies);
}

std::optional<Scene> withinEllipsoidBudget(const Scene& scene, double budget, double overdraw) {
  std::vector<const EllipsoidCloud*> clouds;
  for (const EllipsoidCloud& cloud : scene.clouds) clouds.push_back(&cloud);
  std::optional<std::vector<EllipsoidCloud>> kept =
      cloudsWithinBudget(clouds, scene.camera, budget, overdraw);
  if (!kept) return std::nullopt;
  return withClouds(scene, std::move(*kept));
}

}  // namespace nephele
