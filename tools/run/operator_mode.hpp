// Operator mode of `rigctl run` (issue 7): instead of the automatic sequence
// the rig powers up faulted and moves only on authenticated operator
// commands (`rigctl cmd`, docs/operator-commands.md). This builds the command
// receiver from the config's `operator:` section and the command line, and
// sends its rejections into the run's event log beside the state machine's.
#pragma once

#include <memory>
#include <string>

#include "config/rig_config.hpp"
#include "rt/comms/command_receiver.hpp"

namespace rigctl {

class EventLog;

struct OperatorModeOptions {
  bool force = false;       // --operator: safety.auto_sequence taken as false whatever the file says
  std::string key_path;     // --key: overrides operator.key_file
  std::string lcm_url;      // telemetry URL after --lcm-url: the default when operator.lcm_url is absent
  std::string setpoint_unit;  // the feedback channel's unit, for messages
};

// True when the run takes operator commands instead of the automatic sequence.
bool operator_mode(const RigConfig& config, const OperatorModeOptions& options);

// The receiver's settings. Throws ConfigError naming the missing or bad
// field (operator.key_file when there is neither it nor --key).
CommandReceiverOptions operator_receiver_options(const RigConfig& config, const OperatorModeOptions& options);

// Opens the receiver (key file checked, LCM subscribed; not started) with
// every rejection it logs also written to `events` (code
// command_rejected, source receiver). ConfigError or std::runtime_error
// naming the key file or URL.
std::unique_ptr<CommandReceiver> make_operator_receiver(const RigConfig& config, const OperatorModeOptions& options,
                                                        EventLog& events);

// "3 accepted, 1 rejected (bad_tag 1)" for the run summary.
std::string describe_counters(const RejectCounters& counters);

}  // namespace rigctl
