// The iteration itself, independent of how a drive is played and where
// the records go: first drive = the inverse applied to the target; then
// play, compare, and update d(k+1) = d(k) + alpha(f) H^-1 e(k) with e the
// target minus the response. alpha starts below one in every band and is
// halved in a band where the error grew. Every drive passes the safety
// check before it is played. Stops at the tolerance, when an iteration no
// longer lowers the error, at a drive the rig cannot play, or after
// max_iterations.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "tools/iterate/drive_inverse.hpp"
#include "tools/iterate/drive_player.hpp"
#include "tools/iterate/drive_safety.hpp"
#include "tools/iterate/match_metrics.hpp"

namespace rigctl {

enum class IterationEnd {
  kTolerance,      // the error is within the tolerance
  kNoImprovement,  // the last iteration did not lower the error
  kMaxIterations,
  kDriveLimit,     // the next drive would exceed a limit of the rig (not played)
  kRunEnded,       // a played drive ended with a trip or a stop request
};
std::string_view to_string(IterationEnd end);

struct IterationSettings {
  int max_iterations = 6;
  double tolerance_percent = 5.0;
  // alpha at the start: below one, so that a model's error on a line does
  // not overshoot (a line whose true gain is up to twice the model's still
  // converges, |1 - alpha H / H_model| < 1 for H / H_model < 2 / alpha).
  double initial_gain = 0.9;
  double gain_cut = 0.5;        // alpha x this in a band where the error grew
  bool scale_to_fit = false;    // scale a drive beyond the limits instead of refusing it
  double fade_s = 0.25;         // [s] the corrections fade in and out at the ends: the drive starts and ends at rest
  InverseSettings inverse;
};

struct IterationRecord {
  int index = 0;              // 1-based
  std::vector<double> drive;  // played
  std::vector<double> response;
  MatchMetrics match;
  DrivePeaks peaks;
  double drive_scale = 1.0;   // < 1: scaled to fit the limits
  std::string limited_by;     // then the limit it was scaled for
  std::vector<double> gain;   // alpha per gain band the drive was made with
};

struct IterationOutcome {
  std::vector<IterationRecord> iterations;
  IterationEnd end = IterationEnd::kMaxIterations;
  std::string end_detail;     // the limit, the trip, the numbers
  std::size_t best = 0;       // index into iterations of the lowest error
};

struct IterationRig {
  const RigConfig* config = nullptr;
  double operating_point = 0.0;
  double command_hold = 0.0;  // the valve command that holds the operating point
  std::function<PlayResult(const std::vector<double>& drive, int iteration)> play;
  std::function<void(const IterationRecord&)> on_iteration;  // records, progress
};

IterationOutcome iterate_drive(const std::vector<double>& target, const DriveFrf& frf, const IterationRig& rig,
                               const IterationSettings& settings);

}  // namespace rigctl
