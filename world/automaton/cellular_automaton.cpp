#include "world/automaton/cellular_automaton.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <thread>

#include "world/check.h"
#include "world/counter_random.h"

namespace nephele {
namespace {

int wordsFor(int nx) {
  return (nx + 63) / 64;
}

// Runs fn(k_begin, k_end) over [0, nz) split into `threads` slabs of layers.
template <class Fn>
void forSlabs(int nz, int threads, Fn&& fn) {
  threads = std::clamp(threads, 1, std::max(nz, 1));
  if (threads == 1) {
    fn(0, nz);
    return;
  }
  std::vector<std::jthread> workers;
  for (int t = 1; t < threads; ++t)
    workers.emplace_back([&fn, nz, threads, t] { fn(nz * t / threads, nz * (t + 1) / threads); });
  fn(0, nz / threads);
}

// Random purposes: one independent stream per stochastic rule.
enum Purpose : std::uint64_t { kExtinctionDraw = 1, kHumidityDraw = 2, kActivationDraw = 3 };

// For each lane in `lanes`, 1 with probability p(lane): compares an infinite string of random
// bits, most significant first, with p's 16 bits and stops once every lane has differed.
// `key` selects the stream; `word` makes the draws of every word independent.
std::uint64_t bernoulliWord(const ProbabilityField& p, std::size_t word, std::uint64_t lanes,
                            std::uint64_t key) {
  const std::uint64_t certain = p.certain(word) & lanes;
  std::uint64_t undecided = p.nonZero(word) & lanes & ~certain;
  std::uint64_t below = 0;
  for (int b = 0; b < ProbabilityField::kBits && undecided; ++b) {
    const std::uint64_t random = mix64(key ^ (std::uint64_t(word) * ProbabilityField::kBits + b));
    const std::uint64_t plane = p.plane(word, b);
    below |= undecided & ~random & plane;  // first differing bit: rnd has 0 where p has 1
    undecided &= ~(random ^ plane);
  }
  return certain | below;
}

}  // namespace

ProbabilityField::ProbabilityField(GridSize size)
    : size_(size),
      words_per_row_(wordsFor(size.nx)),
      planes_(std::size_t(words_per_row_) * size.ny * size.nz * kBits, 0),
      non_zero_(std::size_t(words_per_row_) * size.ny * size.nz, 0),
      certain_(non_zero_.size(), 0) {}

void ProbabilityField::set(int i, int j, int k, double p) {
  NEPHELE_CHECK(i >= 0 && i < size_.nx && j >= 0 && j < size_.ny && k >= 0 && k < size_.nz,
                i << "," << j << "," << k);
  const std::size_t word = (std::size_t(k) * size_.ny + j) * words_per_row_ + i / 64;
  const std::uint64_t lane = std::uint64_t(1) << (i % 64);
  const long q = std::lround(std::clamp(std::isnan(p) ? 0.0 : p, 0.0, 1.0) * 65536.0);
  certain_[word] = (q == 65536) ? certain_[word] | lane : certain_[word] & ~lane;
  non_zero_[word] = (q != 0) ? non_zero_[word] | lane : non_zero_[word] & ~lane;
  for (int b = 0; b < kBits; ++b) {
    const bool bit = (q >> (kBits - 1 - b)) & 1;
    std::uint64_t& plane = planes_[word * kBits + b];
    plane = bit ? plane | lane : plane & ~lane;
  }
}

double ProbabilityField::at(int i, int j, int k) const {
  const std::size_t word = (std::size_t(k) * size_.ny + j) * words_per_row_ + i / 64;
  const int lane = i % 64;
  if ((certain_[word] >> lane) & 1) return 1.0;
  long q = 0;
  for (int b = 0; b < kBits; ++b) q = (q << 1) | long((planes_[word * kBits + b] >> lane) & 1);
  return double(q) / 65536.0;
}

CellularAutomaton::CellularAutomaton(GridSize size, std::uint64_t seed)
    : size_(size), seed_(seed), words_per_row_(wordsFor(size.nx)) {
  NEPHELE_CHECK(size.nx > 0 && size.ny > 0 && size.nz > 0,
                size.nx << "x" << size.ny << "x" << size.nz);
  for (auto& b : bits_) b.assign(std::size_t(words_per_row_) * size.ny * size.nz, 0);
}

std::uint64_t CellularAutomaton::laneMask(int w) const {
  const int valid = std::min(64, size_.nx - 64 * w);
  return valid == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << valid) - 1;
}

bool CellularAutomaton::get(CellBit bit, int i, int j, int k) const {
  if (i < 0 || i >= size_.nx || j < 0 || j >= size_.ny || k < 0 || k >= size_.nz) return false;
  return (bits_[int(bit)][wordIndex(i / 64, j, k)] >> (i % 64)) & 1;
}

void CellularAutomaton::set(CellBit bit, int i, int j, int k, bool value) {
  NEPHELE_CHECK(i >= 0 && i < size_.nx && j >= 0 && j < size_.ny && k >= 0 && k < size_.nz,
                i << "," << j << "," << k);
  std::uint64_t& word = bits_[int(bit)][wordIndex(i / 64, j, k)];
  const std::uint64_t lane = std::uint64_t(1) << (i % 64);
  word = value ? word | lane : word & ~lane;
}

std::int64_t CellularAutomaton::count(CellBit bit) const {
  std::int64_t n = 0;
  for (std::uint64_t w : bits_[int(bit)]) n += std::popcount(w);
  return n;
}

void CellularAutomaton::growRows(int k_begin, int k_end, std::vector<std::uint64_t> next[3]) const {
  const auto& hum = bits_[int(CellBit::kHum)];
  const auto& act = bits_[int(CellBit::kAct)];
  const auto& cld = bits_[int(CellBit::kCld)];
  const int nw = words_per_row_;
  // act of row (j, k), word w; 0 outside the grid (MODEL.md section 6: cells outside read 0).
  auto actAt = [&](int w, int j, int k) -> std::uint64_t {
    if (j < 0 || j >= size_.ny || k < 0 || k >= size_.nz) return 0;
    return act[wordIndex(w, j, k)];
  };
  for (int k = k_begin; k < k_end; ++k)
    for (int j = 0; j < size_.ny; ++j)
      for (int w = 0; w < nw; ++w) {
        const std::size_t idx = wordIndex(w, j, k);
        const std::uint64_t a = act[idx];
        const std::uint64_t before = w > 0 ? act[idx - 1] : 0;
        const std::uint64_t after = w + 1 < nw ? act[idx + 1] : 0;
        // Bit i of (a << 1 | before >> 63) is act at i - 1, and so on along x.
        const std::uint64_t along_x = (a << 1 | before >> 63) | (a >> 1 | after << 63) |
                                      (a << 2 | before >> 62) | (a >> 2 | after << 62);
        // f_act: (i+-1, j, k), (i, j+-1, k), (i, j, k+-1), (i+-2, j, k), (i, j+-2, k), (i, j, k-2).
        const std::uint64_t f_act = along_x | actAt(w, j - 1, k) | actAt(w, j + 1, k) |
                                    actAt(w, j - 2, k) | actAt(w, j + 2, k) | actAt(w, j, k - 1) |
                                    actAt(w, j, k + 1) | actAt(w, j, k - 2);
        next[int(CellBit::kHum)][idx] = hum[idx] & ~a;
        next[int(CellBit::kCld)][idx] = cld[idx] | a;
        // hum is 0 in padding lanes, so the new act is too.
        next[int(CellBit::kAct)][idx] = ~a & hum[idx] & f_act;
      }
}

void CellularAutomaton::growth(int threads) {
  std::vector<std::uint64_t> next[3];
  for (auto& b : next) b.resize(bits_[0].size());
  forSlabs(size_.nz, threads, [&](int k0, int k1) { growRows(k0, k1, next); });
  for (int b = 0; b < 3; ++b) bits_[b].swap(next[b]);
}

void CellularAutomaton::stochasticRows(const AutomatonProbabilities& p, int k_begin, int k_end) {
  auto& hum = bits_[int(CellBit::kHum)];
  auto& act = bits_[int(CellBit::kAct)];
  auto& cld = bits_[int(CellBit::kCld)];
  const std::uint64_t ext_key = hashCounters(seed_, steps_, kExtinctionDraw);
  const std::uint64_t hum_key = hashCounters(seed_, steps_, kHumidityDraw);
  const std::uint64_t act_key = hashCounters(seed_, steps_, kActivationDraw);
  for (int k = k_begin; k < k_end; ++k)
    for (int j = 0; j < size_.ny; ++j)
      for (int w = 0; w < words_per_row_; ++w) {
        const std::size_t idx = wordIndex(w, j, k);
        const std::uint64_t lanes = laneMask(w);
        // Draws only where they can change a bit; each draw depends on (seed, step, cell,
        // purpose) alone, so skipping the others changes nothing.
        if (cld[idx]) cld[idx] &= ~bernoulliWord(p.extinction, idx, cld[idx], ext_key);
        if (~hum[idx] & lanes)
          hum[idx] |= bernoulliWord(p.humidity, idx, ~hum[idx] & lanes, hum_key);
        if (~act[idx] & lanes)
          act[idx] |= bernoulliWord(p.activation, idx, ~act[idx] & lanes, act_key);
      }
}

void CellularAutomaton::stochastic(const AutomatonProbabilities& p, int threads) {
  NEPHELE_CHECK(
      p.humidity.size() == size_ && p.activation.size() == size_ && p.extinction.size() == size_,
      "probability fields sized for another grid");
  forSlabs(size_.nz, threads, [&](int k0, int k1) { stochasticRows(p, k0, k1); });
}

void CellularAutomaton::step(const AutomatonProbabilities& p, int threads) {
  growth(threads);
  stochastic(p, threads);
  ++steps_;
}

void CellularAutomaton::shiftLayer(int k, int dx, int dy) {
  NEPHELE_CHECK(k >= 0 && k < size_.nz, k);
  if (dx == 0 && dy == 0) return;
  const int nw = words_per_row_;
  std::vector<std::uint64_t> row(nw);
  for (auto& bits : bits_) {
    std::vector<std::uint64_t> layer(std::size_t(nw) * size_.ny, 0);
    for (int j = 0; j < size_.ny; ++j) {
      const int source_j = j - dy;
      if (source_j < 0 || source_j >= size_.ny) continue;
      const std::uint64_t* src = &bits[wordIndex(0, source_j, k)];
      // Bit i of the new row is bit i - dx of the old one.
      for (int w = 0; w < nw; ++w) {
        std::uint64_t value = 0;
        for (int part = 0; part < 2; ++part) {
          // Old bits [64 w - dx, 64 w - dx + 63] span at most two source words.
          const long first = 64L * w - dx;
          const long source_word = (first >= 0 ? first / 64 : (first - 63) / 64) + part;
          const int offset = int(first - 64L * (source_word - part));  // 0..63
          if (source_word < 0 || source_word >= nw) continue;
          const std::uint64_t s = src[source_word];
          if (part == 0)
            value |= s >> offset;
          else if (offset != 0)
            value |= s << (64 - offset);
        }
        layer[std::size_t(j) * nw + w] = value & laneMask(w);
      }
    }
    std::copy(layer.begin(), layer.end(), bits.begin() + wordIndex(0, 0, k));
  }
}

bool CellularAutomaton::restore(std::uint64_t steps, const std::vector<std::uint64_t>& hum,
                                const std::vector<std::uint64_t>& act,
                                const std::vector<std::uint64_t>& cld) {
  const std::size_t n = bits_[0].size();
  if (hum.size() != n || act.size() != n || cld.size() != n) return false;
  for (const auto* bits : {&hum, &act, &cld})
    for (std::size_t idx = 0; idx < n; ++idx)
      if ((*bits)[idx] & ~laneMask(int(idx % words_per_row_))) return false;
  bits_[0] = hum;
  bits_[1] = act;
  bits_[2] = cld;
  steps_ = steps;
  return true;
}

}  // namespace nephele
