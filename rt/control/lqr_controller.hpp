// LQR active suspension for the half car: state feedback f = -K x on the
// eight states of the linear model (plant/half_car/half_car_model.hpp), gains from
// the continuous-time Riccati equation (rt/control/lqr_riccati.hpp), forces clamped.
//
// Measured states: all eight, x = [z_s - setpoint, phi, z_u1, z_u2, z_s_dot,
// phi_dot, z_u1_dot, z_u2_dot]. On the rig the displacements come from
// LVDTs to the rig frame (z_s, phi from two body LVDTs, z_u1/2 as in the
// run-file spec) and the rates from velocity transducers and a gyro; the
// plant exposes each as a channel. The road is the disturbance and is not
// fed back (z_u is regulated towards 0, which is the tyre deflection on a
// level road).
//
// Cost (Bryson's rule: each weight is 1 / (largest acceptable value)^2):
//   J = integral  (z_s''/a)^2 + (phi''/alpha)^2 + sum_i (travel_i/s)^2
//               + sum_i (z_ui/t)^2 + (z_s/h)^2 + (phi/p)^2 + sum_i (F_i/F)^2 dt
// The accelerations depend on the forces directly, which gives the cross
// term N and adds to R.
//
// The design itself (Eigen) is in rt/control/lqr_design.hpp: this header is
// read wherever a rig's config is (config/rig_config.hpp), and Eigen's Dense
// module would cost every one of those translation units its parse.
#pragma once

#include <array>

#include "plant/half_car/half_car_params.hpp"
#include "rt/control/suspension_controller.hpp"

namespace rigctl {

struct LqrWeights {
  double heave_acceleration = 1.0;   // a [m/s^2]: comfort first
  double angle_acceleration = 1.0;   // alpha [rad/s^2]
  double suspension_travel = 0.08;   // s [m]: a typical +-80 mm of working travel
  double tyre_deflection = 0.01;     // t [m]: about 1/3 of the static tyre deflection (27-33 mm)
  double heave = 0.05;               // h [m]
  double angle = 0.03;               // p [rad]
  double force = 2000.0;             // F [N]: the actuator limit
};

struct LqrConfig {
  std::array<std::array<double, 8>, 2> gain{};  // K, rows f_1, f_2
  double force_limit = kDefaultSuspensionForceLimit;  // [N]
  SuspensionChannels channels;
  // Gains of design_half_car_lqr(params, weights).
  static LqrConfig from_design(const HalfCarParams& params, const LqrWeights& weights = {}, double force_limit = kDefaultSuspensionForceLimit);
};

class LqrController final : public Controller {
 public:
  explicit LqrController(const LqrConfig& config);
  const std::string& name() const override { return name_; }
  // "f_1", "f_2": clamped forces; "body_1", "wheel_1", "body_2", "wheel_2":
  // the parts of each unclamped force from the body states (z_s, phi and
  // rates) and the wheel states.
  const std::vector<std::string>& term_names() const override { return term_names_; }
  void reset() noexcept override {}
  void update(double setpoint, const Sample& sample, Command& command, ControllerTerms& terms) noexcept override;

 private:
  LqrConfig config_;
  std::string name_ = "lqr";
  std::vector<std::string> term_names_{"f_1", "f_2", "body_1", "wheel_1", "body_2", "wheel_2"};
};

}  // namespace rigctl
