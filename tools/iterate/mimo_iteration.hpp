// Drive iteration with several drives and responses (the two-poster rig):
// the first drive is H^+ of the target at a reduced level, then every
// iteration plays the drives, measures the responses and adds H^+ G e, the
// gain G per gain band and response channel halved where that channel's
// error in that band grew. The player is a callback, so the same loop runs
// a simulated rig in a test, the real run path, or a model.
//
// The error of a channel is the relative RMS of (target - response) over
// the target, both band-limited to the inverse's band: what the
// iteration can change.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "tools/iterate/mimo_inverse.hpp"

namespace rigctl {

struct MimoIterationSettings {
  int max_iterations = 6;
  double tolerance = 0.05;   // relative RMS on every response
  double first_level = 1.0;  // the first drive's fraction of H^+ target
  double period_s = 0.0025;
};

// Plays one drive per drive channel and returns one response record per
// response channel, each of the drives' length.
using PlayDrives = std::function<Records(const Records& drives)>;

struct MimoIterationResult {
  std::vector<std::vector<double>> error;  // per played iteration, per response channel
  Records drives;                          // the last played drives
  Records responses;                       // and what they gave
  bool converged = false;
  std::string stopped;                     // not empty: a drive was refused or its run did not complete, and why
};

// What a command adds around the loop (all optional): a safety check of
// each drive before it is played (returns "" to play it, else the refusal),
// and each played iteration's records (1-based index) as they come.
struct MimoIterationHooks {
  std::function<std::string(const Records& drives, int iteration)> admit;
  std::function<void(int iteration, const Records& drives, const Records& responses, const std::vector<double>& error)> on_iteration;
};

// `play` returns no records when the run did not complete (its own report
// says why); the iteration then stops with `stopped` set, as at a refusal.
MimoIterationResult iterate_mimo(const MimoDriveInverse& inverse, const Records& targets, const PlayDrives& play,
                                 const MimoIterationSettings& settings, const MimoIterationHooks& hooks = {});

// Relative RMS of target - response in [low_hz, high_hz].
double band_relative_rms(const std::vector<double>& target, const std::vector<double>& response, double period_s,
                         double low_hz, double high_hz);

// The FRF as a one-channel tool sees it: each response from its own drive
// only (the off-diagonal entries zero). Square FRFs only.
MimoFrf diagonal_only(const MimoFrf& frf);

}  // namespace rigctl
