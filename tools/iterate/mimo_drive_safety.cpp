#include "tools/iterate/mimo_drive_safety.hpp"

#include <algorithm>
#include <cmath>

#include "tools/identify/channel_view.hpp"
#include "tools/iterate/mimo_inverse.hpp"
#include "tools/iterate/spectrum.hpp"

namespace rigctl {

namespace {

// Row `response` of the matrix at f, entry `drive`: below the first line
// the path at rest (a loop's own feedback 1 from its own demand, nothing
// from the others', a command 0) joined to the first line; a command's path
// falls with the frequency there as a velocity's command does.
std::complex<double> path_at(const FrfMatrixData& m, std::size_t response, std::size_t drive, bool is_command,
                             bool own, double f) {
  const MimoFrf& frf = m.frf;
  const double f0 = frf.frequency_hz.front();
  const auto j = static_cast<Eigen::Index>(response), i = static_cast<Eigen::Index>(drive);
  if (f >= f0) return mimo_frf_at(frf, f)(j, i);
  const std::complex<double> first = frf.value.front()(j, i);
  if (is_command) return first * (f / f0);
  if (f <= 0.0) return own ? 1.0 : 0.0;
  return first;
}

std::vector<double> predicted(const FrfMatrixData& m, std::size_t response, bool is_command, std::size_t actuator,
                              const std::vector<std::vector<double>>& deviations, double dt) {
  std::vector<double> sum(deviations.front().size(), m.response_mean[response]);
  for (std::size_t i = 0; i < deviations.size(); ++i) {
    const auto part = filtered(deviations[i], dt, [&](double f) { return path_at(m, response, i, is_command, i == actuator, f); });
    for (std::size_t t = 0; t < sum.size(); ++t) sum[t] += part[t];
  }
  return sum;
}

double peak_rate(const std::vector<double>& x, double dt) {
  double peak = 0.0;
  for (std::size_t i = 1; i + 1 < x.size(); ++i) peak = std::max(peak, std::abs(x[i + 1] - x[i - 1]) / (2.0 * dt));
  return peak;
}

}  // namespace

std::vector<ActuatorCheck> check_actuators(const RigConfig& config, const FrfMatrixData& m,
                                           const std::vector<std::vector<double>>& deviations) {
  const double dt = config.loop.period_s;
  std::vector<ActuatorCheck> out;
  for (std::size_t a = 0; a < channel_count(config); ++a) {
    const RigConfig one = channel_view(config, a);
    const ControllerConfig& c = one.controller;
    const std::size_t drive = a;
    const double op = m.operating_point.at(drive);
    const auto rod = predicted(m, m.response_index(c.feedback), false, a, deviations, dt);
    const auto command = predicted(m, m.response_index(c.output), true, a, deviations, dt);
    PredictedMotion p;
    const auto [lo, hi] = std::minmax_element(rod.begin(), rod.end());
    // About the operating point: the rod's mean at rest is the loop's, the demand.
    p.rod_min = *lo - m.response_mean[m.response_index(c.feedback)] + op;
    p.rod_max = *hi - m.response_mean[m.response_index(c.feedback)] + op;
    p.rod_velocity = peak_rate(rod, dt);
    for (double u : command) p.valve_effort = std::max(p.valve_effort, std::abs(u));
    std::vector<double> demand(deviations[drive]);
    for (double& v : demand) v += op;
    ActuatorCheck check;
    check.actuator = "actuator " + std::to_string(a + 1) + " (" + m.drives[drive].name + " -> " + c.feedback + ", " + c.output + ")";
    check.peaks = drive_peaks(demand, op, dt, p);
    check.verdict = check_drive(check.peaks, drive_limits(one), op);
    out.push_back(std::move(check));
  }
  return out;
}

std::string refusal(const std::vector<ActuatorCheck>& checks) {
  for (const auto& c : checks) {
    if (!c.verdict.ok) return c.actuator + ": " + c.verdict.reason;
  }
  return "";
}

}  // namespace rigctl
