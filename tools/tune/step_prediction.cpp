#include "tools/tune/step_prediction.hpp"

#include <cmath>
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

}  // namespace

StepPrediction predict_step(const PlantModel& m, const LoopGains& g, const RigConfig& c, double hold_command) {
  StepPrediction out;
  out.test = standard_step(c);
  double duration = 0.0;
  auto profile = make_profile(c, duration);
  const double start = c.profile.start;
  if (c.profile.start_from_measurement) profile->start_from(start);
  auto controller = controller_for(c, g);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(m.phi.rows());  // deviation from the operating point
  Sample sample{};
  Command command{};
  ControllerTerms terms{};
  const double period = c.loop.period_s;
  for (long k = 0; static_cast<double>(k) * period <= duration; ++k) {
    const double t = static_cast<double>(k) * period;
    const Eigen::VectorXd y = m.c * x;
    sample.value[0] = start + y(0);
    sample.value[1] = m.has_pressure() ? y(1) : 0.0;
    const double r = profile->next(t);
    controller->update(r, sample, command, terms);
    out.t.push_back(t);
    out.demand.push_back(r);
    out.response.push_back(sample.value[0]);
    x = m.phi * x + m.gamma * (command.value[0] - hold_command);
  }
  out.metrics = step_metrics(out.test, out.t, out.demand, out.response);
  return out;
}

}  // namespace rigctl
