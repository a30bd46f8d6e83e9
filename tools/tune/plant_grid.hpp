// The measured plant between its frequencies: log-magnitude and unwrapped
// phase interpolated linearly in log frequency, on the coherent part of the
// FRF only (a design must not rest on noise).
#pragma once

#include <vector>

#include "tools/tune/loop_response.hpp"

namespace rigctl {

// Points below this coherence are left out of designs and margins.
inline constexpr double kDesignCoherence = 0.8;

class PlantGrid {
 public:
  explicit PlantGrid(const PlantResponse& measured, double min_coherence = kDesignCoherence);
  double f_min() const { return f_.front(); }
  double f_max() const { return f_.back(); }
  Complex position(double f_hz) const { return at(f_hz, pos_db_, pos_deg_); }
  Complex pressure(double f_hz) const { return has_pressure_ ? at(f_hz, pr_db_, pr_deg_) : Complex{}; }
  bool has_pressure() const { return has_pressure_; }
  // `points` log-spaced frequencies over the coherent band.
  std::vector<double> log_grid(std::size_t points) const;
  // The loop transfer of `gains` on that grid.
  std::vector<Complex> loop(const LoopGains& gains, const std::vector<double>& f_hz) const;
  std::vector<Complex> inner_loop(const LoopGains& gains, const std::vector<double>& f_hz) const;

 private:
  Complex at(double f, const std::vector<double>& db, const std::vector<double>& deg) const;
  std::vector<double> f_, pos_db_, pos_deg_, pr_db_, pr_deg_;
  bool has_pressure_ = false;
};

}  // namespace rigctl
