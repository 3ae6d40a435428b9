#pragma once
// Dobashi's cellular automaton for cloud growth (MODEL.md section 6). Each of the three bits
// (hum, act, cld) is packed 64 cells to a word along x, so the growth rules run as bitwise
// operations over whole words, and the stochastic rules make 64 Bernoulli draws at once.
#include <cstdint>
#include <vector>

namespace nephele {

struct GridSize {
  int nx = 0;
  int ny = 0;
  int nz = 0;
  std::int64_t cells() const { return std::int64_t(nx) * ny * nz; }
  bool operator==(const GridSize&) const = default;
};

// A probability per cell, quantised to 1/65536 and stored as 16 bit planes per word (most
// significant first). Comparing a word of random bits with the planes one plane at a time
// decides rnd < p for 64 cells together, and usually after a handful of planes.
class ProbabilityField {
 public:
  static constexpr int kBits = 16;

  ProbabilityField() = default;
  explicit ProbabilityField(GridSize size);

  GridSize size() const { return size_; }
  void set(int i, int j, int k, double p);  // p clamped to [0, 1]
  double at(int i, int j, int k) const;
  // Lanes of `word` whose probability is non-zero.
  std::uint64_t nonZero(std::size_t word) const { return non_zero_[word]; }
  std::uint64_t plane(std::size_t word, int bit) const { return planes_[word * kBits + bit]; }
  // Lanes that are certain (p = 1), which need no draw.
  std::uint64_t certain(std::size_t word) const { return certain_[word]; }

 private:
  GridSize size_;
  int words_per_row_ = 0;
  std::vector<std::uint64_t> planes_;
  std::vector<std::uint64_t> non_zero_;
  std::vector<std::uint64_t> certain_;
};

// The three per-cell probabilities of the extinction and supply rules.
struct AutomatonProbabilities {
  ProbabilityField humidity;    // p_hum
  ProbabilityField activation;  // p_act
  ProbabilityField extinction;  // p_ext
};

enum class CellBit { kHum = 0, kAct = 1, kCld = 2 };

class CellularAutomaton {
 public:
  CellularAutomaton() = default;
  // All cells start with every bit 0. `seed` keys the random draws.
  CellularAutomaton(GridSize size, std::uint64_t seed);

  GridSize size() const { return size_; }
  std::uint64_t seed() const { return seed_; }
  std::uint64_t steps() const { return steps_; }  // completed steps
  int wordsPerRow() const { return words_per_row_; }

  bool get(CellBit bit, int i, int j, int k) const;
  void set(CellBit bit, int i, int j, int k, bool value);
  std::int64_t count(CellBit bit) const;

  // One full step: growth, then extinction and supply, with the step's own random draws.
  // `threads` > 1 splits the grid into slabs; the result is the same for any count.
  void step(const AutomatonProbabilities& p, int threads = 1);
  // The parts of a step, for tests; `step` is growth() then stochastic() then steps_ + 1.
  void growth(int threads = 1);
  void stochastic(const AutomatonProbabilities& p, int threads = 1);

  // Moves layer k by whole cells (wind); cells leaving the grid are lost, entering ones are 0.
  void shiftLayer(int k, int dx, int dy);

  // The packed words of one bit, rows of wordsPerRow() words, x fastest (for snapshots).
  const std::vector<std::uint64_t>& words(CellBit bit) const { return bits_[int(bit)]; }
  // Replaces the state; false if the sizes do not match or padding bits are set.
  bool restore(std::uint64_t steps, const std::vector<std::uint64_t>& hum,
               const std::vector<std::uint64_t>& act, const std::vector<std::uint64_t>& cld);

 private:
  std::size_t wordIndex(int w, int j, int k) const {
    return (std::size_t(k) * size_.ny + j) * words_per_row_ + w;
  }
  std::uint64_t laneMask(int w) const;  // valid cells of word w in a row
  void growRows(int k_begin, int k_end, std::vector<std::uint64_t> next[3]) const;
  void stochasticRows(const AutomatonProbabilities& p, int k_begin, int k_end);

  GridSize size_;
  std::uint64_t seed_ = 0;
  std::uint64_t steps_ = 0;
  int words_per_row_ = 0;
  std::vector<std::uint64_t> bits_[3];
};

}  // namespace nephele
