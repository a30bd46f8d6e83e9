// What a drive will make the rig do, predicted before it is played: the
// rod's displacement and velocity and the valve command, through the same
// FRF source the inverse comes from (drive_frf.hpp LoopPaths). The drive is
// the demand to a closed loop; above the loop's bandwidth the inverse raises
// it, but the rod, which draws the flow and meets the stroke and the rate
// detector, follows the closed loop: so the limits are judged on the
// predicted rod and command, not on the drive's own velocity.
//
// After a drive is played the prediction is compared with what the rig did
// (peak rod velocity and peak valve command), and the next prediction is
// multiplied by that ratio: the model's error on the rig's large-signal
// behaviour (the valve's two metering edges, friction) is taken from the
// rig itself.
#pragma once

#include <functional>
#include <vector>

#include "config/rig_config.hpp"
#include "tools/iterate/drive_frf.hpp"

namespace rigctl {

struct PredictedMotion {
  double rod_min = 0.0, rod_max = 0.0;  // [feedback unit] the rod's extremes
  double rod_velocity = 0.0;            // [unit/s] peak |d rod / dt|
  double valve_effort = 0.0;            // [1] peak |command| (the hold included)
};

struct MeasuredMotion {
  double rod_velocity = 0.0;  // [unit/s] peak, of the feedback low-passed at the band's top
  double valve_effort = 0.0;  // [1] peak |command|
};

// Measured over predicted, from the last played drive: the next prediction
// is multiplied by it (1: nothing measured yet).
struct PredictionCorrection {
  double velocity = 1.0;
  double effort = 1.0;
};

// The valve command a rod velocity needs, the hold included: the rig's
// large-signal valve law where the rig has one (the quarter car's orifice
// law through both metering edges of its asymmetric cylinder); empty for
// the others, whose command is predicted through the loop's FRF to it.
using ValveLaw = std::function<double(double velocity)>;
ValveLaw valve_law(const RigConfig& config, double command_hold);

// command_hold: the command that holds the rig at rest (the leakage's).
// The command: the valve law at the predicted rod's velocity where there is
// one (the linearised FRF to the command cannot tell extending from
// retracting, 30 % apart on the quarter car), else the FRF's.
PredictedMotion predict_motion(const LoopPaths& paths, const std::vector<double>& drive, double dt,
                               double command_hold, const ValveLaw& law, const PredictionCorrection& correction);

// feedback and command as recorded over the drive's ticks.
MeasuredMotion measured_motion(const std::vector<double>& feedback, const std::vector<double>& command, double dt,
                               double band_max_hz);

// Measured over predicted (the prediction as made, before any correction),
// each kept within [kMinRatio, kMaxRatio] so that one odd record cannot
// switch the check off or refuse everything.
PredictionCorrection correction_from(const PredictedMotion& uncorrected, const MeasuredMotion& measured);

}  // namespace rigctl
