// Shared pieces of the half-car active-suspension controllers (fuzzy,
// skyhook, LQR): where their measurements sit in the sample, the body
// corner kinematics, and the passive case (no active force).
//
// Every suspension controller regulates the body to rest: the loop's
// setpoint is the body heave demand z_s at the centre of gravity (0 for
// the road-disturbance tests); the road is the disturbance. Outputs are the
// two actuator forces f_1, f_2 [N] (positive lifts the body at corner i,
// see plant/half_car/half_car_params.hpp), each clamped to +-force_limit.
#pragma once

#include <array>
#include <cstddef>

#include "rt/control/controller.hpp"

namespace rigctl {

// Actuator force limit per corner [N]. Chosen (the paper gives none, only
// that its forces stay "well within the constraints"): 2 kN, about 40 % of
// the front static tyre load (5.4 kN), so that full pull cannot unload a
// tyre at rest, and within the 1-3 kN of electro-hydraulic suspension
// actuators in the literature.
inline constexpr double kDefaultSuspensionForceLimit = 2000.0;

// Sample indices; the defaults are HalfCarPlant's signals() order.
struct SuspensionChannels {
  int z_s = 2;
  int phi = 3;
  int z_u1 = 4;
  int z_u2 = 5;
  int z_s_dot = 6;
  int z_s_ddot = 7;
  int phi_dot = 8;
  int phi_ddot = 9;
  int z_u1_dot = 10;
  int z_u2_dot = 11;
  int output_1 = 0;  // command index of f_1
  int output_2 = 1;  // command index of f_2
};

// Lever arms l1 > 0, l2 < 0 of the corners from the centre of gravity [m]:
// pitch {a, -b}, roll {w/2, -w/2}. Default: the pitch-plane half car.
using LeverArms = std::array<double, 2>;
inline constexpr LeverArms kPitchLeverArms = {1.524, -1.156};

inline double sample_at(const Sample& s, int index) noexcept { return s.value[static_cast<std::size_t>(index)]; }

// Body corner i from centre-of-gravity quantities: q + l_i * angle-quantity.
struct BodyCorners {
  std::array<double, 2> displacement{};  // z_s + l_i phi [m]
  std::array<double, 2> velocity{};      // [m/s]
  std::array<double, 2> acceleration{};  // [m/s^2]
};
BodyCorners body_corners(const Sample& s, const SuspensionChannels& ch, const LeverArms& lever) noexcept;

void write_forces(Command& command, const SuspensionChannels& ch, double f1, double f2) noexcept;

// The terms every half-car controller reports besides its own (fill_terms):
// the body heave z_s against the demand, the first force before (raw) and
// after its limit, saturated when either force was limited.
void fill_suspension_terms(ControllerTerms& terms, double setpoint, const Sample& sample, const SuspensionChannels& ch,
                           const std::array<double, 2>& raw, const std::array<double, 2>& force) noexcept;

// Passive suspension: both actuator forces 0. Terms: none.
class PassiveSuspensionController final : public Controller {
 public:
  explicit PassiveSuspensionController(const SuspensionChannels& channels = {}) : channels_(channels) {}
  const std::string& name() const override { return name_; }
  const std::vector<std::string>& term_names() const override { return term_names_; }
  void reset() noexcept override {}
  void update(double setpoint, const Sample& sample, Command& command, ControllerTerms& terms) noexcept override;

 private:
  SuspensionChannels channels_;
  std::string name_ = "passive";
  std::vector<std::string> term_names_;
};

}  // namespace rigctl
