// How many RK4 sub-steps the quarter car needs per control period.
//
// The step is limited by stability, not accuracy: the oil column's
// stiffness on the light rod (about 770 Hz at mid-stroke, nominal) and, at
// the ends of the stroke, the smaller chamber and the end stop on top of it.
// RK4 is stable for h |lambda| up to about 2.8 on the imaginary axis. A fixed
// count (20, as the plant first had) was 2.5 times what the nominal rig
// needs, and still not safe for every parameter set the diagnosis fits or
// the hidden-effect generator draws (a stiffer oil or smaller dead volumes
// raise the mode). So the count follows the parameters: the fastest rate is
// bounded from above, and the step keeps h * rate <= 2.5.
//
// The bound: the rod mass on the sum of the worst end's hydraulic stiffness
// beta (A1^2 / V1 + A2^2 / V2), the end stop's and the tyre's. Damping only
// moves the eigenvalues into RK4's wider left-half region, and entrained
// air only softens the oil, so neither is needed for an upper bound.
#pragma once

#include "plant/quarter_car/quarter_car_params.hpp"

namespace rigctl {

// Upper bound of |lambda| over the stroke [rad/s].
double quarter_car_fastest_rate(const QuarterCarParams& p);

// RK4 sub-steps for a period dt: params.substeps when set (> 0), else the
// fewest that keep dt / n * fastest_rate <= kQuarterCarStepLimit.
int quarter_car_substeps(const QuarterCarParams& p, double dt);
int quarter_car_substeps(const QuarterCarParams& p, double fastest_rate, double dt);

// h * |lambda| kept at or below this: 2.5 of RK4's 2.83 on the imaginary axis.
inline constexpr double kQuarterCarStepLimit = 2.5;

}  // namespace rigctl
