// Converts a run's LCM log into an MCAP file (foxglove/mcap) with the same
// channels, JSON schemas and JSON messages as the live Foxglove server, so
// Foxglove, Lichtblick and PlotJuggler open a recorded run directly and seek
// in it fast (docs/foxglove.md).
#pragma once

#include <cstdint>
#include <map>
#include <string>

namespace rigctl {

struct Log2McapResult {
  int64_t messages = 0;                        // written to the MCAP
  std::map<std::string, int64_t> per_channel;  // by LCM channel name
  int64_t skipped = 0;     // events on other channels, or that did not decode as their channel's type
  int64_t chunks = 0;
  // Non-empty when the log ends in a partial event (a run that was killed, a
  // copy cut short): the MCAP holds what was readable before it.
  std::string warning;
};

// Throws std::runtime_error naming the file when the log is missing or not an
// LCM log, or the MCAP cannot be written. The MCAP is written under a
// temporary name and renamed into place.
Log2McapResult log_to_mcap(const std::string& lcm_log_path, const std::string& mcap_path,
                           const std::string& channel_prefix = "RIGCTL_");

}  // namespace rigctl
