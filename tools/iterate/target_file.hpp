// The iteration's target: one channel of a run file (`t` and the channel;
// other columns ignored, docs/run-files.md; `t` may start anywhere) or of an
// RPC III time history (.rsp, .tim, .drv: tools/iterate/rpc3_file.hpp),
// chosen by name or by its 1-based number, on the loop's period: resampled
// when the file's period differs, through an anti-aliasing low-pass below
// the lower of the two Nyquist frequencies (resample.hpp).
#pragma once

#include <string>
#include <vector>

namespace rigctl {

struct Target {
  std::vector<double> values;  // on the loop's period
  std::string channel;         // the file's name of the channel taken
  double file_period_s = 0.0;  // the file's own sample period
  double start_s = 0.0;        // the file's first time (run files; 0 for RPC III)
  double duration_s = 0.0;     // as read
};

// `channel`: a name, or a 1-based number of the file's data channels (for
// a run file, its columns after `t`). Throws RunFileError / Rpc3Error naming
// the file, line or channel, std::invalid_argument when the target is longer
// than max_length_s (nothing is truncated).
Target read_target(const std::string& path, const std::string& channel, double period_s, double max_length_s);

}  // namespace rigctl
