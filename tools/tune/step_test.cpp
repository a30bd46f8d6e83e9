#include "tools/tune/step_test.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "tools/run/rig_assembly.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {

namespace {

constexpr double kSettlingBand = 0.02;  // 2 % of the step: the usual settling criterion

}  // namespace

StepTest standard_step(const RigConfig& c) {
  const ProfileConfig& p = c.profile;
  if (p.type != ProfileKind::kRampSteps) {
    throw std::invalid_argument(c.file + ": profile.type: the standard step test needs ramp_steps");
  }
  const double lead = p.hold_s + std::abs(p.ramp_target - p.start) / p.ramp_rate;
  double previous = 0.0;
  for (std::size_t i = 0; i < p.steps.size(); ++i) {
    if (p.steps[i] == previous) continue;
    StepTest s;
    s.step_time_s = lead + static_cast<double>(i) * p.step_hold_s;
    s.step = p.steps[i] - previous;
    s.target = p.ramp_target + p.steps[i];
    s.window_end_s = s.step_time_s + p.step_hold_s;
    s.end_s = lead + static_cast<double>(p.steps.size()) * p.step_hold_s;
    return s;
  }
  throw std::invalid_argument(c.file + ": profile.steps: no step moves the demand");
}

StepMetrics step_metrics(const StepTest& s, const std::vector<double>& t, const std::vector<double>& demand,
                         const std::vector<double>& response, double t_offset) {
  StepMetrics m;
  const double t0 = s.step_time_s + t_offset, t1 = s.window_end_s + t_offset, t_end = s.end_s + t_offset;
  const double dir = s.step > 0.0 ? 1.0 : -1.0;
  double last_outside = t0;
  for (std::size_t i = 0; i < t.size(); ++i) {
    if (t[i] < t0) continue;
    if (t[i] <= t1) {
      m.overshoot = std::max(m.overshoot, dir * (response[i] - s.target) / std::abs(s.step));
      if (std::abs(response[i] - s.target) > kSettlingBand * std::abs(s.step)) last_outside = t[i];
    }
    if (i + 1 < t.size() && t[i] < t_end) m.iae += std::abs(demand[i] - response[i]) * (t[i + 1] - t[i]);
  }
  m.settling_s = last_outside - t0;
  return m;
}

StepMetrics measured_step(const RigConfig& c, const std::string& path) {
  const std::string demand = setpoint_name_for(c.rig);
  const RunFile f = read_run_file(path, RunFileOptions{{c.controller.output, c.controller.feedback, demand}, {}, false, 10});
  const auto& u = f.col(c.controller.output);
  std::size_t first = 0;
  while (first < u.size() && u[first] == 0.0) ++first;
  const double offset = first > 0 ? f.t[first - 1] : 0.0;
  return step_metrics(standard_step(c), f.t, f.col(demand), f.col(c.controller.feedback), offset);
}

}  // namespace rigctl
