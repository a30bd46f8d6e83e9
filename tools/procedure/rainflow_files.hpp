// A rainflow matrix on disk, and the counting of a recorded run
// (`rigctl rainflow RUN.lcm|RUN.csv --channel NAME`; docs/procedures.md).
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include "rt/procedure/rainflow.hpp"

namespace rigctl {

// Writes the matrix's non-empty bins as CSV (`range,mean,cycles`, bin
// centres in the channel's SI unit) after `# key: value` lines naming the
// channel, the totals and the Basquin parameters. Atomic: a temporary file
// renamed over `path`, so a reader never sees half a matrix.
void write_rainflow_matrix(const std::string& path, const std::string& channel, const RainflowMatrix& m);

struct RainflowFileOptions {
  std::string run_path;     // a run file (CSV, docs/run-files.md) or a run's LCM log (.lcm)
  std::string channel;      // the column to count
  std::string matrix_path;  // optional: the matrix as CSV
  double basquin_exponent = 5.0;  // rubber and forged steel: 5-10; welded steel 3 (docs/procedures.md)
  double reference_range = 0.0;   // 0: the history's own largest range
  std::string channel_prefix = "RIGCTL_";
};

struct RainflowFileResult {
  std::size_t samples = 0;
  RainflowMatrix matrix;
  std::vector<RainflowCycle> largest;  // the largest ranges counted, largest first (at most 10)
};

// The channel's samples of a recorded run. Throws std::runtime_error naming
// the file and the channel when the file cannot be read or lacks it (the
// known columns listed).
std::vector<double> read_channel(const std::string& run_path, const std::string& channel,
                                 const std::string& channel_prefix);

RainflowFileResult count_rainflow(const RainflowFileOptions& options);
int run_rainflow_command(const RainflowFileOptions& options, std::ostream& out);

}  // namespace rigctl
