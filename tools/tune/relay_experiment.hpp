// The relay experiment of Astrom and Hagglund on the rig, through the same
// assembly, loop and safety machinery as every run: the config's lead-in to
// the operating point, a proportional hold there, then the relay
// (tools/tune/relay_controller.hpp). From the limit cycle in the log: the
// ultimate period Tu (between relay switchings) and, by the describing
// function of a relay with hysteresis, the ultimate gain
//   Ku = 4 d / (pi sqrt(a^2 - eps^2)),
// d the relay output, a the oscillation's amplitude, eps the hysteresis.
// Ziegler and Nichols' rules turn them into gains.
#pragma once

#include <atomic>
#include <ostream>
#include <string>

#include "config/rig_config.hpp"
#include "tools/tune/loop_gains.hpp"
#include "tools/tune/tune_command.hpp"

namespace rigctl {

struct RelayResult {
  bool aborted = false;
  std::string abort_reason;
  double ultimate_gain = 0.0;      // Ku [command unit / feedback unit]
  double ultimate_period_s = 0.0;  // Tu
  double oscillation_amplitude = 0.0;  // a
  double relay_amplitude = 0.0;    // d, as the relay drove it (after any halving)
  double hysteresis = 0.0;         // eps
  double hold_command = 0.0;
  int cycles = 0;                  // whole cycles analysed
  std::string log_path;
  LoopGains gains;                 // Ziegler-Nichols
};

// Ziegler-Nichols from (Ku, Tu): PI kp = 0.45 Ku, Ti = Tu / 1.2; P+V+dP the
// P and D parts of their PID, Ke = 0.6 Ku, Kv = Ke Tu / 8, no pressure term.
LoopGains ziegler_nichols(LoopGains base, double ku, double tu);

// stabiliser_gain: the hold phase's P gain (<= 0: the config's proportional gain).
RelayResult run_relay_experiment(const RigConfig& config, const TuneOptions& options, double stabiliser_gain,
                                 const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl
