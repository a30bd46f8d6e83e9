// Pure Coulomb friction of the caliper brake (seed 002 section 2.3, Fig. 2d),
// and the rest/motion decision shared by every friction-like torque on the
// rotary load (the brake and the step part of the bladder hysteresis).
//
// Sliding: the torque is +-T_c with the stored direction of motion, not
// sign(omega), so an RK4 stage that overshoots zero velocity does not flip
// it. At rest: the load holds while the residual torque R (everything else
// acting on it) stays within the holding capacity, and the friction then
// carries exactly R: it opposes but never exceeds the applied torque. No
// velocity threshold, no tanh and no division by the velocity: the stick
// state is a separate mode of the plant, changed only between RK4 steps.
#pragma once

#include "plant/pneumatic_rotary/pneumatic_rotary_params.hpp"

namespace rigctl {

// T_c = level x max torque [N m]; 0 when disabled.
double coulomb_brake_level(const CoulombBrakeParams& p, double max_torque);

// Direction in which a load at rest starts to move under residual torque
// `residual` [N m] against holding capacity `capacity` [N m] >= 0: 0 while
// |residual| <= capacity (it stays), else the sign of the residual.
int breakaway_direction(double residual, double capacity);

// The part of a holding torque `residual` that one of several friction-like
// elements carries while the load is at rest: shared in proportion to their
// capacities (the split is not observable in the motion; this one keeps each
// element within its own level). 0 when the total capacity is 0.
double holding_share(double residual, double capacity, double total_capacity);

}  // namespace rigctl
