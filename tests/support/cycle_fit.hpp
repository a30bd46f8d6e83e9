// Per-cycle measurements of a recorded procedure, written here rather than
// taken from the runner: the fundamental of the feedback against the wanted
// sine (least squares on the wanted value and its quadrature, the branch
// from the wanted signal's slope), and a cycle's peak and valley.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "rt/procedure_status.hpp"

namespace rigctl::proctest {

struct ProcedureTick {
  double wanted = 0.0;  // the programmed demand (status.wanted)
  double demand = 0.0;  // what the loop was told (compensated)
  double y = 0.0;       // the feedback of the tick
  double watched = 0.0; // another channel (the peak-valley detector's)
  ProcedureStatus status;
};

struct CycleFit {
  double amplitude_ratio = 0.0;  // feedback fundamental / wanted amplitude
  double phase_deg = 0.0;        // feedback against the wanted sine, + leads
  double mean = 0.0;
};

// Ticks of a step's counted cycle `cycle` (status.step_cycles == cycle:
// the (cycle+1)-th test cycle of the step).
inline CycleFit fit_cycle(const std::vector<ProcedureTick>& log, int32_t step, int64_t cycle, double mean,
                          double amplitude) {
  double A[3][3] = {}, B[3] = {};
  for (std::size_t i = 1; i + 1 < log.size(); ++i) {
    const ProcedureStatus& s = log[i].status;
    if (s.step != step || s.phase != ProcedurePhase::kRun || s.step_cycles != cycle) continue;
    const double w = std::clamp((log[i].wanted - mean) / amplitude, -1.0, 1.0);
    const double dw = log[i + 1].wanted - log[i - 1].wanted;
    const double c = (dw >= 0 ? 1.0 : -1.0) * std::sqrt(1.0 - w * w);
    const double v[3] = {1.0, w, c};
    for (int r = 0; r < 3; ++r) {
      for (int q = 0; q < 3; ++q) A[r][q] += v[r] * v[q];
      B[r] += v[r] * log[i].y;
    }
  }
  for (int p = 0; p < 3; ++p) {
    for (int r = p + 1; r < 3; ++r) {
      const double f = A[r][p] / A[p][p];
      for (int q = p; q < 3; ++q) A[r][q] -= f * A[p][q];
      B[r] -= f * B[p];
    }
  }
  double x[3];
  for (int r = 2; r >= 0; --r) {
    double acc = B[r];
    for (int q = r + 1; q < 3; ++q) acc -= A[r][q] * x[q];
    x[r] = acc / A[r][r];
  }
  return {std::hypot(x[1], x[2]) / amplitude, std::atan2(x[2], x[1]) * 180.0 / M_PI, x[0]};
}

}  // namespace rigctl::proctest
