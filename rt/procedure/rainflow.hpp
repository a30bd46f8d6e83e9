// Streaming rainflow counting, ASTM E1049-85 (reapproved 2017) section 5.4.4,
// the three-point method, with its residue kept.
//
// Samples go in one at a time (a tick, or a recorded run read in pieces);
// turning points are found as they are confirmed (the next sample moving the
// other way), and each one runs the standard's steps 2-5 on a fixed stack:
// a range Y at least as large as the newest range X is a full cycle when the
// starting point is not in it, and a half cycle (the starting point moves on)
// when it is. What never closes stays on the stack: the residue. Step 6 (the
// residue's ranges counted as half cycles) is what `residue_half_cycles`
// does, on a copy, so a matrix can be written at a block end and the count
// still go on: a history counted in pieces gives the same cycles as in one
// pass.
//
// Nothing here allocates after construction: the stack is a fixed array. A
// stack that fills (a history that keeps converging for kStackCapacity
// turning points, which a stationary load never does) counts its oldest
// range as a half cycle and drops its first point, and says so in
// `overflowed()`; the damage of that range is kept, only its pairing with a
// later range is lost.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

namespace rigctl {

// One counted range: from one turning point to the next, whole or half.
struct RainflowCycle {
  double from = 0.0;
  double to = 0.0;
  double count = 0.0;  // 1 (full cycle) or 0.5 (half)
  double range() const noexcept { return from > to ? from - to : to - from; }
  double mean() const noexcept { return 0.5 * (from + to); }
};

// Where counted cycles go (the matrix and the damage sum, or a test's list).
class CycleSink {
 public:
  virtual ~CycleSink() = default;
  virtual void on_cycle(const RainflowCycle& c) noexcept = 0;
};

class RainflowCounter {
 public:
  // 512 turning points: the residue of a random load grows like the log of
  // its length (a few tens for 10^9 cycles); 512 leaves room for programs
  // that ramp their amplitude down over hundreds of levels.
  static constexpr std::size_t kStackCapacity = 512;

  void reset() noexcept;
  // The next sample. Cycles that close go to `sink` at once.
  void push(double x, CycleSink& sink) noexcept;
  // ASTM step 6 for the history so far, without changing the count: the
  // pending last point taken as a turning point, then every range left on
  // the stack as a half cycle. Pure: calling it twice gives the same cycles.
  void residue_half_cycles(CycleSink& sink) const noexcept;

  // The turning points on the stack (the residue), oldest first, and the
  // last sample not yet confirmed as a turning point.
  std::size_t residue_size() const noexcept { return size_; }
  double residue_point(std::size_t i) const noexcept { return stack_[i]; }
  bool has_pending() const noexcept { return started_; }
  double pending() const noexcept { return candidate_; }
  int direction() const noexcept { return direction_; }
  bool overflowed() const noexcept { return overflowed_; }

  // Restores a counter from its residue, pending point and direction (a
  // resumed test: rt/procedure/procedure_state.hpp). Points beyond the
  // capacity are refused: returns false.
  bool restore(const double* points, std::size_t n, bool has_pending, double pending, int direction) noexcept;

 private:
  // A confirmed turning point through steps 2-5.
  static void add_turning_point(double x, std::array<double, kStackCapacity>& stack, std::size_t& size,
                                bool& overflowed, CycleSink& sink) noexcept;

  std::array<double, kStackCapacity> stack_{};
  std::size_t size_ = 0;
  bool started_ = false;  // a first sample was seen: candidate_ holds the newest extreme
  double candidate_ = 0.0;
  int direction_ = 0;  // +1 rising, -1 falling, 0 not yet known (all samples equal so far)
  bool overflowed_ = false;
};

// A range-mean matrix over fixed bins, and the pseudo-damage sum.
//
// Pseudo-damage (Basquin): each cycle adds count * (range / reference)^b,
// b the Basquin exponent (S-N slope; about 3 for welded steel, 5-10 for
// rubber and forged parts). With the reference range the damage of one
// cycle of that range is 1: the sum is "equivalent reference cycles", which
// compares tests on the same part without knowing its S-N curve.
// 32 bins each way: enough to see a block program's levels apart and small
// enough to write at every block end (1024 counts).
inline constexpr std::size_t kRainflowBins = 32;

// The matrix's numbers as plain data (a recovery file holds them as bytes).
struct RainflowMatrixData {
  std::array<std::array<double, kRainflowBins>, kRainflowBins> counts{};
  double lo = -1.0, hi = 1.0;
  double exponent = 3.0;
  double reference = 1.0;
  double total = 0.0;
  double damage = 0.0;
};

class RainflowMatrix final : public CycleSink {
 public:
  static constexpr std::size_t kBins = kRainflowBins;

  // Ranges from 0 to span, means from lo to hi (span = hi - lo). A cycle
  // outside is counted in the nearest bin (its damage is exact anyway).
  void configure(double lo, double hi, double basquin_exponent, double reference_range) noexcept;
  void reset() noexcept;
  void on_cycle(const RainflowCycle& c) noexcept override;

  double count(std::size_t range_bin, std::size_t mean_bin) const noexcept { return d_.counts[range_bin][mean_bin]; }
  double range_bin_centre(std::size_t i) const noexcept { return (static_cast<double>(i) + 0.5) * range_width(); }
  double mean_bin_centre(std::size_t j) const noexcept { return d_.lo + (static_cast<double>(j) + 0.5) * mean_width(); }
  double total_cycles() const noexcept { return d_.total; }
  double damage() const noexcept { return d_.damage; }
  double lo() const noexcept { return d_.lo; }
  double hi() const noexcept { return d_.hi; }
  double basquin_exponent() const noexcept { return d_.exponent; }
  double reference_range() const noexcept { return d_.reference; }
  // Adds another matrix's counts and damage (committed + residue).
  void add(const RainflowMatrix& other) noexcept;
  // The numbers, to save and restore (a resumed test).
  const RainflowMatrixData& data() const noexcept { return d_; }
  void set_data(const RainflowMatrixData& d) noexcept { d_ = d; }

 private:
  double range_width() const noexcept { return (d_.hi - d_.lo) / static_cast<double>(kBins); }
  double mean_width() const noexcept { return (d_.hi - d_.lo) / static_cast<double>(kBins); }
  static std::size_t bin(double x, double lo, double width) noexcept;

  RainflowMatrixData d_;
};

// A channel's whole count: the counter and its committed matrix. `snapshot`
// gives committed + residue (ASTM step 6) without disturbing the stream.
class RainflowChannel {
 public:
  void configure(double lo, double hi, double basquin_exponent, double reference_range) noexcept {
    counter_.reset();
    committed_.configure(lo, hi, basquin_exponent, reference_range);
  }
  void push(double x) noexcept { counter_.push(x, committed_); }
  void snapshot(RainflowMatrix& out) const noexcept;
  const RainflowCounter& counter() const noexcept { return counter_; }
  RainflowCounter& counter() noexcept { return counter_; }
  const RainflowMatrix& committed() const noexcept { return committed_; }
  RainflowMatrix& committed() noexcept { return committed_; }

 private:
  RainflowCounter counter_;
  RainflowMatrix committed_;
};

}  // namespace rigctl
