// Text of an event, made off the real-time path (the publisher thread, the
// event-log thread): the loop hands over codes, channel indices and values.
#pragma once

#include <string>

#include "rt/sample.hpp"
#include "rt/telemetry_record.hpp"

namespace rigctl {

// Names the channel (with its unit) and the value; for commands the kind and,
// for a refusal, the reason; for a state change both states.
std::string event_message(const Event& ev, const ChannelLayout& layout);

// Name of input `channel`, "" when none or out of range.
std::string input_name(int channel, const ChannelLayout& layout);

}  // namespace rigctl
