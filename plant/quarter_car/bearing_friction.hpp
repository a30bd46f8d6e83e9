// Friction law of the quarter-car body's linear bearings (seed 000 section 3
// and appendix B, with the slips resolved in docs/rig-models.md 1.5.3-1.5.4).
// Pure functions: the stick/slip bookkeeping lives in the plant, which knows
// the sub-step boundaries where the mode may change.
#pragma once

#include "plant/quarter_car/quarter_car_params.hpp"

namespace rigctl {

// Force levels of the bearing at one instant; all >= 0 [N].
struct BearingFrictionLevels {
  double normal = 0.0;     // F_n: side load the inclined spring-damper puts on the rails
  double coulomb = 0.0;    // F_c = F_c0 + mu F_n
  double breakaway = 0.0;  // F_s = F_c + dF_s: largest force a stuck bearing holds
};

// Eq. 14: change of the spring-damper's inclination when the suspension
// deflects by `deflection` = x_w - x_b [m]. The asin argument is clamped to
// [-1, 1] so that absurd deflections give a finite angle instead of NaN.
double linkage_angle_change(const BearingFrictionParams& p, double deflection);

// Eqs. 19-21 with the static preload: F_n = |body_weight + F_susp| / tan(theta - dtheta).
// `suspension_force` is the dynamic part ks (x_w - x_b) + bd (v_w - v_b) [N].
BearingFrictionLevels bearing_friction_levels(const BearingFrictionParams& p, double body_weight,
                                              double suspension_force, double deflection);

// Friction of a sliding bearing, signed as it opposes the body: positive when
// the body slides up. `direction` (+1 up, -1 down) is the stored slip
// direction, not sign(velocity), so that an RK4 stage that overshoots zero
// velocity does not flip the force inside a step. Decaying Stribeck form:
// direction (F_c + (F_s - F_c) exp(-(|v|/v_s)^delta)) + D v, which starts at
// the breakaway force at v = 0 so that the stick -> slip switch is
// force-continuous.
double sliding_friction(const BearingFrictionParams& p, const BearingFrictionLevels& levels,
                        int direction, double velocity);

}  // namespace rigctl
