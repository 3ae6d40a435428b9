#include "world/automaton/cloud_density.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "world/check.h"

namespace nephele {

namespace {

// The field of a^2 = (r / R)^2, for a^2 < 1.
double fieldOfSquare(double a2) {
  const double a4 = a2 * a2;
  return -4.0 / 9.0 * a4 * a2 + 17.0 / 9.0 * a4 - 22.0 / 9.0 * a2 + 1.0;
}

}  // namespace

double metaballField(double r, double radius) {
  return r < radius ? fieldOfSquare((r / radius) * (r / radius)) : 0.0;
}

std::vector<float> cellMeans(const CellularAutomaton& automaton, double radius_cells) {
  const GridSize n = automaton.size();
  const int reach = int(std::floor(radius_cells));
  std::vector<glm::ivec3> offsets;
  for (int dz = -reach; dz <= reach; ++dz)
    for (int dy = -reach; dy <= reach; ++dy)
      for (int dx = -reach; dx <= reach; ++dx)
        if (dx * dx + dy * dy + dz * dz <= radius_cells * radius_cells)
          offsets.push_back({dx, dy, dz});
  std::vector<float> means(std::size_t(n.cells()), 0.0f);
  const float share = 1.0f / float(offsets.size());
  // Scatter each cloudy cell's share to its neighbours: cost follows the cloudy cells.
  for (int k = 0; k < n.nz; ++k)
    for (int j = 0; j < n.ny; ++j)
      for (int i = 0; i < n.nx; ++i) {
        if (!automaton.get(CellBit::kCld, i, j, k)) continue;
        for (const glm::ivec3& o : offsets) {
          const glm::ivec3 c(i + o.x, j + o.y, k + o.z);
          if (c.x < 0 || c.y < 0 || c.z < 0 || c.x >= n.nx || c.y >= n.ny || c.z >= n.nz) continue;
          means[(std::size_t(c.z) * n.ny + c.y) * n.nx + c.x] += share;
        }
      }
  return means;
}

double metaballDensity(const std::vector<float>& means, GridSize size, double cell_size,
                       glm::dvec3 x, double radius_cells) {
  // In cell units, where cell (i, j, k) is centred on (i, j, k): the field needs only the
  // squared distance over R^2, and a row of cells beyond R is passed over whole.
  const glm::dvec3 c = x / cell_size - 0.5;
  const double reach2 = radius_cells * radius_cells;
  const glm::ivec3 lo = glm::max(glm::ivec3(glm::ceil(c - radius_cells)), glm::ivec3(0));
  const glm::ivec3 hi =
      glm::min(glm::ivec3(glm::floor(c + radius_cells)), glm::ivec3(size.nx, size.ny, size.nz) - 1);
  double rho = 0.0;
  for (int k = lo.z; k <= hi.z; ++k) {
    const double dz2 = (k - c.z) * (k - c.z);
    for (int j = lo.y; j <= hi.y; ++j) {
      const double dyz2 = dz2 + (j - c.y) * (j - c.y);
      if (!(dyz2 < reach2)) continue;
      const float* row = means.data() + (std::size_t(k) * size.ny + j) * size.nx;
      for (int i = lo.x; i <= hi.x; ++i) {
        if (row[i] == 0.0f) continue;
        const double d2 = dyz2 + (i - c.x) * (i - c.x);
        if (d2 < reach2) rho += row[i] * fieldOfSquare(d2 / reach2);
      }
    }
  }
  return rho;
}

double DensityLattice::densityAt(glm::dvec3 x) const {
  const glm::dvec3 u = (x - origin) / spacing;
  const glm::ivec3 base(glm::floor(u));
  const glm::dvec3 f = u - glm::dvec3(base);
  double rho = 0.0;
  for (int corner = 0; corner < 8; ++corner) {
    const glm::ivec3 o(corner & 1, (corner >> 1) & 1, corner >> 2);
    const glm::ivec3 s = base + o;
    if (glm::any(glm::lessThan(s, glm::ivec3(0))) || glm::any(glm::greaterThanEqual(s, dims)))
      continue;
    const double w = (o.x ? f.x : 1.0 - f.x) * (o.y ? f.y : 1.0 - f.y) * (o.z ? f.z : 1.0 - f.z);
    rho += w * density[index(s.x, s.y, s.z)];
  }
  return rho;
}

DensityLattice densityLattice(const std::vector<float>& means, GridSize size, double cell_size,
                              int samples_per_cell) {
  NEPHELE_CHECK(samples_per_cell >= 1, samples_per_cell);
  NEPHELE_CHECK(means.size() == std::size_t(size.cells()), means.size());
  const int r = samples_per_cell;
  const int margin = int(std::ceil(kMetaballRadiusCells * r));
  DensityLattice lattice;
  lattice.spacing = cell_size / r;
  lattice.dims =
      glm::ivec3((size.nx - 1) * r, (size.ny - 1) * r, (size.nz - 1) * r) + 1 + 2 * margin;
  lattice.origin = glm::dvec3(0.5 * cell_size - margin * lattice.spacing);
  lattice.density.assign(std::size_t(lattice.dims.x) * lattice.dims.y * lattice.dims.z, 0.0f);
  lattice.sunlight.assign(lattice.density.size(), 1.0f);
  lattice.sun_diffuse.assign(lattice.density.size(), 1.0f);

  // Samples are aligned with cell centres, so every cell sees the same kernel of weights.
  const double radius = kMetaballRadiusCells * cell_size;
  struct Tap {
    glm::ivec3 offset;
    float weight;
  };
  std::vector<Tap> kernel;
  for (int z = -margin; z <= margin; ++z)
    for (int y = -margin; y <= margin; ++y)
      for (int x = -margin; x <= margin; ++x) {
        const double w = metaballField(glm::length(glm::dvec3(x, y, z)) * lattice.spacing, radius);
        if (w > 0.0) kernel.push_back({{x, y, z}, float(w)});
      }
  glm::ivec3 lo(std::numeric_limits<int>::max()), hi(std::numeric_limits<int>::min());
  for (int k = 0; k < size.nz; ++k)
    for (int j = 0; j < size.ny; ++j)
      for (int i = 0; i < size.nx; ++i) {
        const float q = means[(std::size_t(k) * size.ny + j) * size.nx + i];
        if (q == 0.0f) continue;
        const glm::ivec3 centre = glm::ivec3(i, j, k) * r + margin;
        lo = glm::min(lo, centre - margin);
        hi = glm::max(hi, centre + margin);
        for (const Tap& tap : kernel) {
          const glm::ivec3 s = centre + tap.offset;
          lattice.density[lattice.index(s.x, s.y, s.z)] += q * tap.weight;
        }
      }
  if (lo.x <= hi.x) {
    lattice.occupied_lo = glm::max(lo - 1, glm::ivec3(0));
    lattice.occupied_hi = glm::min(hi + 1, lattice.dims - 1);
  }
  sweepSkylight(lattice);
  return lattice;
}

namespace {

// The optical depth from every sample out of the lattice along the unit direction `towards`, by
// one sweep from that side: each sample's is that of the point one slice further along
// (bilinear on that slice) plus the exact integral over the segment between them, with the
// density linear along it. O(samples).
std::vector<double> sweptOpticalDepth(const DensityLattice& lattice, glm::dvec3 towards,
                                      double extinction_per_m) {
  // Sweep along the axis the direction leans on most; B and C are the other two.
  int a = 0;
  for (int axis = 1; axis < 3; ++axis)
    if (std::abs(towards[axis]) > std::abs(towards[a])) a = axis;
  const int b = (a + 1) % 3, c = (a + 2) % 3;
  const glm::ivec3 dims = lattice.dims;
  const double da = std::abs(towards[a]);
  const int forward = towards[a] >= 0.0 ? 1 : -1;
  // One slice along moves by (db, dc) samples across and `length` metres.
  const double db = towards[b] / da, dc = towards[c] / da;
  const double length = lattice.spacing / da;
  auto at = [&](int ia, int ib, int ic) {
    glm::ivec3 s;
    s[a] = ia;
    s[b] = ib;
    s[c] = ic;
    return lattice.index(s.x, s.y, s.z);
  };
  std::vector<double> tau(lattice.density.size(), 0.0);
  const int first = forward > 0 ? dims[a] - 1 : 0;
  for (int ib = 0; ib < dims[b]; ++ib)
    for (int ic = 0; ic < dims[c]; ++ic) {
      // Beyond the first slice lies empty space: its density is 0 at the lattice edge.
      const std::size_t here = at(first, ib, ic);
      tau[here] = extinction_per_m * 0.5 * lattice.density[here] * length;
    }
  for (int ia = first - forward; ia >= 0 && ia < dims[a]; ia -= forward) {
    const int next = ia + forward;
    for (int ib = 0; ib < dims[b]; ++ib)
      for (int ic = 0; ic < dims[c]; ++ic) {
        const double ub = ib + db, uc = ic + dc;
        const int b0 = int(std::floor(ub)), c0 = int(std::floor(uc));
        const double fb = ub - b0, fc = uc - c0;
        double tau_next = 0.0, rho_next = 0.0;
        for (int corner = 0; corner < 4; ++corner) {
          const int sb = b0 + (corner & 1), sc = c0 + (corner >> 1);
          if (sb < 0 || sc < 0 || sb >= dims[b] || sc >= dims[c]) continue;  // open sky: 0
          const double w = ((corner & 1) ? fb : 1.0 - fb) * ((corner >> 1) ? fc : 1.0 - fc);
          const std::size_t s = at(next, sb, sc);
          tau_next += w * tau[s];
          rho_next += w * lattice.density[s];
        }
        const std::size_t here = at(ia, ib, ic);
        tau[here] = tau_next + extinction_per_m * 0.5 * (lattice.density[here] + rho_next) * length;
      }
  }
  return tau;
}

}  // namespace

void sweepSunlight(DensityLattice& lattice, glm::dvec3 to_sun, double extinction_per_m) {
  to_sun = glm::normalize(to_sun);
  const std::vector<double> towards = sweptOpticalDepth(lattice, to_sun, extinction_per_m);
  const std::vector<double> away = sweptOpticalDepth(lattice, -to_sun, extinction_per_m);
  lattice.sunlight.resize(lattice.density.size());
  lattice.sun_diffuse.resize(lattice.density.size());
  for (std::size_t i = 0; i < towards.size(); ++i) {
    lattice.sunlight[i] = float(std::exp(-towards[i]));
    lattice.sun_diffuse[i] = float(diffuseSunlight(towards[i], away[i]));
  }
}

void sweepSkylight(DensityLattice& lattice, double extinction_per_m) {
  lattice.skylight.assign(lattice.density.size(), 1.0f);
  const glm::ivec3 dims = lattice.dims;
  for (int y = 0; y < dims.y; ++y)
    for (int x = 0; x < dims.x; ++x) {
      // Down the column from the top sample, above which the density has fallen to 0 within
      // half a spacing (as in sweepSunlight); the optical depth summed exactly in double.
      double tau = 0.0, rho_above = 0.0, step = 0.5 * lattice.spacing;
      for (int z = dims.z - 1; z >= 0; --z) {
        const double rho = lattice.density[lattice.index(x, y, z)];
        tau += extinction_per_m * 0.5 * (rho + rho_above) * step;
        lattice.skylight[lattice.index(x, y, z)] = float(diffuseTransmittance(tau));
        rho_above = rho;
        step = lattice.spacing;
      }
    }
}

double cornetteShanksAsymmetry(double u) {
  const double u2 = u * u;
  const double x = 5.0 / 9.0 * u + 125.0 / 729.0 * u2 * u +
                   std::sqrt(64.0 / 27.0 - 325.0 / 243.0 * u2 + 1250.0 / 2187.0 * u2 * u2);
  const double cube_root = std::cbrt(x);
  return 5.0 / 9.0 * u - (4.0 / 3.0 - 25.0 / 81.0 * u2) / cube_root + cube_root;
}

}  // namespace nephele
