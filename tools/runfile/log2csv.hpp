// Converts an LCM telemetry log (written by TelemetryPublisher or lcm-logger)
// into a run file of docs/run-files.md, so a recorded run can go
// straight into `rigctl diagnose`.
#pragma once

#include <cstdint>
#include <string>

namespace rigctl {

struct Log2CsvResult {
  int64_t rows = 0;     // data rows written
  int64_t skipped = 0;  // ticks not written: a message missing, invalid or non-finite input, t not increasing
  std::string rig;      // from sample_t.rig
  int64_t dropped_records = 0;  // telemetry records the run's queue dropped (newest timing message)
};

// Reads <prefix>SAMPLE and <prefix>COMMAND from the log, joins them by tick
// and writes csv_path atomically (temp file + rename). Throws
// std::runtime_error naming the file and the reason when the log is missing,
// is not an LCM log, or holds no sample/command messages. simulator_truth
// false leaves out the simulator's truth channels (sim_*): a run file with
// only what a rig's transducers measure (the hidden-effect generator's).
Log2CsvResult log_to_csv(const std::string& lcm_log_path, const std::string& csv_path,
                         const std::string& channel_prefix = "RIGCTL_", bool simulator_truth = true);

}  // namespace rigctl
