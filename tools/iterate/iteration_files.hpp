// What `rigctl iterate` leaves in its output folder (docs/drive-iteration.md):
// per iteration the drive and the recorded response as run files
// (`iter_NN_drive.csv`, `iter_NN_response.csv`) and as RPC III files
// (`iter_NN_drive.drv`, `iter_NN_response.rsp`), and `summary.json` with
// every iteration's numbers and why the iteration ended.
#pragma once

#include <string>
#include <vector>

#include "tools/iterate/drive_iteration.hpp"
#include "tools/iterate/drive_safety.hpp"

namespace rigctl {

struct IterationSummary {
  std::string config, target, channel, frf_source, rig;
  std::string target_channel;     // the file's channel taken
  double target_period_s = 0.0;   // the file's own period (resampled to the loop's when it differs)
  double target_start_s = 0.0;    // the file's first time
  double first_level = 1.0, max_growth = 0.0;
  double period_s = 0.0;          // the loop's (the window's times)
  double operating_point = 0.0;
  double band_min_hz = 0.0, band_max_hz = 0.0;
  double tolerance_percent = 0.0;
  std::size_t lines_gated = 0;
  DriveLimits limits;
};

// DIR/iter_NN_<kind>.csv
std::string iteration_file(const std::string& dir, int index, const std::string& kind);

// t, the drive (named as the rig's setpoint, e.g. x_ref); t, the channel and the target.
void write_drive_file(const std::string& path, const std::string& setpoint, const std::vector<double>& drive,
                      double period_s, const std::string& rig);
void write_response_file(const std::string& path, const std::string& channel, const std::vector<double>& response,
                         const std::vector<double>& target, double period_s, const std::string& rig);

// The same as RPC III time histories, what road-simulator tools exchange:
// `iter_NN_drive.drv` (the drive) and `iter_NN_response.rsp` (the channel and the target).
void write_iteration_rpc3(const std::string& dir, int index, const std::string& setpoint, const std::string& channel,
                          const std::string& unit, const IterationRecord& record, const std::vector<double>& target,
                          double period_s);

std::string summary_json(const IterationSummary& summary, const IterationOutcome& outcome);
void write_text_file(const std::string& path, const std::string& text);

}  // namespace rigctl
