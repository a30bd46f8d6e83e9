// The drive safety check: before a drive is played, its displacement, its
// velocity and the valve effort it will need are checked against the rig's
// limits from the config. A drive that would exceed them is refused, naming
// the limit, or (when asked) scaled about the operating point until it fits.
// The check is on the drive (the demand), so that the loop's own limit
// detectors never have to trip: a target beyond the actuator's reach ends
// the iteration here, with the valve never driven past its means.
#pragma once

#include <string>
#include <vector>

#include "config/rig_config.hpp"

namespace rigctl {

struct DriveLimits {
  double position_min = 0.0, position_max = 0.0;  // [feedback unit]
  std::string position_source;                    // e.g. "safety.setpoint_range"
  double velocity_max = 0.0;                      // [unit/s]; infinity: no limit in the config
  std::string velocity_source;
  double effort_max = 0.0;                        // [1] of the valve's rated command
  std::string effort_source;
};

struct DrivePeaks {
  double min = 0.0, max = 0.0;     // [unit] the drive's extremes
  double displacement = 0.0;       // [unit] largest |drive - operating point|
  double velocity = 0.0;           // [unit/s] largest |d drive / dt|
  double valve_effort = 0.0;       // [1] predicted largest |valve command| (0: no prediction for this rig)
};

struct DriveVerdict {
  bool ok = true;
  std::string reason;  // the limit exceeded with the least room (the one that stops the drive), with the numbers
  double fit_scale = 1.0;  // the largest factor on (drive - operating point) that fits every limit (> 1: room to spare)
};

DriveLimits drive_limits(const RigConfig& config);

// The valve effort a rod velocity needs [fraction of rated command]: the
// quarter car's orifice law through both metering edges of the asymmetric
// cylinder against its static load; 0 for rigs without this prediction.
double predicted_valve_effort(const RigConfig& config, double velocity, double command_hold);

// command_hold: the valve command that holds the rig still at the operating
// point (the quarter car's leakage needs one; its linearisation gives it).
DrivePeaks drive_peaks(const RigConfig& config, const std::vector<double>& drive, double operating_point,
                       double command_hold);

DriveVerdict check_drive(const DrivePeaks& peaks, const DriveLimits& limits, double operating_point);

// (drive - operating point) x scale + operating point.
void scale_drive(std::vector<double>& drive, double operating_point, double scale);

}  // namespace rigctl
