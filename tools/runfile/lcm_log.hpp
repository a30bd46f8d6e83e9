// Reading a run's LCM log (lcm-logger format), shared by log2csv and log2mcap.
#pragma once

#include <string>

namespace rigctl {

// Throws std::runtime_error "TOOL: 'PATH': reason" when the file is missing,
// not a regular file, empty or does not start with an LCM event's sync word
// (lcm_eventlog would skip garbage and report only "no events").
void check_is_lcm_log(const std::string& path, const std::string& tool);

}  // namespace rigctl
