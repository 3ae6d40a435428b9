// Weather layers drawn as their genera (MODEL.md section 10): the cloud fraction measured on
// rendered nadir images against the coverage asked (SPEC section 9), repetition, tiles that
// do not depend on the order they are visited in, and refused descriptions.
#include "world/formations/weather.h"
#include "world/world.h"

#include <gtest/gtest.h>

#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "gl_test_fixture.h"
#include "image/cloud_statistics.h"
#include "world/counter_random.h"
#include "world/formations/cloud_field.h"
#include "world/formations/ellipsoid.h"
#include "world/formations/genus.h"

namespace nephele {
namespace {

constexpr CloudType kGenera[] = {CloudType::kAltocumulus,   CloudType::kAltostratus,
                                 CloudType::kCirrocumulus,  CloudType::kCirrostratus,
                                 CloudType::kCirrus,        CloudType::kCumulonimbus,
                                 CloudType::kCumulus,       CloudType::kNimbostratus,
                                 CloudType::kStratocumulus, CloudType::kStratus};

Scene weatherScene(const WeatherLayer& w, std::uint64_t seed) {
  Scene scene;
  const WeatherClouds add = weatherClouds(w, "w", seed);
  scene.layers = add.layers;
  scene.fields = add.fields;
  return scene;
}

// Straight down from far above the layer onto a square `span` metres wide centred at `xy`.
Camera nadir(const WeatherLayer& w, glm::dvec2 xy, double span, int pixels) {
  return nadirCamera(xy, w.base_m, w.thickness_m, span, pixels);
}

// The horizontal extent of a genus's largest feature, metres: the nominal texture period or
// a few heaps.
double featureScale(const Scene& scene) {
  double scale = 0.0;
  for (const CloudLayer& l : scene.layers) {
    const LayerTexture t(l.texture);
    scale = std::max({scale, t.period().x, t.period().y});
  }
  for (const CloudField& f : scene.fields) scale = std::max(scale, fieldTileSize(f));
  return scale;
}

// Coverage channel >= 1/2 (SPEC section 9).
std::vector<double> coverageMask(const FloatImage& image) {
  std::vector<double> mask(std::size_t(image.width) * image.height);
  for (std::size_t i = 0; i < mask.size(); ++i) mask[i] = image.rgba[4 * i + 3] >= 0.5f ? 1.0 : 0.0;
  return mask;
}

// The highest secondary peak of the normalised autocorrelation of an s x s mask (s a power of
// two): lags up to s/2, each normalised by its overlap, outside the main lobe (the lags nearer
// than the first radius whose ring mean drops below zero).
double secondaryPeak(const std::vector<double>& mask, int s) {
  double mean = 0.0;
  for (double v : mask) mean += v;
  mean /= double(mask.size());
  double variance = 0.0;
  for (double v : mask) variance += (v - mean) * (v - mean);
  variance /= double(mask.size());
  if (variance <= 0.0) return 0.0;
  const int n = 2 * s;  // zero-padded: no wrap-around
  std::vector<std::complex<double>> x(std::size_t(n) * n), ones(std::size_t(n) * n);
  for (int y = 0; y < s; ++y)
    for (int i = 0; i < s; ++i) {
      x[std::size_t(y) * n + i] = mask[std::size_t(y) * s + i] - mean;
      ones[std::size_t(y) * n + i] = 1.0;
    }
  fft2(x, n, false), fft2(ones, n, false);
  for (std::size_t i = 0; i < x.size(); ++i) x[i] *= std::conj(x[i]), ones[i] *= std::conj(ones[i]);
  fft2(x, n, true), fft2(ones, n, true);
  const int max_lag = s / 2;
  auto acf = [&](int dx, int dy) {
    const std::size_t k = std::size_t((dy + n) % n) * n + std::size_t((dx + n) % n);
    return x[k].real() / (std::max(ones[k].real(), 1.0) * variance);
  };
  // The main lobe: lags connected to lag 0 through positive values (an elongated cloud's lobe
  // is long, not round).
  const int side = 2 * max_lag + 1;
  std::vector<char> lobe(std::size_t(side) * side, 0);
  std::vector<std::pair<int, int>> stack{{0, 0}};
  lobe[std::size_t(max_lag) * side + max_lag] = 1;
  while (!stack.empty()) {
    const auto [x0, y0] = stack.back();
    stack.pop_back();
    for (const auto& [ox, oy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
      const int x1 = x0 + ox, y1 = y0 + oy;
      if (std::abs(x1) > max_lag || std::abs(y1) > max_lag) continue;
      char& seen = lobe[std::size_t(y1 + max_lag) * side + std::size_t(x1 + max_lag)];
      if (seen || acf(x1, y1) <= 0.0) continue;
      seen = 1;
      stack.push_back({x1, y1});
    }
  }
  double peak = 0.0;
  for (int dy = -max_lag; dy <= max_lag; ++dy)
    for (int dx = -max_lag; dx <= max_lag; ++dx)
      if (!lobe[std::size_t(dy + max_lag) * side + std::size_t(dx + max_lag)])
        peak = std::max(peak, acf(dx, dy));
  return peak;
}

class WeatherRenderTest : public GlRenderTest {
 protected:
  // Fraction of the ground with coverage >= 1/2 seen straight down, over four views far
  // apart (one at 100 km from the origin), each spanning several of the genus's features.
  static double drawnFraction(const WeatherLayer& w, std::uint64_t seed,
                              FloatImage* first = nullptr) {
    Scene scene = weatherScene(w, seed);
    const double span = 4.0 * featureScale(scene);
    double covered = 0.0, total = 0.0;
    const glm::dvec2 places[] = {
        {0.0, 0.0}, {100000.0, 0.0}, {-37000.0, 61000.0}, {52000.0, -83000.0}};
    for (const glm::dvec2& xy : places) {
      scene.camera = nadir(w, xy, span, 192);
      const FloatImage image = renderer_->renderFloat(scene, {});
      if (first && xy == places[0]) *first = image;
      for (double v : coverageMask(image)) covered += v;
      total += double(image.width) * image.height;
    }
    return covered / total;
  }
};

// The in-layer veil (MODEL.md section 5): from inside a stratiform layer, and from its
// transition band, GL and the reference agree; the veil follows the layer's visibility (a
// thinner one shows more of the planes, so the image varies more), vanishes beyond the band
// and in a broken layer's gap.
TEST_F(WeatherRenderTest, InsideALayerTheVeilFollowsItsVisibility) {
  WeatherLayer w{CloudType::kStratus, 600.0, 500.0, 1.0, {}, {}, {}};
  w.transition_band_m = 200.0;
  Scene scene = weatherScene(w, 5);
  scene.camera.width = 160;
  scene.camera.height = 120;
  scene.camera.orientation.pitch_deg = 10.0;
  auto at = [&](double z, double visibility) {
    w.visibility_m = visibility;
    Scene s = weatherScene(w, 5);
    s.camera = scene.camera;
    s.camera.position = {0.0, 0.0, z};
    return s;
  };
  auto spread = [](const FloatImage& image) {  // of the green channel, top row to bottom
    double lo = 1e9, hi = -1e9;
    for (std::size_t i = 1; i < image.rgba.size(); i += 4)
      lo = std::min(lo, double(image.rgba[i])), hi = std::max(hi, double(image.rgba[i]));
    return hi - lo;
  };
  for (double z : {850.0, 1200.0})  // inside; in the band above the top
    for (double v : {0.0, 2000.0}) {
      const Scene s = at(z, v);
      ASSERT_TRUE(inLayerVeil(s)) << z;
      expectClose(renderer_->renderFloat(s, {}), renderReference(s, {1, 0}), 40.0, 0.02,
                  "in_layer_veil_" + std::to_string(int(z)) + "_" + std::to_string(int(v)));
    }
  // The genus's 130 m hides the planes; 2 km shows them.
  EXPECT_LT(spread(renderer_->renderFloat(at(850.0, 0.0), {})), 0.01);
  EXPECT_GT(spread(renderer_->renderFloat(at(850.0, 2000.0), {})), 0.03);
  EXPECT_FALSE(inLayerVeil(at(1350.0, 0.0)));  // beyond the band: the layer's planes alone
  EXPECT_FALSE(inLayerVeil(at(300.0, 0.0)));
  // A broken layer: the veil is as dense as the plane's cover over the eye, the genus's 120 m
  // under its cells and thinner in its gaps (opacity 0.38 there at 40 % cover).
  WeatherLayer broken{CloudType::kStratocumulus, 600.0, 500.0, 0.4, {}, {}, {}};
  Scene s = weatherScene(broken, 5);
  double thickest = 1e9, thinnest = 0.0;
  for (int i = 0; i < 64; ++i) {
    s.camera.position = {250.0 * i, 0.0, 800.0};
    const std::optional<Fog> veil = inLayerVeil(s);
    ASSERT_TRUE(veil);
    thickest = std::min(thickest, veil->visibility_m);
    thinnest = std::max(thinnest, veil->visibility_m);
  }
  EXPECT_NEAR(thickest, genus(CloudType::kStratocumulus).planes.in_layer_visibility_m, 1e-9);
  EXPECT_GT(thinnest, 2.0 * thickest);
}

TEST_F(WeatherRenderTest, EveryGenusDrawsTheCoverageAsked) {
  std::printf("%-14s", "drawn");
  for (double c : {0.1, 0.3, 0.5, 0.7, 0.9, 1.0}) std::printf(" %6.1f", c);
  std::printf("\n");
  for (CloudType type : kGenera) {
    std::printf("%-14s", std::string(cloudTypeName(type)).c_str());
    double previous = 0.0;
    for (double c : {0.1, 0.3, 0.5, 0.7, 0.9, 1.0}) {
      const double drawn = drawnFraction(typicalWeatherLayer(type, c), 11);
      std::printf(" %6.3f", drawn);
      std::fflush(stdout);
      EXPECT_NEAR(drawn, c, 0.05) << cloudTypeName(type) << " at " << c;
      EXPECT_GE(drawn, previous - 0.01) << cloudTypeName(type) << " at " << c;
      previous = drawn;
    }
    std::printf("\n");
  }
}

// Scud (MODEL.md section 10): one plane of fragments under the base, half way through the
// transition band (or a sixth of the thickness without one), none at 0; alone and seen straight
// down it covers the fraction asked, within the 0.05 every genus is held to, under a stratus
// and under cumulus heaps alike.
TEST_F(WeatherRenderTest, ScudIsDrawnUnderTheBaseAtItsFrequency) {
  for (CloudType type : {CloudType::kStratus, CloudType::kCumulus}) {
    WeatherLayer w = typicalWeatherLayer(type, 0.5);
    const std::size_t without = weatherClouds(w, "w", 5).layers.size();
    w.transition_band_m = 200.0;
    for (double scud : {0.2, 0.5}) {
      w.scud = scud;
      const WeatherClouds with = weatherClouds(w, "w", 5);
      ASSERT_EQ(with.layers.size(), without + 1) << cloudTypeName(type);
      const CloudLayer& plane = with.layers.back();
      EXPECT_EQ(plane.name, "w/scud");
      EXPECT_DOUBLE_EQ(plane.altitude_m, w.base_m - 100.0);
      Scene scene;
      scene.layers = {plane};
      const double span = 4.0 * featureScale(scene);
      double covered = 0.0, total = 0.0;
      for (const glm::dvec2& xy : {glm::dvec2(0.0), glm::dvec2(60000.0, -40000.0)}) {
        scene.camera = nadirCamera(xy, plane.altitude_m, 1.0, span, 192);
        for (double v : coverageMask(renderer_->renderFloat(scene, {}))) covered += v;
        total += 192.0 * 192.0;
      }
      std::printf("scud %.1f under %s: drawn %.3f\n", scud,
                  std::string(cloudTypeName(type)).c_str(), covered / total);
      EXPECT_NEAR(covered / total, scud, 0.05) << cloudTypeName(type);
    }
  }
  WeatherLayer bad = typicalWeatherLayer(CloudType::kStratus, 0.5);
  bad.scud = 1.5;
  EXPECT_NE(weatherLayerError(bad).find("scud"), std::string::npos) << weatherLayerError(bad);
}

// The species change a heap's shape (genus.h, Species): the cover drawn still follows the
// asked where their rows measured it and between them.
TEST_F(WeatherRenderTest, EverySpeciesDrawsTheCoverageAsked) {
  for (double thickness : {500.0, 2200.0, 4000.0})
    for (double c : {0.3, 0.5}) {
      WeatherLayer w = typicalWeatherLayer(CloudType::kCumulus, c);
      w.thickness_m = thickness;
      const double drawn = drawnFraction(w, 11);
      std::printf("cumulus %5.0f m thick at %.1f: drawn %.3f\n", thickness, c, drawn);
      EXPECT_NEAR(drawn, c, 0.05) << thickness << " m thick";
    }
}

TEST_F(WeatherRenderTest, NoGenusRepeatsAtHalfCover) {
  for (CloudType type : kGenera) {
    const WeatherLayer w = typicalWeatherLayer(type, 0.5);
    Scene scene = weatherScene(w, 11);
    // Ten texture periods (or heap tiles) across, so a lattice would show as a peak, and
    // enough cells that a streaky genus's few large features do not make the estimate noisy.
    scene.camera = nadir(w, {3000.0, -2000.0}, 10.0 * featureScale(scene), 512);
    const FloatImage image = renderer_->renderFloat(scene, {});
    const double peak = secondaryPeak(coverageMask(image), 512);
    std::printf("%-14s secondary autocorrelation peak %.3f\n",
                std::string(cloudTypeName(type)).c_str(), peak);
    const double bound = 0.3;  // the bound
    EXPECT_LT(peak, bound) << cloudTypeName(type);
    if (peak >= bound)
      writeFailureImages(image, image, "repeat_" + std::string(cloudTypeName(type)));
  }
}

// Tiles are pure functions of (field, tile index): built in any order, or reached from any
// view, they hold the same heaps; and a field 100 km away is the same field.
TEST(CloudField, TilesDoNotDependOnVisitingOrder) {
  CloudField f;
  f.name = "f";
  f.coverage = 0.4;
  f.seed = 21;
  std::vector<std::vector<EllipsoidCloud>> forward, backward;
  for (int k = 0; k < 6; ++k) forward.push_back(tileClouds(f, k - 3, 40 + k));
  for (int k = 5; k >= 0; --k) backward.insert(backward.begin(), tileClouds(f, k - 3, 40 + k));
  int heaps = 0;
  for (int k = 0; k < 6; ++k) {
    ASSERT_EQ(forward[k].size(), backward[k].size());
    for (std::size_t c = 0; c < forward[k].size(); ++c) {
      ASSERT_EQ(forward[k][c].ellipsoids.size(), backward[k][c].ellipsoids.size());
      heaps += int(forward[k][c].ellipsoids.size());
      for (std::size_t e = 0; e < forward[k][c].ellipsoids.size(); ++e)
        EXPECT_EQ(forward[k][c].ellipsoids[e].centre, backward[k][c].ellipsoids[e].centre);
    }
  }
  EXPECT_GT(heaps, 0);
  // Two cameras far apart looking at the same ground see the same tile.
  Camera a, b;
  a.position = {0.0, 0.0, 30000.0};
  a.orientation = {0.0, -90.0, 0.0};
  b = a;
  b.position = {20000.0, 0.0, 30000.0};
  b.orientation = {270.0, -50.0, 0.0};
  auto tileNamed = [](const std::vector<EllipsoidCloud>& clouds, const std::string& name) {
    for (const EllipsoidCloud& c : clouds)
      if (c.name == name) return c.ellipsoids;
    return std::vector<Ellipsoid>{};
  };
  const auto from_a = tileNamed(fieldClouds(f, a), "f/0,0");
  const auto from_b = tileNamed(fieldClouds(f, b), "f/0,0");
  ASSERT_FALSE(from_a.empty());
  ASSERT_EQ(from_a.size(), from_b.size());
  for (std::size_t e = 0; e < from_a.size(); ++e) EXPECT_EQ(from_a[e].centre, from_b[e].centre);
  // Far from the origin the field is as dense as near it: heaps exist around every view.
  Camera far = a;
  far.position = {150000.0, -120000.0, 30000.0};
  std::size_t near_count = 0, far_count = 0;
  for (const EllipsoidCloud& c : fieldClouds(f, a)) near_count += c.ellipsoids.size();
  for (const EllipsoidCloud& c : fieldClouds(f, far)) far_count += c.ellipsoids.size();
  EXPECT_GT(far_count, near_count / 2);
  EXPECT_LT(far_count, near_count * 2);
}

// A cumulonimbus (MODEL.md section 10) is one tower from its base to its anvil, and its anvil
// is at least three times as wide as the tower and carried downwind by the shear; checked on
// the ellipsoids themselves: points well inside one (|W (p - c)|^2 < 1/2) all the way up the
// vertical through the base from the middle of its flat bottom, and the extents along the shear
// from each ellipsoid's support |W^-T d| (which sees a mistaken heading, unlike a bounding sphere).
// The heaps drawn as ellipsoids are bounded in tiles as well as in distance (issue 31): a legal
// 10 m cumulonimbus layer has heaps a few metres wide, and its 40 km range held millions of
// tiles (34 s a frame); a typical field keeps its automatic range.
TEST(CloudField, HeapRangeIsBoundedInTiles) {
  Camera camera;
  camera.position = {0.0, 0.0, 300.0};
  WeatherLayer thin;
  thin.type = CloudType::kCumulonimbus;
  thin.base_m = 500.0, thin.thickness_m = 10.0, thin.coverage = 0.3;
  const WeatherClouds drawn = weatherClouds(thin, "w", 3);
  ASSERT_EQ(drawn.fields.size(), 1u);
  const CloudField& f = drawn.fields[0];
  EXPECT_LE(heapRange(f, camera), CloudField::kMaxRangeTiles * fieldTileSize(f));
  EXPECT_LE(heapRange(f, camera, 1.0e6), CloudField::kMaxRangeTiles * fieldTileSize(f));
  Scene scene;
  scene.camera = camera;
  scene.fields = drawn.fields;
  EXPECT_LT(ellipsoidCount(withFieldClouds(scene)), 200000u);
  const WeatherClouds typical =
      weatherClouds(typicalWeatherLayer(CloudType::kCumulus, 0.3), "w", 3);
  EXPECT_EQ(heapRange(typical.fields[0], camera),
            CloudField::kRangeM + 2.0 * std::abs(300.0 - typical.fields[0].base_m));
}

// MODEL.md section 10: a cumulonimbus is one column from its base to the anvil, which spreads
// from the tower (the incus) to several times its width, downwind of it when the wind shears.
TEST(CloudField, CumulonimbusIsOneTowerUnderAnAnvilCarriedDownwind) {
  CloudField f;
  f.name = "cb";
  f.type = CloudType::kCumulonimbus;
  f.base_m = 900.0;
  f.thickness_m = 9000.0;
  auto insideSome = [](const std::vector<Ellipsoid>& heap, glm::dvec3 p) {
    for (const Ellipsoid& e : heap) {
      const glm::dvec3 q = worldToUnitSphere(e) * (p - e.centre);
      if (glm::dot(q, q) < 0.5) return true;
    }
    return false;
  };
  // Extents along unit d of the ellipsoids centred above (anvil) and below (tower) z.
  struct Extent {
    double lo = 1e30, hi = -1e30;
    double width() const { return hi - lo; }
    double middle() const { return 0.5 * (lo + hi); }
  };
  auto extent = [](const std::vector<Ellipsoid>& heap, glm::dvec2 d, bool above, double z) {
    Extent x;
    for (const Ellipsoid& e : heap) {
      if ((e.centre.z > z) != above) continue;
      const glm::dvec3 along(d, 0.0);
      const double c = glm::dot(glm::dvec3(e.centre), along);
      const double support =
          glm::length(glm::inverse(glm::transpose(worldToUnitSphere(e))) * along);
      x.lo = std::min(x.lo, c - support), x.hi = std::max(x.hi, c + support);
    }
    return x;
  };
  const double anvil_z = f.base_m + 0.8 * f.thickness_m, tower_z = f.base_m + 0.6 * f.thickness_m;
  for (glm::dvec2 shear : {glm::dvec2(12.0, 0.0), glm::dvec2(0.0, -20.0), glm::dvec2(0.0)}) {
    f.shear = shear;
    SCOPED_TRACE(testing::Message() << "shear " << shear.x << ", " << shear.y);
    const std::vector<Ellipsoid> heap = typicalHeap(f, {0.0, 0.0, f.base_m}).ellipsoids;
    // From the middle of the flat base (0.05 h above the cloud base) to the anvil.
    for (double z = f.base_m + 0.05 * f.thickness_m; z < anvil_z; z += 50.0)
      ASSERT_TRUE(insideSome(heap, {0.0, 0.0, z})) << "gap at " << z << " m";
    const double speed = glm::length(shear);
    const glm::dvec2 d = speed > 0.0 ? shear / speed : glm::dvec2(1.0, 0.0);
    const Extent anvil = extent(heap, d, true, anvil_z), tower = extent(heap, d, false, tower_z);
    EXPECT_GE(anvil.width(), 3.0 * tower.width());
    // The tower spreads into the anvil (the incus) rather than standing as a stem under a
    // plate: the cloud's width along the shear grows from the middle of the tower to the
    // anvil, by half again at 0.72 h.
    auto widthAt = [&](double height) {
      double lo = 1e30, hi = -1e30;
      for (double x = -4.0 * f.thickness_m; x <= 4.0 * f.thickness_m; x += 50.0)
        if (insideSome(heap, glm::dvec3(x * d, f.base_m + height * f.thickness_m)))
          lo = std::min(lo, x), hi = std::max(hi, x);
      return hi - lo;
    };
    const double middle = widthAt(0.45), shoulder = widthAt(0.72), top = widthAt(0.9);
    EXPECT_GE(shoulder, 1.5 * middle) << middle << " m at 0.45 h";
    EXPECT_GE(top, shoulder) << shoulder << " m at 0.72 h";
    if (speed > 0.0)
      EXPECT_GT(anvil.middle() - tower.middle(), 0.25 * f.thickness_m);
    else
      EXPECT_LT(std::abs(anvil.middle() - tower.middle()), 0.1 * f.thickness_m);
  }
}

// Species (genus.h): a layer's heaps are of the species its thickness names, and a heap's width
// over its height, measured on its ellipsoids (extents from each one's support |W^-T d|), is
// its row's within a third at the row's thickness and falls as the layer thickens: humilis
// wider than tall, congestus taller than wide.
TEST(CloudField, HeapsTakeTheShapeOfTheirSpecies) {
  auto widthOverHeight = [](const CloudField& f) {
    double width = 0.0, top = 0.0;
    for (const Ellipsoid& e : typicalHeap(f, {0.0, 0.0, f.base_m}).ellipsoids) {
      const glm::dmat3 inverse = glm::inverse(glm::transpose(worldToUnitSphere(e)));
      width = std::max(width, std::abs(e.centre.x) + glm::length(inverse * glm::dvec3(1, 0, 0)));
      top = std::max(top, e.centre.z + glm::length(inverse * glm::dvec3(0, 0, 1)));
    }
    return 2.0 * width / (top - f.base_m);
  };
  CloudField f;
  f.base_m = 1200.0;
  double previous = 1e9;
  for (const Species& row : genus(CloudType::kCumulus).species) {
    SCOPED_TRACE(std::string(row.name));
    f.thickness_m = row.thickness_m;
    EXPECT_EQ(heapSpecies(f), row.name);
    const double ratio = widthOverHeight(f);
    std::printf("%-10s %5.0f m: width over height %.2f (row %.2f)\n", std::string(row.name).c_str(),
                row.thickness_m, ratio, row.width_over_height);
    EXPECT_NEAR(ratio, row.width_over_height, row.width_over_height / 3.0);
    EXPECT_LT(ratio, previous);
    previous = ratio;
  }
  f.thickness_m = 400.0;
  EXPECT_EQ(heapSpecies(f), "humilis");
  EXPECT_GT(widthOverHeight(f), 1.5);
  f.thickness_m = 6000.0;
  EXPECT_EQ(heapSpecies(f), "congestus");
  EXPECT_LT(widthOverHeight(f), 1.0);
}

// The genus table (world/formations/genus.h) is what every reader sees: each genus's name
// reads back as the genus, its typical layer is a valid layer, and it draws heaps exactly when
// the table says so (the convective genera), planes otherwise.
TEST(Weather, EveryGenusOfTheTableReadsBackAndDrawsAsItsRowSays) {
  for (CloudType type : kGenera) {
    const std::string_view name = cloudTypeName(type);
    SCOPED_TRACE(std::string(name));
    EXPECT_EQ(genus(type).name, name);
    ASSERT_TRUE(cloudTypeFromName(name).has_value());
    EXPECT_EQ(*cloudTypeFromName(name), type);
    const WeatherLayer layer = typicalWeatherLayer(type, 0.4);
    EXPECT_EQ(weatherLayerError(layer), "");
    const WeatherClouds drawn = weatherClouds(layer, "w", 5);
    EXPECT_EQ(!drawn.fields.empty(), genus(type).heaps);
    EXPECT_EQ(drawn.layers.empty(), genus(type).heaps);  // 0.4 is below the heaps' own cover
  }
  EXPECT_EQ(cloudTypeName(CloudType(kCloudTypeCount)), "unknown");
  EXPECT_FALSE(cloudTypeFromName("cumulus humilis").has_value());
}

TEST(Weather, InvalidLayersAreRefusedWithTheAllowedRange) {
  EXPECT_NE(
      weatherLayerError({CloudType(11), 1000.0, 500.0, 0.5, {}, {}, {}}).find("allowed: 0 none"),
      std::string::npos);
  EXPECT_NE(
      weatherLayerError({CloudType::kCumulus, 1000.0, -5.0, 0.5, {}, {}, {}}).find("thickness"),
      std::string::npos);
  EXPECT_NE(
      weatherLayerError({CloudType::kCumulus, 1000.0, 500.0, 1.5, {}, {}, {}}).find("coverage"),
      std::string::npos);
  EXPECT_NE(weatherLayerError({CloudType::kStratus, -1.0, 500.0, 0.5, {}, {}, {}}).find("base"),
            std::string::npos);
  EXPECT_EQ(weatherLayerError({CloudType::kStratus, 100.0, 500.0, 0.5, {}, {}, {}}), "");
  // Nothing is drawn for a layer that is refused.
  const WeatherClouds none =
      weatherClouds({CloudType::kCumulus, 1000.0, 500.0, 1.5, {}, {}, {}}, "w", 1);
  EXPECT_TRUE(none.layers.empty() && none.fields.empty());
  // Scene files name the key and the allowed values, and load nothing.
  for (const char* bad :
       {"type = \"cumulous\"", "coverage = 150", "thickness = -3", "base = 1e9"}) {
    const std::filesystem::path path =
        std::filesystem::temp_directory_path() / "nephele_weather_test.toml";
    {
      std::ofstream out(path);
      out << "[[weather]]\n" << bad << "\n";
    }
    SceneFile file;
    const std::string error = loadSceneFile(path.string(), file);
    EXPECT_NE(error.find("weather[0]"), std::string::npos) << bad << ": " << error;
    EXPECT_NE(error.find("allowed"), std::string::npos) << bad << ": " << error;
  }
}

// A scene file's [[weather]] is the world's weather layer 1, held as set: the world it makes
// is the world that set_weather (or Modbus, or CIGI) makes from the same layer.
TEST(Weather, ASceneFilesWeatherIsTheSameLayerAsAHostSets) {
  SceneFile file;
  ASSERT_EQ(parseSceneText("[[weather]]\ntype = \"cumulus\"\nbase = 1200\nthickness = 1500\n"
                           "coverage = 35\n[[weather]]\ntype = \"stratocumulus\"\nbase = 2500\n"
                           "thickness = 400\ncoverage = 60\n",
                           "weather.toml", file),
            "");
  ASSERT_EQ(file.scene.weather.size(), 2u);
  const WeatherLayer cumulus = file.scene.weather.at({1, std::nullopt});
  EXPECT_EQ(cumulus.type, CloudType::kCumulus);
  EXPECT_DOUBLE_EQ(cumulus.coverage, 0.35);
  World from_file(file.scene, file.dynamics);
  SceneFile empty;
  ASSERT_EQ(parseSceneText("", "empty.toml", empty), "");
  World from_host(empty.scene, empty.dynamics);
  for (const auto& [key, layer] : file.scene.weather)
    ASSERT_EQ(from_host.setWeather(key, layer), "");
  EXPECT_EQ(from_host.base().weather, from_file.base().weather);
  EXPECT_EQ(from_host.hash(), from_file.hash());
}

}  // namespace
}  // namespace nephele
