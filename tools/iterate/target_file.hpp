// The iteration's target: one channel of a run file (`t` and the channel;
// other columns ignored, docs/run-files.md) or of an RPC III time history
// (.rsp, .tim, .drv: tools/iterate/rpc3_file.hpp), on the loop's period
// (resampled linearly when the file's period differs).
#pragma once

#include <string>
#include <vector>

namespace rigctl {

// Throws RunFileError / Rpc3Error naming the file, line or channel.
std::vector<double> read_target(const std::string& path, const std::string& channel, double period_s);

// x sampled every `from_s` resampled to every `to_s` over the same span.
std::vector<double> resample(const std::vector<double>& x, double from_s, double to_s);

}  // namespace rigctl
