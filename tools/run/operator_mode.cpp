#include "tools/run/operator_mode.hpp"

#include <cmath>
#include <cstdint>
#include <limits>

#include "config/config_reader.hpp"
#include "rt/comms/event_log.hpp"

namespace rigctl {

bool operator_mode(const RigConfig& config, const OperatorModeOptions& options) {
  return options.force || !config.safety.auto_sequence;
}

CommandReceiverOptions operator_receiver_options(const RigConfig& config, const OperatorModeOptions& options) {
  const OperatorConfig& op = config.operator_commands;
  CommandReceiverOptions r;
  r.key_path = options.key_path.empty() ? op.key_file : options.key_path;
  if (r.key_path.empty()) {
    throw ConfigError(config.file + ": operator.key_file: operator mode (" +
                      (options.force ? std::string("--operator") : std::string("safety.auto_sequence: false")) +
                      ") needs the rig's operator key: add an `operator:` section with key_file, or give --key");
  }
  r.lcm_url = op.lcm_url.empty() ? options.lcm_url : op.lcm_url;
  r.channel = op.channel.empty() ? default_command_channel(config.telemetry.channel_prefix) : op.channel;
  r.policy.max_age_us = std::llround((op.present ? op.staleness_s : 2.0) * 1e6);
  // The verifier refuses setpoints outside the same range the state machine
  // enforces; without a configured range it refuses every setpoint (NaN).
  const bool range = std::isfinite(config.safety.setpoint_min) && std::isfinite(config.safety.setpoint_max);
  r.policy.setpoint_min = range ? config.safety.setpoint_min : std::numeric_limits<double>::quiet_NaN();
  r.policy.setpoint_max = range ? config.safety.setpoint_max : std::numeric_limits<double>::quiet_NaN();
  r.policy.setpoint_unit = options.setpoint_unit;
  return r;
}

std::unique_ptr<CommandReceiver> make_operator_receiver(const RigConfig& config, const OperatorModeOptions& options,
                                                        EventLog& events) {
  CommandReceiverOptions r = operator_receiver_options(config, options);
  // Receiver thread to the event log's mutex-guarded note queue (never the
  // loop's lock-free one, which has a single producer: the loop).
  r.on_rejection_logged = [&events](const RejectionNote& n) {
    events.push_note(n.utime, "command_rejected", "receiver", n.sequence, n.reason + ": " + n.text);
  };
  return std::make_unique<CommandReceiver>(r);
}

std::string describe_counters(const RejectCounters& counters) {
  std::string text = std::to_string(counters.accepted()) + " accepted, " + std::to_string(counters.rejected()) + " rejected";
  std::string reasons;
  for (std::size_t i = 1; i < kRejectReasonCount; ++i) {
    const auto reason = static_cast<RejectReason>(i);
    if (counters.get(reason) == 0) continue;
    reasons += (reasons.empty() ? "" : ", ") + std::string(to_string(reason)) + " " + std::to_string(counters.get(reason));
  }
  return reasons.empty() ? text : text + " (" + reasons + ")";
}

}  // namespace rigctl
