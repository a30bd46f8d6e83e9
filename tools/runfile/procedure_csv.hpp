// A test procedure's channel (<prefix>PROCEDURE, docs/procedures.md) of an
// LCM log as CSV: one row per message (each cycle, pass and step end and
// every 0.1 s), beside the run file that log2csv writes from the samples.
// The run file keeps its contract (docs/run-files.md); the procedure's
// counts, compensation and damage have a file of their own.
#pragma once

#include <cstdint>
#include <string>

namespace rigctl {

// "<run>.procedure.csv" for "<run>.csv" (any other name: + ".procedure.csv").
std::string procedure_csv_path(const std::string& run_csv_path);

// Writes the log's procedure messages to csv_path atomically (temp file and
// rename). Returns the rows written; 0 and no file when the log has none
// (a run without a procedure). Throws std::runtime_error naming the file.
int64_t procedure_log_to_csv(const std::string& lcm_log_path, const std::string& csv_path,
                             const std::string& channel_prefix = "RIGCTL_");

}  // namespace rigctl
