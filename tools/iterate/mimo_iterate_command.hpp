// `rigctl iterate` on a rig with several control channels (the two-poster):
// one target channel per drive (or more, least squares), e.g.
//   rigctl iterate config/half_car_two_poster.yaml --frf FRF.json \
//     --target road.csv --channel a_s1,a_s2 --out DIR --fast
// The MIMO inverse (mimo_inverse.hpp) of the measured FRF matrix's rows of
// those channels (a matrix FRF file from `rigctl identify` with --response
// for each), every drive vector checked per actuator before it is played
// (mimo_drive_safety.hpp), played on the rig (mimo_drive_player.hpp), and
// the update d += H^+ G e with the gain halved per band and channel where
// that channel's error grew (mimo_iteration.hpp). Per iteration the error
// of every channel is reported and the drives and responses written
// (docs/drive-iteration.md 9).
#pragma once

#include <atomic>
#include <ostream>
#include <string>
#include <vector>

#include "tools/iterate/iterate_command.hpp"
#include "tools/iterate/mimo_iteration.hpp"

namespace rigctl {

struct MimoIterateResult {
  MimoIterationResult iteration;
  std::vector<std::string> channels;
  std::string summary_path;
};

// "a,b" -> {"a", "b"}; empty parts are refused (std::invalid_argument naming the option).
std::vector<std::string> split_channel_list(const std::string& text, const std::string& option);

// options.channel (and target_channel): comma-separated lists. Throws as run_iterate.
MimoIterateResult run_mimo_iterate(const IterateOptions& options, const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl
