// The world a hidden-effect run is made in differs from the diagnosis model
// the way a real rig differs from its nominal data (docs/diagnosis.md 7):
// every plant parameter drawn per run within a stated tolerance, the
// controller gains and the demand varied within the rig's stable range.
// A Perturbation draws those numbers from the run's seed and records each
// factor for the truth file, so a run can be re-made and a miss explained.
#pragma once

#include <cstdint>
#include <map>
#include <random>
#include <string>

namespace rigctl {

class Perturbation {
 public:
  // tolerance: the half-width of the uniform draw of every plant parameter,
  // as a fraction (0.05 = +-5 %); 0 leaves the plant at nominal (the
  // controller and demand draws then stay at nominal too).
  Perturbation(uint64_t seed, double tolerance) : rng_(seed * 7919u + 17u), tolerance_(tolerance) {}

  double tolerance() const { return tolerance_; }
  bool active() const { return tolerance_ > 0.0; }

  // Multiplies `value` by a factor uniform in [1 - tol, 1 + tol] (tol: the
  // plant tolerance unless given) and records it under `name`.
  void scale(const std::string& name, double& value, double tol = -1.0);
  // A factor uniform in [lo, hi], recorded under `name` (1 when inactive).
  double factor(const std::string& name, double lo, double hi);
  // An integer uniform in [0, n), recorded under `name` (0 when inactive).
  int pick(const std::string& name, int n);

  const std::map<std::string, double>& drawn() const { return drawn_; }

 private:
  double uniform(double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng_); }
  std::mt19937_64 rng_;
  double tolerance_;
  std::map<std::string, double> drawn_;
};

// Writes a copy of the demand table `in` (columns t and `column`) to `out`
// with the demand scaled by `amplitude` and the time axis stretched by
// `stretch`, resampled at the table's own step (linear interpolation).
// Throws std::runtime_error naming the file on a read or write failure.
void write_varied_demand(const std::string& in, const std::string& column, const std::string& out, double amplitude,
                         double stretch);

}  // namespace rigctl
