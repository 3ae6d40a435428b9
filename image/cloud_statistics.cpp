#include "image/cloud_statistics.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numbers>
#include <utility>

namespace nephele {

void fft(std::vector<std::complex<double>>& a, bool inverse) {
  const std::size_t n = a.size();
  for (std::size_t i = 1, j = 0; i < n; ++i) {  // bit-reversal permutation
    std::size_t bit = n >> 1;
    for (; j & bit; bit >>= 1) j ^= bit;
    j ^= bit;
    if (i < j) std::swap(a[i], a[j]);
  }
  for (std::size_t len = 2; len <= n; len <<= 1) {
    const double angle = 2.0 * std::numbers::pi / double(len) * (inverse ? 1.0 : -1.0);
    const std::complex<double> w_len(std::cos(angle), std::sin(angle));
    for (std::size_t i = 0; i < n; i += len) {
      std::complex<double> w(1.0);
      for (std::size_t k = 0; k < len / 2; ++k, w *= w_len) {
        const auto u = a[i + k], v = a[i + k + len / 2] * w;
        a[i + k] = u + v;
        a[i + k + len / 2] = u - v;
      }
    }
  }
  if (inverse)
    for (auto& x : a) x /= double(n);
}

void fft2(std::vector<std::complex<double>>& g, int n, bool inverse) {
  std::vector<std::complex<double>> line(static_cast<std::size_t>(n));
  for (int y = 0; y < n; ++y) {
    std::copy_n(g.begin() + std::ptrdiff_t(y) * n, n, line.begin());
    fft(line, inverse);
    std::copy(line.begin(), line.end(), g.begin() + std::ptrdiff_t(y) * n);
  }
  for (int x = 0; x < n; ++x) {
    for (int y = 0; y < n; ++y) line[std::size_t(y)] = g[std::size_t(y) * n + x];
    fft(line, inverse);
    for (int y = 0; y < n; ++y) g[std::size_t(y) * n + x] = line[std::size_t(y)];
  }
}

std::vector<CloudRegion> cloudRegions(const FloatImage& image, int min_pixels) {
  const int w = image.width, h = image.height;
  auto cloud = [&](int p) { return image.rgba[4 * std::size_t(p) + 3] > 0.5f; };
  std::vector<char> seen(std::size_t(w) * h, 0);
  std::vector<CloudRegion> out;
  for (int start = 0; start < w * h; ++start) {
    if (seen[start] || !cloud(start)) continue;
    CloudRegion region;
    std::vector<int> stack{start};
    seen[start] = 1;
    bool border = false;
    while (!stack.empty()) {
      const int p = stack.back();
      stack.pop_back();
      region.pixels.push_back(p);
      const int x = p % w, y = p / w;
      border = border || x == 0 || y == 0 || x == w - 1 || y == h - 1;
      for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
        const int nx = x + dx, ny = y + dy;
        const int q = ny * w + nx;
        if (nx < 0 || ny < 0 || nx >= w || ny >= h || !cloud(q)) {
          ++region.perimeter;  // an edge to clear sky (or the frame)
          continue;
        }
        if (seen[q]) continue;
        seen[q] = 1;
        stack.push_back(q);
      }
    }
    if (!border && int(region.pixels.size()) >= min_pixels) out.push_back(std::move(region));
  }
  return out;
}

LineFit fitLine(const std::vector<double>& x, const std::vector<double>& y) {
  LineFit fit;
  fit.points = int(std::min(x.size(), y.size()));
  if (fit.points < 2) return fit;
  double mx = 0.0, my = 0.0;
  for (int i = 0; i < fit.points; ++i) mx += x[i], my += y[i];
  mx /= fit.points, my /= fit.points;
  double sxy = 0.0, sxx = 0.0;
  for (int i = 0; i < fit.points; ++i) {
    sxy += (x[i] - mx) * (y[i] - my);
    sxx += (x[i] - mx) * (x[i] - mx);
  }
  fit.slope = sxx > 0.0 ? sxy / sxx : 0.0;
  fit.intercept = my - fit.slope * mx;
  return fit;
}

Fitted perimeterAreaDimension(const std::vector<CloudRegion>& clouds, int min_pixels) {
  std::vector<double> log_area, log_perimeter;
  for (const CloudRegion& c : clouds)
    if (int(c.pixels.size()) >= min_pixels) {
      log_area.push_back(std::log(double(c.pixels.size())));
      log_perimeter.push_back(std::log(double(c.perimeter)));
    }
  const LineFit fit = fitLine(log_area, log_perimeter);
  return {2.0 * fit.slope, fit.points};
}

Fitted sizeDistributionExponent(const std::vector<CloudRegion>& clouds, int min_pixels) {
  constexpr double kBinsPerDecade = 4.0;
  std::map<int, int> bins;  // bin index -> clouds
  for (const CloudRegion& c : clouds)
    if (int(c.pixels.size()) >= min_pixels)
      ++bins[int(std::floor(kBinsPerDecade * std::log10(double(c.pixels.size()))))];
  std::vector<double> log_size, log_density;
  for (const auto& [bin, count] : bins) {
    const double lower = std::pow(10.0, bin / kBinsPerDecade);
    const double upper = std::pow(10.0, (bin + 1) / kBinsPerDecade);
    log_size.push_back(std::log(std::sqrt(lower * upper)));
    log_density.push_back(std::log(count / (upper - lower)));  // clouds per pixel of area
  }
  const LineFit fit = fitLine(log_size, log_density);
  return {-fit.slope, fit.points};
}

Fitted transectSpectrumSlope(const std::vector<double>& field, int w, double longest_px,
                             double shortest_px) {
  std::vector<double> power(std::size_t(w / 2 + 1), 0.0);
  std::vector<std::complex<double>> line(static_cast<std::size_t>(w));
  for (int pass = 0; pass < 2; ++pass)  // rows, then columns
    for (int r = 0; r < w; ++r) {
      double mean = 0.0;
      for (int i = 0; i < w; ++i)
        mean += field[pass == 0 ? std::size_t(r) * w + i : std::size_t(i) * w + r];
      mean /= w;
      for (int i = 0; i < w; ++i) {
        const double hann = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * i / w);
        const double v = field[pass == 0 ? std::size_t(r) * w + i : std::size_t(i) * w + r];
        line[std::size_t(i)] = hann * (v - mean);
      }
      fft(line, false);
      for (int k = 1; k <= w / 2; ++k) power[std::size_t(k)] += std::norm(line[std::size_t(k)]);
    }
  // Logarithmic bins, eight per octave, of wavenumbers k (cycles per transect) whose
  // wavelengths w / k lie between the two limits.
  const double k_low = std::max(1.0, w / longest_px), k_high = std::min(w / 2.0, w / shortest_px);
  struct Bin {
    double power = 0.0, log_k = 0.0;
    int count = 0;
  };
  std::map<int, Bin> bins;
  for (int k = int(std::ceil(k_low)); k <= int(std::floor(k_high)); ++k) {
    Bin& bin = bins[int(std::floor(8.0 * std::log2(double(k))))];
    bin.power += power[std::size_t(k)];
    bin.log_k += std::log(double(k));
    ++bin.count;
  }
  std::vector<double> log_k, log_power;
  for (const auto& [index, bin] : bins) {
    if (bin.power <= 0.0) continue;
    log_k.push_back(bin.log_k / bin.count);
    log_power.push_back(std::log(bin.power / bin.count));
  }
  const LineFit fit = fitLine(log_k, log_power);
  return {fit.slope, fit.points};
}

OutlineFigures outlineFigures(const std::vector<int>& pixels, int width, int height) {
  OutlineFigures out;
  if (pixels.empty() || width <= 0 || height <= 0) return out;
  std::vector<std::uint8_t> in(std::size_t(width) * height, 0);
  for (int p : pixels) in[std::size_t(p)] = 1;
  // Perimeter of the silhouette coarse-grained into s x s blocks, in pixel lengths.
  auto perimeter = [&](int s) {
    const int bw = (width + s - 1) / s, bh = (height + s - 1) / s;
    std::vector<std::uint8_t> block(std::size_t(bw) * bh, 0);
    for (int by = 0; by < bh; ++by)
      for (int bx = 0; bx < bw; ++bx) {
        int count = 0;
        for (int y = by * s; y < std::min(by * s + s, height); ++y)
          for (int x = bx * s; x < std::min(bx * s + s, width); ++x)
            count += in[std::size_t(y) * width + x];
        block[std::size_t(by) * bw + bx] = 2 * count >= s * s;
      }
    auto at = [&](int x, int y) {
      return x >= 0 && y >= 0 && x < bw && y < bh && block[std::size_t(y) * bw + x];
    };
    long edges = 0;
    for (int y = 0; y < bh; ++y)
      for (int x = 0; x < bw; ++x)
        if (at(x, y)) edges += !at(x - 1, y) + !at(x + 1, y) + !at(x, y - 1) + !at(x, y + 1);
    return double(edges) * s;
  };
  std::vector<double> log_s, log_p;
  for (int s : {1, 2, 4, 8})
    if (const double p = perimeter(s); p > 0.0) {
      log_s.push_back(std::log(double(s)));
      log_p.push_back(std::log(p));
    }
  if (log_s.size() >= 2) out.dimension = 1.0 - fitLine(log_s, log_p).slope;
  // The ellipse of the same second moments: a filled ellipse of semi-axes a, b has covariance
  // eigenvalues a^2 / 4 and b^2 / 4, so its boundary is d^T C^-1 d = 4.
  double mx = 0.0, my = 0.0;
  for (int p : pixels) mx += p % width + 0.5, my += p / width + 0.5;
  mx /= double(pixels.size()), my /= double(pixels.size());
  double cxx = 0.0, cxy = 0.0, cyy = 0.0;
  for (int p : pixels) {
    const double dx = p % width + 0.5 - mx, dy = p / width + 0.5 - my;
    cxx += dx * dx, cxy += dx * dy, cyy += dy * dy;
  }
  const double n = double(pixels.size());
  cxx = cxx / n + 1.0 / 12.0, cxy /= n, cyy = cyy / n + 1.0 / 12.0;  // + a pixel's own spread
  const double det = cxx * cyy - cxy * cxy;
  if (!(det > 0.0)) return out;
  int outline = 0, near = 0;
  for (int p : pixels) {
    const int x = p % width, y = p / width;
    auto inside = [&](int u, int v) {
      return u >= 0 && v >= 0 && u < width && v < height && in[std::size_t(v) * width + u];
    };
    if (inside(x - 1, y) && inside(x + 1, y) && inside(x, y - 1) && inside(x, y + 1)) continue;
    ++outline;
    const double dx = x + 0.5 - mx, dy = y + 0.5 - my;
    const double q = std::sqrt((cyy * dx * dx - 2.0 * cxy * dx * dy + cxx * dy * dy) / det) / 2.0;
    const double r = std::hypot(dx, dy);
    // The boundary lies at r / q along this ray; the pixel's centre is half a pixel inside an
    // outline that follows the ellipse exactly.
    if (q > 0.0 && std::abs(r - r / q) <= 1.0) ++near;
  }
  out.near_ellipse = outline > 0 ? double(near) / outline : 0.0;
  return out;
}

ShadowAgreement shadowAgreement(const FloatImage& actual, const FloatImage& reference,
                                const FloatImage& unshadowed) {
  ShadowAgreement out;
  auto luminance = [](const FloatImage& image, std::size_t i) {
    const float* p = &image.rgba[4 * i];
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
  };
  const std::size_t pixels = std::size_t(actual.width) * actual.height;
  int shadowed = 0, both = 0;
  double difference = 0.0;
  for (std::size_t i = 0; i < pixels; ++i) {
    if (!(actual.rgba[4 * i + 3] < 0.01f && reference.rgba[4 * i + 3] < 0.01f)) continue;
    const double lit = luminance(unshadowed, i);
    if (!(lit > 0.0)) continue;
    const double a = luminance(actual, i) / lit, r = luminance(reference, i) / lit;
    ++out.clear_pixels;
    difference += std::abs(a - r);
    if (a < kShadowedRatio) {
      ++shadowed;
      both += r < kShadowedRatio;
    }
  }
  if (out.clear_pixels > 0) {
    out.mean_ratio_difference = difference / out.clear_pixels;
    out.shadowed = double(shadowed) / out.clear_pixels;
  }
  out.agreement = shadowed > 0 ? double(both) / shadowed : 1.0;
  return out;
}

}  // namespace nephele
