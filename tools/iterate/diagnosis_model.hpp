// The model a diagnosis extended (`rigctl diagnose --json`, docs/run-files.md
// 2.3), as a rig config: the config's plant with the diagnosis's
// `final_parameters` (the baseline's calibrated values and every kept
// effect's, fitted jointly) written into it, so that what the diagnosis
// learned about the rig shapes the drive iteration's inverse.
#pragma once

#include <string>
#include <vector>

#include "config/rig_config.hpp"

namespace rigctl {

struct DiagnosisModel {
  RigConfig config;
  std::vector<std::string> applied;  // parameter names written into the plant
  std::vector<std::string> ignored;  // names with no counterpart in the plant's linear model (sensor effects)
};

// Throws std::invalid_argument naming the file and the bad key, or a rig
// other than the config's; only the quarter car's parameters are mapped.
DiagnosisModel diagnosis_model(const RigConfig& nominal, const std::string& json_path);

inline RigConfig diagnosis_model_config(const RigConfig& nominal, const std::string& json_path) {
  return diagnosis_model(nominal, json_path).config;
}

}  // namespace rigctl
