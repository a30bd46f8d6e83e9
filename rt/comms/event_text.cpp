#include "rt/comms/event_text.hpp"

#include <cstdio>

#include "rt/safety/limit_action.hpp"
#include "rt/safety/operator_command.hpp"
#include "rt/safety/rig_state_machine.hpp"

namespace rigctl {

namespace {

std::string format_g(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

std::string with_unit(double v, const std::string& unit) { return format_g(v) + (unit.empty() ? "" : " " + unit); }

std::string command_name(int kind) {
  return kind >= 0 && static_cast<std::size_t>(kind) < kOperatorCommandKindCount
             ? std::string(to_string(static_cast<OperatorCommandKind>(kind)))
             : "command " + std::to_string(kind);
}

std::string state_name(int s) {
  return s >= 0 && static_cast<std::size_t>(s) < kSafetyStateCount ? std::string(to_string(static_cast<SafetyState>(s)))
                                                                   : "state " + std::to_string(s);
}

std::string action_suffix(const Event& ev) {
  if (ev.action == 0) return "";
  return " (action " + std::string(to_string(static_cast<LimitAction>(ev.action))) + ")";
}

}  // namespace

std::string input_name(int channel, const ChannelLayout& layout) {
  if (channel >= 0 && static_cast<std::size_t>(channel) < layout.inputs.size()) return layout.inputs[channel].name;
  if (channel >= 0) return "input " + std::to_string(channel);
  return "";
}

std::string event_message(const Event& ev, const ChannelLayout& layout) {
  const std::string channel = input_name(ev.channel, layout);
  const std::string unit = ev.channel >= 0 && static_cast<std::size_t>(ev.channel) < layout.inputs.size()
                               ? layout.inputs[ev.channel].unit
                               : "";
  const std::string value = with_unit(ev.value, unit);
  switch (ev.code) {
    case EventCode::kNone: return "";
    case EventCode::kRunStarted: return "run started";
    case EventCode::kProfileFinished: return "profile finished";
    case EventCode::kStopRequested: return "stop requested";
    // The limits themselves are not in the record: name channel and value.
    case EventCode::kLimitTripped: return channel + " = " + value + " outside its limits" + action_suffix(ev);
    case EventCode::kInputInvalid: return channel + " invalid (value " + value + ")" + action_suffix(ev);
    case EventCode::kDriverReadFailed:
      return channel.empty() ? "driver read failed" : "driver read failed on " + channel;
    case EventCode::kQueueOverflow: return "telemetry queue dropped " + format_g(ev.value) + " records";
    case EventCode::kStateChanged:
      return state_name(static_cast<int>(ev.value)) + " -> " + state_name(ev.detail);
    case EventCode::kCommandAccepted:
      return command_name(ev.detail) +
             (ev.detail == static_cast<uint8_t>(OperatorCommandKind::kSetpoint) ? " " + format_g(ev.value) : "") +
             " accepted";
    case EventCode::kCommandRejected:
      return command_name(ev.channel) + " refused: " +
             std::string(ev.detail < kRejectionCount ? to_string(static_cast<Rejection>(ev.detail)) : "unknown reason");
    case EventCode::kRateLimit:
      return channel + " rate " + with_unit(ev.value, unit + "/s") + " over its limit" + action_suffix(ev);
    case EventCode::kTrackingError:
      return channel + " tracking error " + value + " over its limit" + action_suffix(ev);
    case EventCode::kValveSaturated: {
      const std::string out = ev.channel >= 0 && static_cast<std::size_t>(ev.channel) < layout.outputs.size()
                                  ? layout.outputs[ev.channel].name
                                  : "output " + std::to_string(ev.channel);
      return out + " saturated at " + format_g(ev.value) + action_suffix(ev);
    }
    case EventCode::kSampleStale: return "sample time stamp " + format_g(ev.value) + " s old" + action_suffix(ev);
    case EventCode::kOverruns: return format_g(ev.value) + " loop overruns in the window" + action_suffix(ev);
    case EventCode::kOpenCircuit: return channel + " = " + value + " at its rail: open circuit?" + action_suffix(ev);
    case EventCode::kSensorStuck:
      return channel + " stuck at " + value + " while the valve was commanded" + action_suffix(ev);
    case EventCode::kStopTimeout: return "controlled stop did not settle in time: valve made safe";
    case EventCode::kLogWriteFailed: return "log write failed (value = errno " + format_g(ev.value) + ")";
    case EventCode::kFaultReset: return "faults reset";
    case EventCode::kPeakValleyChange:
      return channel + " peaks/valleys changed by " + format_g(100.0 * ev.value) + " % of the reference range" +
             action_suffix(ev);
    case EventCode::kCompensationLimit:
      return "compensation needed a factor " + format_g(ev.value) + ", beyond its limit: step stopped" + action_suffix(ev);
    case EventCode::kBlockEndStop:
      return "block ended after " + format_g(ev.value) + " test cycles: stopping as asked";
  }
  return "unknown event";
}

}  // namespace rigctl
