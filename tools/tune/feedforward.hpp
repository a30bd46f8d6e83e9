// The demand feedforward `rigctl tune` adds to a PI on a plant that
// integrates (a valve-controlled cylinder: command -> flow -> rod speed).
// Feedback alone follows a moving demand with an error that shrinks as ki
// grows, and ki is bounded by the phase margin; the feedforward opens the
// valve for the demanded speed, kff = 1 / K_v with K_v the plant's velocity
// gain [m/s per unit command], so the feedback is left only the model's
// error. It acts outside the loop: the margins are the PI's alone.
//
// K_v is read from the measured plant FRF as |G(j w)| w, the median over the
// coherent lines in the octave below the designed crossover, where the
// feedback hands the tracking over to it. Not at the lowest lines: there
// the small excitation moves the rod slowly, and the leakage under the
// load's pressure and the bearing's friction take a larger share of the
// flow (the simulated quarter car: 0.18 m/s at 0.5 Hz, 0.31 at 10 Hz; on
// its 50 mm step, read 0.2 s into the rise and the fall from the tracked
// demand's speed over the valve command, about 0.36 extending and 0.25
// retracting).
// One K_v for both edges of an asymmetric cylinder: the PI corrects the rest.
#pragma once

#include <string>

#include "config/rig_config.hpp"
#include "tools/tune/loop_response.hpp"

namespace rigctl {

struct FeedforwardDesign {
  double kff = 0.0;             // [s per feedback unit]; 0 = none
  double velocity_gain = 0.0;   // K_v [feedback unit / s per command unit], when measured
  double band_low_hz = 0.0, band_high_hz = 0.0;  // the lines K_v was read from
  std::string reason_for_none;  // why kff is 0, when it is
};

// The velocity feedforward for the rig's PI from the measured plant and the
// designed crossover; none (with the reason) for a P+V+dP controller, a
// config whose standard step is unfiltered (a step in one tick would be one
// tick at full valve), no coherent line below the crossover, or a plant
// whose phase there is not an integrator's (-90 deg within 30 deg).
FeedforwardDesign design_feedforward(const PlantResponse& plant, double crossover_hz, const RigConfig& config);

}  // namespace rigctl
