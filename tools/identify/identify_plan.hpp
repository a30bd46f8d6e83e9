// What an identification run will do, worked out from the config and the
// command line before anything moves: the controller in the loop (the
// config's, or a proportional stabiliser), the operating point, the
// excitation and its clamp, and the safety settings of the run (every
// limit trip an interlock: the excitation stops and the valve goes to null).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "config/rig_config.hpp"
#include "tools/identify/amplitude_clamp.hpp"
#include "tools/identify/excitation.hpp"

namespace rigctl {

// Command-line settings; each one set overrides the config's `identify:`.
struct IdentifySettings {
  std::optional<ExcitationKind> excitation;
  std::optional<double> band_min_hz, band_max_hz;
  std::optional<double> amplitude;
  std::optional<double> duration_s;
  std::optional<double> resolution_hz;
  std::optional<double> operating_point;
  std::optional<double> settle_s;
  // The loop's controller replaced by a proportional one of this gain
  // (PI: kp = K, ki = 0; P+V+dP: Ke = K, Kv = Kp = 0): a rig with no gains yet.
  std::optional<double> stabiliser_gain;
  // Further response channels measured after the controller's own (the drive
  // iteration's target channel, e.g. the wheel's x_w): `--response NAME`.
  std::vector<std::string> extra_responses;
};

struct IdentifyPlan {
  RigConfig config;            // as the loop runs it: controller and safety adapted
  double operating_point = 0.0;
  double amplitude_requested = 0.0;  // 0: none asked, the clamp is used
  AmplitudeClamp clamp;
  ExcitationSpec excitation;   // amplitude already clamped
  double settle_s = 0.0;
  std::vector<std::string> responses;  // the controller's feedback channels, the controlled one first, then the extra ones
};

// Throws ConfigError for a rig whose controller is not a position loop
// (pi, pvp) or an operating point outside the setpoint range.
IdentifyPlan plan_identification(RigConfig config, const IdentifySettings& settings);

// The default operating point: the middle of safety.setpoint_range
// (mid-stroke), else the profile's ramp target.
double default_operating_point(const RigConfig& config);

// The controller's gains by their config keys (config units), as the FRF
// file and the tuned config carry them.
std::map<std::string, double> controller_gains(const ControllerConfig& controller);

}  // namespace rigctl
