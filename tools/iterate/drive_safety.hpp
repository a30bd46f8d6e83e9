// The drive safety check: before a drive is played, the drive itself (the
// demand) is checked against the range held setpoints keep to, and what it
// will make the rig do, predicted through the closed loop
// (motion_prediction.hpp), against the stroke, the rate detector and the
// valve's output limit, each with a stated margin. A drive that would exceed
// them is refused, naming the limit with the least room, or (when asked)
// scaled about the operating point until it fits. So the loop's own limit
// detectors never have to trip: a target beyond the actuator's reach ends
// the iteration here, with the valve never driven past its means.
#pragma once

#include <string>
#include <vector>

#include "config/rig_config.hpp"
#include "tools/iterate/motion_prediction.hpp"

namespace rigctl {

struct DriveLimits {
  double position_min = 0.0, position_max = 0.0;  // [feedback unit] the drive (demand)
  std::string position_source;                    // e.g. "safety.setpoint_range"
  double stroke_min = 0.0, stroke_max = 0.0;      // [feedback unit] the predicted rod
  std::string stroke_source;                      // e.g. "limits.x_r less 3 %"
  double velocity_max = 0.0;                      // [unit/s] the predicted rod; infinity: no limit in the config
  std::string velocity_source;
  double effort_max = 0.0;                        // [1] of the valve's rated command, the predicted command
  std::string effort_source;
};

struct DrivePeaks {
  double min = 0.0, max = 0.0;     // [unit] the drive's extremes
  double displacement = 0.0;       // [unit] largest |drive - operating point|
  double velocity = 0.0;           // [unit/s] largest |d drive / dt| (reported, not a limit: the rod's is)
  PredictedMotion predicted;       // the rod and the valve command it will make
};

struct DriveVerdict {
  bool ok = true;
  std::string reason;  // the limit exceeded with the least room (the one that stops the drive), with the numbers
  double fit_scale = 1.0;  // the largest factor on (drive - operating point) that fits every limit (> 1: room to spare)
};

DriveLimits drive_limits(const RigConfig& config);

DrivePeaks drive_peaks(const std::vector<double>& drive, double operating_point, double period_s,
                       const PredictedMotion& predicted);

DriveVerdict check_drive(const DrivePeaks& peaks, const DriveLimits& limits, double operating_point);

// (drive - operating point) x scale + operating point.
void scale_drive(std::vector<double>& drive, double operating_point, double scale);

}  // namespace rigctl
