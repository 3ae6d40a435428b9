// The statistics the realism benchmark prints (image/cloud_statistics.h), on fields whose
// answer is known in closed form.
#include "image/cloud_statistics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace nephele {
namespace {

FloatImage blank(int w, int h) {
  FloatImage image;
  image.width = w, image.height = h;
  image.rgba.assign(std::size_t(w) * h * 4, 0.0f);
  return image;
}

void fillSquare(FloatImage& image, int x0, int y0, int side) {
  for (int y = y0; y < y0 + side; ++y)
    for (int x = x0; x < x0 + side; ++x) image.rgba[4 * (std::size_t(y) * image.width + x) + 3] = 1;
}

// Squares have perimeter 4 sqrt(A): D = 1. A square cut by the frame and one below the size
// limit are left out.
TEST(CloudStatistics, SquaresHaveDimensionOne) {
  FloatImage image = blank(400, 400);
  int x = 2;
  for (int side : {4, 6, 9, 14, 20, 30, 45}) {
    fillSquare(image, x, 10, side);
    x += side + 3;
  }
  fillSquare(image, 0, 200, 50);   // touches the border
  fillSquare(image, 100, 300, 3);  // 9 pixels, under the limit
  const std::vector<CloudRegion> clouds = cloudRegions(image, 16);
  ASSERT_EQ(clouds.size(), 7u);
  for (const CloudRegion& c : clouds)
    EXPECT_EQ(double(c.perimeter), 4.0 * std::sqrt(double(c.pixels.size())));
  const Fitted d = perimeterAreaDimension(clouds, 16);
  EXPECT_EQ(d.points, 7);
  EXPECT_NEAR(d.value, 1.0, 1e-9);
}

// An isotropic random field whose 2D power falls as |k|^-8/3 has transects with power
// k^-5/3 (a transect integrates the 2D spectrum over the other wavenumber; on the grid,
// well below the sampling limit): the fitted slope comes back within 0.1.
TEST(CloudStatistics, TransectSpectrumRecoversAPowerLaw) {
  constexpr int n = 256;
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> phase(0.0, 2.0 * std::numbers::pi);
  // Hermitian (g(-k) = conj g(k)), so that the field is real and each wavenumber keeps
  // exactly its power.
  std::vector<std::complex<double>> g(std::size_t(n) * n);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const int kx = x <= n / 2 ? x : x - n, ky = y <= n / 2 ? y : y - n;
      const double k = std::hypot(kx, ky);
      const std::size_t mirror = std::size_t((n - y) % n) * n + std::size_t((n - x) % n);
      const std::size_t here = std::size_t(y) * n + x;
      if (k == 0.0 || mirror < here) continue;
      g[here] = std::polar(std::pow(k, -4.0 / 3.0), mirror == here ? 0.0 : phase(rng));
      g[mirror] = std::conj(g[here]);
    }
  fft2(g, n, true);
  std::vector<double> field(g.size());
  for (std::size_t i = 0; i < g.size(); ++i) field[i] = g[i].real();
  const Fitted s = transectSpectrumSlope(field, n, n / 4.0, 8.0);
  EXPECT_GE(s.points, 10);
  EXPECT_NEAR(s.value, -5.0 / 3.0, 0.1);
}

// Clouds whose numbers per unit area fall as A^-2 give a = 2.
TEST(CloudStatistics, SizeDistributionExponent) {
  std::vector<CloudRegion> clouds;
  // Areas spaced evenly in log, counts per log bin ~ A^-1 (so per unit area ~ A^-2).
  for (int e = 0; e < 12; ++e) {
    const int area = int(std::round(20.0 * std::pow(10.0, (e + 0.5) / 4.0)));
    const int count = int(std::round(4000.0 / area * 20.0 / 20.0));
    for (int i = 0; i < count; ++i) clouds.push_back({std::vector<int>(std::size_t(area)), 0});
  }
  const Fitted a = sizeDistributionExponent(clouds, 16);
  EXPECT_GE(a.points, 10);
  EXPECT_NEAR(a.value, 2.0, 0.15);
}

}  // namespace
}  // namespace nephele
