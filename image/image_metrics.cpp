#include "image/image_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "world/check.h"

namespace nephele {

ImageError compareImages(const FloatImage& actual, const FloatImage& expected) {
  NEPHELE_CHECK(
      actual.width == expected.width && actual.height == expected.height,
      actual.width << "x" << actual.height << " vs " << expected.width << "x" << expected.height);
  ImageError e;
  double sum_sq = 0.0, coverage_sum_sq = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < actual.rgba.size(); i += 4) {
    bool finite = true;
    for (int c = 0; c < 4; ++c)
      finite = finite && std::isfinite(actual.rgba[i + c]) && std::isfinite(expected.rgba[i + c]);
    if (!finite) {
      ++e.non_finite;
      continue;
    }
    for (int c = 0; c < 3; ++c) {
      const double d = srgbEncode(actual.rgba[i + c]) - srgbEncode(expected.rgba[i + c]);
      sum_sq += d * d;
      e.max_abs = std::max(e.max_abs, std::abs(d));
      ++count;
    }
    const double coverage = std::abs(actual.rgba[i + 3] - expected.rgba[i + 3]);
    e.coverage_max = std::max(e.coverage_max, coverage);
    coverage_sum_sq += coverage * coverage;
  }
  auto psnr = [](double mse) {
    return mse > 0.0 ? 10.0 * std::log10(1.0 / mse) : std::numeric_limits<double>::infinity();
  };
  const double mse = count ? sum_sq / double(count) : 0.0;
  const double coverage_mse = count ? coverage_sum_sq / double(count / 3) : 0.0;
  e.rms = std::sqrt(mse);
  e.psnr_db = psnr(mse);
  e.coverage_rms = std::sqrt(coverage_mse);
  e.coverage_psnr = psnr(coverage_mse);
  return e;
}

FloatImage differenceImage(const FloatImage& actual, const FloatImage& expected, float gain) {
  FloatImage out{actual.width, actual.height, std::vector<float>(actual.rgba.size())};
  for (std::size_t i = 0; i < actual.rgba.size(); ++i)
    out.rgba[i] = (i % 4 == 3) ? 1.0f : gain * std::abs(actual.rgba[i] - expected.rgba[i]);
  return out;
}

ProfileError rowProfileError(const FloatImage& a, const FloatImage& b, int band) {
  NEPHELE_CHECK(a.width == b.width && a.height == b.height && band >= 1, "sizes differ");
  ProfileError out;
  for (int y0 = 0; y0 + band <= a.height; y0 += band) {
    double cover = 0.0, luminance = 0.0;
    for (int y = y0; y < y0 + band; ++y)
      for (int x = 0; x < a.width; ++x) {
        const std::size_t i = 4 * (std::size_t(y) * a.width + x);
        cover += a.rgba[i + 3] - b.rgba[i + 3];
        for (int c = 0; c < 3; ++c) luminance += (a.rgba[i + c] - b.rgba[i + c]) / 3.0;
      }
    const double n = double(band) * a.width;
    out.cover = std::max(out.cover, std::abs(cover) / n);
    out.luminance = std::max(out.luminance, std::abs(luminance) / n);
  }
  return out;
}

PlaneError comparePlanes(const std::vector<float>& actual, const std::vector<float>& expected) {
  PlaneError e;
  std::size_t flipped = 0, finite = 0;
  for (std::size_t i = 0; i < std::min(actual.size(), expected.size()); ++i) {
    const float a = actual[i], b = expected[i];
    if (std::isinf(a) != std::isinf(b)) {
      ++flipped;
    } else if (!std::isinf(b)) {
      ++finite;
      e.mean_abs += std::abs(a - b);
      e.mean_relative += b != 0.0f ? std::abs(a - b) / std::abs(b) : std::abs(a - b);
    }
  }
  if (!expected.empty()) e.flipped = double(flipped) / double(expected.size());
  if (finite) e.mean_abs /= double(finite), e.mean_relative /= double(finite);
  return e;
}

}  // namespace nephele
