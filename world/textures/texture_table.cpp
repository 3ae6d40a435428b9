#include "world/textures/texture_table.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "world/counter_random.h"

namespace nephele {
namespace {

// Signed uniform in [-1, 1) keyed by seed, position and purpose.
double signedRandom(std::uint64_t seed, int x, int y, std::uint64_t purpose) {
  return 2.0 * unitFromBits(hashCounters(seed, purpose, std::uint32_t(x), std::uint32_t(y))) - 1.0;
}

}  // namespace

int wrapIndex(int i, int n) {
  const int r = i % n;
  return r < 0 ? r + n : r;
}

double smootherstep(double t) {
  return t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
}

void normaliseToUnit(std::vector<float>& values) {
  const auto [lo, hi] = std::minmax_element(values.begin(), values.end());
  const float low = *lo, range = *hi - *lo;
  for (float& v : values) v = range > 0.0f ? (v - low) / range : 0.5f;
}

float TextureTable::at(int x, int y) const {
  return values[std::size_t(wrapIndex(y, height)) * width + wrapIndex(x, width)];
}

double TextureTable::sampleBilinear(glm::dvec2 uv) const {
  const double x = uv.x * width - 0.5, y = uv.y * height - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const double tx = x - fx, ty = y - fy;
  // Reduce the integer part modulo the table so that far-away coordinates stay exact.
  const int ix = int(std::fmod(fx, double(width))), iy = int(std::fmod(fy, double(height)));
  const double top = (1.0 - tx) * at(ix, iy) + tx * at(ix + 1, iy);
  const double bottom = (1.0 - tx) * at(ix, iy + 1) + tx * at(ix + 1, iy + 1);
  return (1.0 - ty) * top + ty * bottom;
}

TextureTable diamondSquare(int size_log2, double roughness, std::uint64_t seed) {
  const int n = 1 << size_log2;
  TextureTable table{n, n, std::vector<float>(std::size_t(n) * n, 0.0f)};
  auto cell = [&](int x, int y) -> float& {
    return table.values[std::size_t(wrapIndex(y, n)) * n + wrapIndex(x, n)];
  };
  const double decay = std::exp2(-roughness);
  double amplitude = 1.0;
  for (int step = n; step > 1; step /= 2, amplitude *= decay) {
    const int half = step / 2;
    // Diamond step: square centres from their four corners (wrapping around the edges).
    for (int y = 0; y < n; y += step)
      for (int x = 0; x < n; x += step) {
        const double mean =
            0.25 * (cell(x, y) + cell(x + step, y) + cell(x, y + step) + cell(x + step, y + step));
        cell(x + half, y + half) =
            float(mean + amplitude * signedRandom(seed, x + half, y + half, 0x4453ull));
      }
    // Square step: edge midpoints from their four diamond neighbours.
    for (int y = 0; y < n; y += half)
      for (int x = ((y / half) % 2 == 0) ? half : 0; x < n; x += step) {
        const double mean =
            0.25 * (cell(x - half, y) + cell(x + half, y) + cell(x, y - half) + cell(x, y + half));
        cell(x, y) = float(mean + amplitude * signedRandom(seed, x, y, 0x4453ull));
      }
  }
  normaliseToUnit(table.values);
  return table;
}

TextureTable perlinNoise(int size, int cells, int octaves, double persistence, std::uint64_t seed) {
  TextureTable table{size, size, std::vector<float>(std::size_t(size) * size, 0.0f)};
  double amplitude = 1.0;
  for (int octave = 0; octave < octaves; ++octave, amplitude *= persistence) {
    const int lattice = cells << octave;
    auto gradient = [&](int gx, int gy) {
      const double angle = 2.0 * std::numbers::pi *
                           unitFromBits(hashCounters(seed, 0x5065726cull + octave,
                                                     std::uint32_t(wrapIndex(gx, lattice)),
                                                     std::uint32_t(wrapIndex(gy, lattice))));
      return glm::dvec2(std::cos(angle), std::sin(angle));
    };
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        const double px = (x + 0.5) * lattice / size, py = (y + 0.5) * lattice / size;
        const int gx = int(std::floor(px)), gy = int(std::floor(py));
        const double fx = px - gx, fy = py - gy;
        auto corner = [&](int dx, int dy) {
          return glm::dot(gradient(gx + dx, gy + dy), glm::dvec2(fx - dx, fy - dy));
        };
        const double sx = smootherstep(fx), sy = smootherstep(fy);
        const double bottom = glm::mix(corner(0, 0), corner(1, 0), sx);
        const double top = glm::mix(corner(0, 1), corner(1, 1), sx);
        table.values[std::size_t(y) * size + x] += float(amplitude * glm::mix(bottom, top, sy));
      }
  }
  normaliseToUnit(table.values);
  return table;
}

int gardnerBakeSize(int terms, int texels_per_cycle) {
  while (texels_per_cycle > 2 && (texels_per_cycle << terms) > kMaxBakeSize) texels_per_cycle /= 2;
  return texels_per_cycle << terms;
}

GardnerTruncations bakeGardner(const GardnerTexture& texture, int size, int terms) {
  const int m = std::clamp(terms, 0, texture.terms());
  const glm::dvec2 period = texture.period();
  const double t0 = texture.params().t0, k = texture.normalisation();
  // Each term is sin(a(x) + b(y)) along X and sin(a'(y) + b'(x)) along Y, so the sines are
  // tabulated once per column and row: sin(a + b) = sin a cos b + cos a sin b. The tables are
  // taken in double and the sums in float, a row at a time, so that the columns run in SIMD
  // lanes (the values are stored as 16-bit fractions, far coarser than the float sums' error).
  const std::size_t n = std::size_t(size), cells = std::size_t(m) * n;
  std::vector<float> sin_ax(cells), cos_ax(cells), sin_py(cells), cos_py(cells);
  std::vector<float> sin_ay(cells), cos_ay(cells), sin_px(cells), cos_px(cells);
  for (int i = 0; i < m; ++i)
    for (std::size_t t = 0; t < n; ++t) {
      const double x = (t + 0.5) / size * period.x, y = (t + 0.5) / size * period.y;
      const double ax = texture.frequencyX(i) * x + texture.phaseX(i);
      const double ay = texture.frequencyY(i) * y + texture.phaseY(i);
      const double py =
          0.5 * std::numbers::pi * std::sin(0.5 * texture.frequencyX(i) * x);  // PY(i) at X
      const double px =
          0.5 * std::numbers::pi * std::sin(0.5 * texture.frequencyY(i) * y);  // PX(i) at Y
      const std::size_t j = std::size_t(i) * n + t;
      sin_ax[j] = float(std::sin(ax)), cos_ax[j] = float(std::cos(ax));
      sin_ay[j] = float(std::sin(ay)), cos_ay[j] = float(std::cos(ay));
      sin_py[j] = float(std::sin(py)), cos_py[j] = float(std::cos(py));
      sin_px[j] = float(std::sin(px)), cos_px[j] = float(std::cos(px));
    }
  GardnerTruncations out{{size, size, std::vector<float>(n * n)},
                         {size, size, std::vector<float>(n * n)}};
  const float t0f = float(t0);
  auto store = [&](float* to, const std::vector<float>& sx, const std::vector<float>& sy) {
    for (std::size_t col = 0; col < n; ++col) to[col] = float(textureFromSums(sx[col], sy[col], k));
  };
  std::vector<float> sx(n), sy(n);
  for (std::size_t row = 0; row < n; ++row) {
    std::fill(sx.begin(), sx.end(), t0f);
    std::fill(sy.begin(), sy.end(), t0f);
    if (m < 2) store(&out.one_fewer.values[row * n], sx, sy);  // T0 alone
    for (int i = 0; i < m; ++i) {
      // Along X the row's phase is fixed, along Y its term.
      const std::size_t first = std::size_t(i) * n, jy = first + row;
      const float c = float(texture.amplitude(i));
      const float cpx = c * cos_px[jy], spx = c * sin_px[jy];
      const float say = c * sin_ay[jy], cay = c * cos_ay[jy];
      const float *sax = &sin_ax[first], *cax = &cos_ax[first];
      const float *cpy = &cos_py[first], *spy = &sin_py[first];
      for (std::size_t col = 0; col < n; ++col) {
        sx[col] += sax[col] * cpx + cax[col] * spx;
        sy[col] += say * cpy[col] + cay * spy[col];
      }
      if (i == m - 2) store(&out.one_fewer.values[row * n], sx, sy);
    }
    store(&out.with_terms.values[row * n], sx, sy);
  }
  return out;
}

}  // namespace nephele
