#include "world/textures/solid_texture.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "world/counter_random.h"
#include "world/textures/texture_table.h"

namespace nephele {
namespace {

// Unit gradient for a lattice point: uniform on the sphere from two counter-based draws.
glm::dvec3 latticeGradient(std::uint64_t seed, int octave, int x, int y, int z) {
  const std::uint64_t cell = (std::uint64_t(std::uint32_t(x)) << 32) | std::uint32_t(y);
  const double u = unitFromBits(hashCounters(seed, 0x50336430ull + octave, cell, std::uint32_t(z)));
  const double v = unitFromBits(hashCounters(seed, 0x50336431ull + octave, cell, std::uint32_t(z)));
  const double cos_theta = 2.0 * u - 1.0, sin_theta = std::sqrt(1.0 - cos_theta * cos_theta);
  const double phi = 2.0 * std::numbers::pi * v;
  return {sin_theta * std::cos(phi), sin_theta * std::sin(phi), cos_theta};
}
}  // namespace

float VolumeTable::at(int x, int y, int z, int channel) const {
  return values[((std::size_t(wrapIndex(z, size)) * size + wrapIndex(y, size)) * size +
                 wrapIndex(x, size)) *
                    channels +
                channel];
}

double VolumeTable::sampleTrilinear(glm::dvec3 uvw) const {
  const glm::dvec3 p = uvw * double(size) - 0.5;
  const glm::dvec3 f = glm::floor(p), t = p - f;
  const int ix = int(std::fmod(f.x, double(size))), iy = int(std::fmod(f.y, double(size))),
            iz = int(std::fmod(f.z, double(size)));
  double sum = 0.0;
  for (int dz = 0; dz < 2; ++dz)
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx)
        sum += (dx ? t.x : 1.0 - t.x) * (dy ? t.y : 1.0 - t.y) * (dz ? t.z : 1.0 - t.z) *
               at(ix + dx, iy + dy, iz + dz);
  return sum;
}

VolumeTable bakeGardnerSums(const GardnerTexture& texture, int size, int first, int count) {
  const std::size_t n = std::size_t(std::max(size, 0));
  VolumeTable out;
  out.size = size;
  out.channels = 2;
  out.values.resize(2 * n * n * n);
  bakeGardnerSums(texture, size, first, count,
                  [&](std::size_t z, std::size_t y, const float* sx, const float* sy) {
                    float* texel = &out.values[2 * (z * n + y) * n];
                    for (std::size_t x = 0; x < n; ++x)
                      texel[2 * x] = sx[x], texel[2 * x + 1] = sy[x];
                  });
  return out;
}

void bakeGardnerSums(const GardnerTexture& texture, int size, int first, int count,
                     const GardnerSumRow& row) {
  first = std::clamp(first, 0, texture.terms());
  const int end = std::clamp(first + count, first, texture.terms());
  const int m = end - first;
  const glm::dvec2 p2 = texture.period() / std::exp2(first);
  const glm::dvec3 period(p2.x, p2.y, p2.x);  // Z phases run at FX / 2
  const std::size_t n = std::size_t(size);
  // Term i along X is sin(a(x) + b(y, z)), along Y sin(a'(y) + b'(x, z)) (MODEL.md section 2,
  // solid phases): tabulate a per coordinate and b per pair, then sin(a + b) by addition. The
  // tables and sums are float, a row of x at a time, so the compiler runs x in SIMD lanes: the
  // table is stored as half floats, 2^-11 relative, far coarser than the float sums' error.
  std::vector<float> sin_ax(m * n), cos_ax(m * n), sin_ay(m * n), cos_ay(m * n);
  std::vector<float> sin_bx(m * n * n), cos_bx(m * n * n), sin_by(m * n * n), cos_by(m * n * n);
  std::vector<float> amplitude(m);
  auto coordinate = [&](std::size_t t, int axis) { return (t + 0.5) / size * period[axis]; };
  for (int i = 0; i < m; ++i) {
    const int term = first + i;
    amplitude[i] = float(texture.amplitude(term));
    const double fx = texture.frequencyX(term), fy = texture.frequencyY(term);
    for (std::size_t t = 0; t < n; ++t) {
      const double ax = fx * coordinate(t, 0) + texture.phaseX(term);
      const double ay = fy * coordinate(t, 1) + texture.phaseY(term);
      sin_ax[i * n + t] = float(std::sin(ax)), cos_ax[i * n + t] = float(std::cos(ax));
      sin_ay[i * n + t] = float(std::sin(ay)), cos_ay[i * n + t] = float(std::cos(ay));
    }
    // b = PX(y) + PZ(z) and PY(x) + PZ(z), by addition again: sines per coordinate only.
    std::vector<glm::dvec2> px(n), py(n), pz(n);  // (sin, cos) of each phase
    auto sinCos = [](double a) { return glm::dvec2(std::sin(a), std::cos(a)); };
    for (std::size_t t = 0; t < n; ++t) {
      px[t] = sinCos(0.5 * std::numbers::pi * std::sin(0.5 * fy * coordinate(t, 1)));
      py[t] = sinCos(0.5 * std::numbers::pi * std::sin(0.5 * fx * coordinate(t, 0)));
      pz[t] = sinCos(std::numbers::pi * std::sin(0.5 * fx * coordinate(t, 2)));
    }
    for (std::size_t z = 0; z < n; ++z)
      for (std::size_t t = 0; t < n; ++t) {
        const std::size_t j = (i * n + z) * n + t;
        const glm::dvec2 c = pz[z];
        sin_bx[j] = float(px[t].x * c.y + px[t].y * c.x);
        cos_bx[j] = float(px[t].y * c.y - px[t].x * c.x);
        sin_by[j] = float(py[t].x * c.y + py[t].y * c.x);
        cos_by[j] = float(py[t].y * c.y - py[t].x * c.x);
      }
  }
  std::vector<float> sx(n), sy(n);
  for (std::size_t z = 0; z < n; ++z)
    for (std::size_t y = 0; y < n; ++y) {
      std::fill(sx.begin(), sx.end(), 0.0f);
      std::fill(sy.begin(), sy.end(), 0.0f);
      for (int i = 0; i < m; ++i) {
        const float c = amplitude[i];
        // Along X the b term is fixed on the row, along Y the a term.
        const std::size_t row = (i * n + z) * n;
        const float cbx = c * cos_bx[row + y], sbx = c * sin_bx[row + y];
        const float say = c * sin_ay[i * n + y], cay = c * cos_ay[i * n + y];
        const float *sax = &sin_ax[i * n], *cax = &cos_ax[i * n];
        const float *sby = &sin_by[row], *cby = &cos_by[row];
        for (std::size_t x = 0; x < n; ++x) {
          sx[x] += sax[x] * cbx + cax[x] * sbx;
          sy[x] += say * cby[x] + cay * sby[x];
        }
      }
      row(z, y, sx.data(), sy.data());
    }
}

VolumeTable perlinVolume(int size, int cells, int octaves, double persistence, std::uint64_t seed) {
  const std::size_t n = std::size_t(size);
  VolumeTable table{size, std::vector<float>(n * n * n, 0.0f)};
  double amplitude = 1.0;
  for (int octave = 0; octave < octaves; ++octave, amplitude *= persistence) {
    const int lattice = cells << octave;
    for (std::size_t z = 0; z < n; ++z)
      for (std::size_t y = 0; y < n; ++y)
        for (std::size_t x = 0; x < n; ++x) {
          const glm::dvec3 p = (glm::dvec3(x, y, z) + 0.5) * double(lattice) / double(size);
          const glm::ivec3 g(glm::floor(p));
          const glm::dvec3 f = p - glm::dvec3(g);
          auto corner = [&](int dx, int dy, int dz) {
            const glm::dvec3 grad =
                latticeGradient(seed, octave, wrapIndex(g.x + dx, lattice),
                                wrapIndex(g.y + dy, lattice), wrapIndex(g.z + dz, lattice));
            return glm::dot(grad, f - glm::dvec3(dx, dy, dz));
          };
          const glm::dvec3 s(smootherstep(f.x), smootherstep(f.y), smootherstep(f.z));
          double v = 0.0;
          for (int dz = 0; dz < 2; ++dz)
            for (int dy = 0; dy < 2; ++dy)
              for (int dx = 0; dx < 2; ++dx)
                v += (dx ? s.x : 1.0 - s.x) * (dy ? s.y : 1.0 - s.y) * (dz ? s.z : 1.0 - s.z) *
                     corner(dx, dy, dz);
          table.values[(z * n + y) * n + x] += float(amplitude * v);
        }
  }
  normaliseToUnit(table.values);
  return table;
}

SolidTexture::SolidTexture(const SolidTextureSpec& spec) : spec_(spec) {
  if (spec_.source == SolidTextureSource::kGardner) {
    GardnerTextureParams params = spec_.gardner;
    params.seed = spec_.seed;
    gardner_ = std::make_unique<GardnerTexture>(params);
  } else {
    volume_ = std::make_unique<VolumeTable>(perlinVolume(1 << spec_.perlin_size_log2,
                                                         spec_.perlin_cells, spec_.perlin_octaves,
                                                         spec_.perlin_persistence, spec_.seed));
  }
}

glm::dvec3 SolidTexture::period() const {
  if (!gardner_) return glm::dvec3(spec_.perlin_period_m);
  const glm::dvec2 p = gardner_->period();
  return {p.x, p.y, p.x};
}

glm::dvec3 SolidTexture::periodicCoordinate(glm::dvec3 world) const {
  const glm::dvec3 p = period();
  return {wrapPeriodic(world.x, p.x) / p.x, wrapPeriodic(world.y, p.y) / p.y,
          wrapPeriodic(world.z, p.z) / p.z};
}

double SolidTexture::value(glm::dvec3 world) const {
  const glm::dvec3 uvw = periodicCoordinate(world);
  if (gardner_) return gardner_->solid(uvw * period(), gardner_->terms());
  return volume_->sampleTrilinear(uvw);
}

}  // namespace nephele
