// Rainflow counting (rt/procedure/rainflow.hpp) against ASTM E1049-85's own
// worked example, and streamed in pieces against one pass.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

#include "rt/procedure/rainflow.hpp"

using namespace rigctl;

namespace {

struct CycleList final : CycleSink {
  std::vector<RainflowCycle> cycles;
  void on_cycle(const RainflowCycle& c) noexcept override { cycles.push_back(c); }
};

// Counts by (range, mean), half cycles as 0.5.
std::map<std::pair<double, double>, double> by_range_and_mean(const std::vector<RainflowCycle>& cycles) {
  std::map<std::pair<double, double>, double> m;
  for (const auto& c : cycles) m[{c.range(), c.mean()}] += c.count;
  return m;
}

std::vector<RainflowCycle> count_all(const std::vector<double>& history) {
  RainflowCounter counter;
  CycleList list;
  for (double x : history) counter.push(x, list);
  counter.residue_half_cycles(list);
  return list.cycles;
}

}  // namespace

// ASTM E1049-85 (2017) Fig. 6 and Table 4: the load history
// A..I = -2, 1, -3, 5, -1, 3, -4, 4, -2 by the three-point method gives
// range 3: 0.5, 4: 1.5, 6: 0.5, 8: 1.0, 9: 0.5 cycles (10, 7, 5: none).
// The means are those of Fig. 6's pairs: A-B, B-C (half), E-F (full),
// C-D (half) and the residue D-G, G-H, H-I.
TEST(Rainflow, AstmE1049WorkedExampleCountedExactly) {
  const auto cycles = count_all({-2, 1, -3, 5, -1, 3, -4, 4, -2});
  const auto m = by_range_and_mean(cycles);
  const std::map<std::pair<double, double>, double> expected = {
      {{3.0, -0.5}, 0.5},  // A-B, half (contains S)
      {{4.0, -1.0}, 0.5},  // B-C, half
      {{4.0, 1.0}, 1.0},   // E-F, full
      {{8.0, 1.0}, 0.5},   // C-D, half
      {{9.0, 0.5}, 0.5},   // D-G, residue
      {{8.0, 0.0}, 0.5},   // G-H, residue
      {{6.0, 1.0}, 0.5},   // H-I, residue
  };
  EXPECT_EQ(m, expected);
  std::map<double, double> per_range;
  for (const auto& [key, n] : m) per_range[key.first] += n;
  const std::map<double, double> table4 = {{3, 0.5}, {4, 1.5}, {6, 0.5}, {8, 1.0}, {9, 0.5}};
  EXPECT_EQ(per_range, table4);
  // Half and full cycles in the order the method finds them.
  ASSERT_EQ(cycles.size(), 7u);
  EXPECT_EQ(cycles[2].count, 1.0);  // E-F is the one full cycle
  EXPECT_EQ(cycles[2].from, -1.0);
  EXPECT_EQ(cycles[2].to, 3.0);
}

// Samples between the turning points (a sampled sine-like history) and flat
// tops change nothing: the same cycles as the turning points alone.
TEST(Rainflow, SamplesBetweenTurningPointsAndFlatTopsChangeNothing) {
  const std::vector<double> turning = {-2, 1, -3, 5, -1, 3, -4, 4, -2};
  std::vector<double> sampled;
  for (std::size_t i = 0; i + 1 < turning.size(); ++i) {
    for (int k = 0; k < 7; ++k) sampled.push_back(turning[i] + (turning[i + 1] - turning[i]) * k / 7.0);
    sampled.push_back(turning[i + 1]);  // a flat top: the turning point twice
  }
  sampled.push_back(turning.back());
  EXPECT_EQ(by_range_and_mean(count_all(sampled)), by_range_and_mean(count_all(turning)));
}

// The residue is not consumed by asking for it: the count goes on, and a
// history counted in pieces (with snapshots between) equals one pass.
TEST(Rainflow, LongRandomHistoryStreamedInPiecesEqualsOnePass) {
  std::mt19937_64 rng(20261127);
  std::normal_distribution<double> white(0.0, 1.0);
  std::vector<double> history(200000);
  double y = 0.0;
  for (auto& x : history) {
    y = 0.97 * y + white(rng);  // a narrow-band-ish random load, many turning points
    x = y;
  }
  RainflowChannel one;
  one.configure(-40.0, 40.0, 5.0, 10.0);
  for (double x : history) one.push(x);
  RainflowMatrix whole;
  one.snapshot(whole);

  RainflowChannel pieces;
  pieces.configure(-40.0, 40.0, 5.0, 10.0);
  std::uniform_int_distribution<std::size_t> piece(1, 5000);
  RainflowMatrix interim;
  for (std::size_t i = 0; i < history.size();) {
    const std::size_t n = std::min(piece(rng), history.size() - i);
    for (std::size_t k = 0; k < n; ++k) pieces.push(history[i + k]);
    i += n;
    pieces.snapshot(interim);  // a block end's matrix: must not disturb the count
  }
  RainflowMatrix streamed;
  pieces.snapshot(streamed);
  for (std::size_t r = 0; r < RainflowMatrix::kBins; ++r) {
    for (std::size_t c = 0; c < RainflowMatrix::kBins; ++c) ASSERT_EQ(streamed.count(r, c), whole.count(r, c));
  }
  EXPECT_EQ(streamed.total_cycles(), whole.total_cycles());
  EXPECT_DOUBLE_EQ(streamed.damage(), whole.damage());
  EXPECT_GT(whole.total_cycles(), 10000.0);
  EXPECT_FALSE(pieces.counter().overflowed());
  // Every half cycle of the residue, and nothing else, is a half cycle:
  // there are at most residue + 1 halves in the final count beyond those
  // found while streaming.
  EXPECT_LT(pieces.counter().residue_size(), 64u);
}

// The number of cycles of a sine: N full cycles (the residue's halves make
// up the start and the end), and the Basquin sum of N cycles at the
// reference range is N.
TEST(Rainflow, SineOfNCyclesGivesNCyclesAndDamageN) {
  RainflowChannel ch;
  ch.configure(-2.0, 2.0, 4.0, 2.0);
  const int n = 50, per_cycle = 40;
  for (int i = 0; i <= n * per_cycle; ++i) ch.push(std::sin(2.0 * M_PI * i / per_cycle + M_PI / 2));  // peak to peak
  RainflowMatrix m;
  ch.snapshot(m);
  EXPECT_NEAR(m.total_cycles(), n, 1e-12);
  EXPECT_NEAR(m.damage(), n, 1e-9);
}

// A resumed count continues exactly: restore the residue, pending point and
// direction into a fresh counter and the rest of the history counts the same.
TEST(Rainflow, RestoredResidueContinuesTheCount) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> history(5000);
  for (auto& x : history) x = u(rng);
  CycleList whole, split;
  RainflowCounter a, b;
  for (double x : history) a.push(x, whole);
  a.residue_half_cycles(whole);
  for (std::size_t i = 0; i < 2345; ++i) b.push(history[i], split);
  std::vector<double> residue;
  for (std::size_t i = 0; i < b.residue_size(); ++i) residue.push_back(b.residue_point(i));
  RainflowCounter c;
  ASSERT_TRUE(c.restore(residue.data(), residue.size(), b.has_pending(), b.pending(), b.direction()));
  for (std::size_t i = 2345; i < history.size(); ++i) c.push(history[i], split);
  c.residue_half_cycles(split);
  EXPECT_EQ(by_range_and_mean(split.cycles), by_range_and_mean(whole.cycles));
}
