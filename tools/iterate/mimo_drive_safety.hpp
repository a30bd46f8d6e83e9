// The drive safety check of a multi-channel rig, per actuator: before the
// drives are played, each actuator's own demand against its position range,
// and its rod and valve command, predicted from every drive through the
// measured FRF matrix's rows of that actuator's feedback and output (each
// post of a two-poster rig moves under both drives), against its stroke,
// its rate detector and its output limit: the one-channel check
// (drive_safety.hpp) on each actuator's predicted motion. A refusal names
// the actuator and the limit.
#pragma once

#include <string>
#include <vector>

#include "config/rig_config.hpp"
#include "tools/identify/frf_matrix_file.hpp"
#include "tools/iterate/drive_safety.hpp"

namespace rigctl {

struct ActuatorCheck {
  std::string actuator;  // e.g. "actuator 2 (x_ref_2 -> z_r2, u_2)"
  DrivePeaks peaks;      // its drive and its predicted rod and command
  DriveVerdict verdict;
};

// deviations: one record per drive, about the operating points of `frf`.
// The prediction's rows: each channel's controller.feedback and .output,
// which the matrix file holds (rigctl identify measures them first).
std::vector<ActuatorCheck> check_actuators(const RigConfig& config, const FrfMatrixData& frf,
                                           const std::vector<std::vector<double>>& deviations);

// The first refusal as text ("" when every actuator may play its drive).
std::string refusal(const std::vector<ActuatorCheck>& checks);

}  // namespace rigctl
