#include "tools/tune/step_prediction.hpp"

#include <cmath>
#include <deque>
#include <memory>

#include "rt/control/pi_controller.hpp"
#include "rt/control/pvp_controller.hpp"
#include "tools/run/rig_assembly.hpp"

namespace rigctl {

namespace {

std::unique_ptr<Controller> controller_for(const RigConfig& c, const LoopGains& g) {
  ControllerConfig cc = c.controller;
  g.apply_to(cc);
  if (cc.type == ControllerKind::kPi) {
    PiConfig pi = cc.pi;
    pi.feedback_input = 0;
    pi.output_index = 0;
    return std::make_unique<PiController>(pi);
  }
  PvpConfig pvp = cc.pvp;
  pvp.angle_input = 0;
  pvp.pressure_input = 1;
  pvp.output_index = 0;
  return std::make_unique<PvpController>(pvp);
}

// y_k = sum b_i u_{k-i} - sum d_i y_{k-i}, histories newest first.
double filter_step(const std::vector<double>& d, const std::vector<double>& b, const std::deque<double>& u,
                   const std::deque<double>& y) {
  double v = 0.0;
  for (std::size_t i = 0; i < b.size() && i < u.size(); ++i) v += b[i] * u[i];
  for (std::size_t i = 0; i < d.size() && i < y.size(); ++i) v -= d[i] * y[i];
  return v;
}

}  // namespace

StepPrediction predict_step(const PlantModel& m, const LoopGains& g, const RigConfig& c, double hold_command) {
  StepPrediction out;
  out.test = standard_step(c);
  double duration = 0.0;
  auto profile = make_profile(c, duration);
  const double start = c.profile.start;
  if (c.profile.start_from_measurement) profile->start_from(start);
  auto controller = controller_for(c, g);
  // (1 - z^-1) A for the position, A for the pressure.
  std::vector<double> d_pos(m.a.size() + 1);
  for (std::size_t i = 0; i <= m.a.size(); ++i) d_pos[i] = (i < m.a.size() ? m.a[i] : 0.0) - (i == 0 ? 1.0 : m.a[i - 1]);
  std::deque<double> u_hist, y_hist, p_hist;
  double y = 0.0, p = 0.0;
  Sample sample{};
  Command command{};
  ControllerTerms terms{};
  const double period = c.loop.period_s;
  for (long k = 0; static_cast<double>(k) * period <= duration; ++k) {
    const double t = static_cast<double>(k) * period;
    sample.value[0] = start + y;
    sample.value[1] = p;
    const double r = profile->next(t);
    controller->update(r, sample, command, terms);
    out.t.push_back(t);
    out.demand.push_back(r);
    out.response.push_back(start + y);
    u_hist.push_front(command.value[0] - hold_command);
    y_hist.push_front(y);
    p_hist.push_front(p);
    y = filter_step(d_pos, m.b_position, u_hist, y_hist);
    if (m.has_pressure()) p = filter_step(m.a, m.b_pressure, u_hist, p_hist);
    const std::size_t keep = m.a.size() + 4;
    while (u_hist.size() > keep) u_hist.pop_back();
    while (y_hist.size() > keep) y_hist.pop_back();
    while (p_hist.size() > keep) p_hist.pop_back();
  }
  out.metrics = step_metrics(out.test, out.t, out.demand, out.response);
  return out;
}

}  // namespace rigctl
