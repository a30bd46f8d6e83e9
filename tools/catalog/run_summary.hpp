// A run's catalog entry read from its record: an LCM log of `rigctl run`
// (with its .events file when present) or a CSV run file
// (docs/run-files.md). What only the running program knows (the config, the
// profile) is left empty for the caller to fill.
#pragma once

#include <cstdint>
#include <string>

#include "tools/catalog/run_entry.hpp"

namespace rigctl::catalog {

// The record's kind by its contents: an LCM log starts with LCM's sync word.
bool is_lcm_log(const std::string& path);

// Channel statistics of every sample input, the setpoint and the outputs;
// rig kind; start (first sample's wall time); duration; samples; how it
// ended from the last state message (a log that stops without a final
// stopped/faulted state: killed); trips (state messages with a trip's
// event). Throws std::runtime_error naming the file.
RunEntry summarise_lcm_log(const std::string& path, const std::string& channel_prefix = "RIGCTL_");

// Statistics of every column but t; rig from `# rig:`, start from
// `# start_utc:` when present (else the file's modification time); end
// reason unknown. Streams the file: any length.
RunEntry summarise_run_file(const std::string& path);

// Either of the above by the file's contents, with size, SHA-256 and the
// absolute path filled.
RunEntry summarise_record(const std::string& path, const std::string& channel_prefix = "RIGCTL_");

// Lower-case hex SHA-256 of a file's bytes; throws naming the file.
std::string file_sha256(const std::string& path);

// ISO 8601 UTC with microseconds, e.g. 2026-11-27T21:02:03.250000Z.
std::string utc_text(int64_t utime_us);
// Seconds since the epoch of such a text (or a date, or a date and time
// without fraction); throws std::invalid_argument naming it.
double utc_seconds(const std::string& text);

// Whether an event code (as the logs write it) is a trip: a detector or the
// driver stopped the rig. One list, in run_summary.cpp.
bool is_trip_event(const std::string& code);

}  // namespace rigctl::catalog
