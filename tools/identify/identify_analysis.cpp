#include "tools/identify/identify_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "tools/identify/frf_estimate.hpp"

namespace rigctl {

std::size_t find_excitation_start(const std::vector<double>& demand, double op, const std::vector<double>& excitation,
                                  std::size_t settle_ticks) {
  const double tol = 1e-9 * std::max(1.0, std::abs(op));
  std::size_t first_nonzero = 0;
  while (first_nonzero < excitation.size() && std::abs(excitation[first_nonzero]) <= tol) ++first_nonzero;
  const std::size_t needed = std::max<std::size_t>(1, settle_ticks / 2);
  std::size_t held = 0;
  for (std::size_t i = 0; i < demand.size(); ++i) {
    if (std::abs(demand[i] - op) <= tol) {
      ++held;
      continue;
    }
    if (held >= needed && i >= first_nonzero) {
      const std::size_t start = i - first_nonzero;
      if (start + excitation.size() > demand.size()) break;
      return start;
    }
    held = 0;
  }
  throw std::runtime_error("the log holds no complete excitation after a hold at the operating point " +
                           std::to_string(op) + " (was the run cut short?)");
}

namespace {

WelchSettings welch_settings(const Excitation& e, double sample_rate_hz) {
  WelchSettings w;
  w.segment = e.segment_ticks;
  w.sample_rate_hz = sample_rate_hz;
  if (e.periodic) {
    w.window = SpectralWindow::kRectangular;  // whole periods: no leakage, no overlap needed
    w.step = e.segment_ticks;
  } else {
    w.window = SpectralWindow::kHann;
    w.step = e.segment_ticks / 2;
  }
  return w;
}

double mean_of(std::span<const double> x) {
  double s = 0.0;
  for (double v : x) s += v;
  return x.empty() ? 0.0 : s / static_cast<double>(x.size());
}

}  // namespace

FrfData analyse_identification(const RunFile& run, const IdentifyPlan& plan, const Excitation& excitation,
                               const FrfChannel& demand, const FrfChannel& command,
                               const std::vector<FrfChannel>& responses) {
  const auto& r = run.col(demand.name);
  const double op = plan.operating_point;
  const auto settle_ticks = static_cast<std::size_t>(plan.settle_s / run.dt);
  const std::size_t start = find_excitation_start(r, op, excitation.values, settle_ticks);
  const std::size_t n = excitation.values.size();
  // The first segment is the loop settling into the excitation: not analysed.
  const std::size_t from = start + excitation.segment_ticks, to = start + n;
  if (to <= from + excitation.segment_ticks - 1) throw std::runtime_error("excitation too short: fewer than two segments");

  FrfData f;
  f.demand = demand;
  f.command = command;
  f.responses = responses;
  f.sample_rate_hz = 1.0 / run.dt;
  const std::size_t len = to - from;
  IdentificationRecord rec{std::span<const double>(r).subspan(from, len),
                           std::span<const double>(run.col(command.name)).subspan(from, len), {}};
  for (const auto& ch : responses) rec.responses.push_back(std::span<const double>(run.col(ch.name)).subspan(from, len));
  const WelchSettings w = welch_settings(excitation, f.sample_rate_hz);
  estimate_frf(rec, w, plan.excitation.band_min_hz, plan.excitation.band_max_hz, excitation.lines, f);

  f.estimation.window = std::string(to_string(w.window));
  f.estimation.segment_s = static_cast<double>(w.segment) * run.dt;
  f.estimation.overlap = 1.0 - static_cast<double>(w.step) / static_cast<double>(w.segment);
  f.estimation.analysed_from_s = run.t[from];
  f.estimation.analysed_to_s = run.t[to - 1] + run.dt;
  f.operating_point.demand = op;
  f.operating_point.response_mean = mean_of(rec.responses.front());
  f.operating_point.command_mean = mean_of(rec.command);

  auto& x = f.excitation;
  x.kind = std::string(to_string(plan.excitation.kind));
  x.band_min_hz = plan.excitation.band_min_hz;
  x.band_max_hz = plan.excitation.band_max_hz;
  x.amplitude = plan.excitation.amplitude;
  x.amplitude_requested = plan.amplitude_requested;
  x.amplitude_clamp = plan.clamp.limit;
  x.clamp_reason = plan.clamp.reason;
  x.duration_s = static_cast<double>(n) * run.dt;
  x.start_s = run.t[start];
  x.end_s = run.t[to - 1] + run.dt;
  for (std::size_t i = start; i < to; ++i) x.logged_peak = std::max(x.logged_peak, std::abs(r[i] - op));
  return f;
}

}  // namespace rigctl
