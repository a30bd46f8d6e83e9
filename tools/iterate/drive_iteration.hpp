// The iteration itself, independent of how a drive is played and where
// the records go. The first drive is the inverse applied to the target, at
// a reduced level (the low-level first pass labs play); then play, compare,
// and update d(k+1) = d(k) + w alpha(f) H^-1 e(k) with e the target minus
// the response and w the correction's weight along the record (0 at the
// target's holds at home, 1 over its test part: test_window.hpp). alpha per
// band is set from what the rig did against the model after each drive
// (gain_adaptation.hpp) and halved in a band where the error grew. Every
// drive passes the safety check on its predicted motion before it is played
// (drive_safety.hpp); the prediction is compared with what the rig did after
// each drive and corrected by the ratio. Stops at the tolerance, when an
// iteration no longer lowers the error, at a drive the rig cannot play or
// that grew too much, or after max_iterations.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tools/iterate/drive_inverse.hpp"
#include "tools/iterate/drive_player.hpp"
#include "tools/iterate/drive_safety.hpp"
#include "tools/iterate/match_metrics.hpp"
#include "tools/iterate/test_window.hpp"

namespace rigctl {

enum class IterationEnd {
  kTolerance,      // the error is within the tolerance
  kNoImprovement,  // the last iteration did not lower the error
  kMaxIterations,
  kDriveLimit,     // the next drive would exceed a limit of the rig (not played)
  kDriveGrowth,    // the next drive grew more than allowed over the last one (not played)
  kRunEnded,       // a played drive ended with a trip or a stop request
};
std::string_view to_string(IterationEnd end);

struct IterationSettings {
  int max_iterations = 6;
  double tolerance_percent = 5.0;
  // alpha before anything is measured: below one, so that a line whose
  // true gain is up to twice the model's still converges.
  double initial_gain = 0.9;
  double gain_cut = 0.5;        // alpha x this in a band where the error grew
  bool scale_to_fit = false;    // scale a drive beyond the limits instead of refusing it
  // The first drive's content in the band, as a share of the inverse's: the
  // usual low-level first pass (the model's error is met at half the level).
  double first_level = 0.5;
  // A drive whose content in the band grows more than this over the last
  // played one is refused: an update that large means the model or the
  // measurement went wrong (the first pass's 0.5 to 1 is a growth of 2).
  double max_growth = 3.0;
  std::optional<std::pair<double, double>> window_s;  // [s] the test part; default: found (test_window.hpp)
  double lead_s = 1.0;          // [s] full correction from this long before the test part to after it
  double fade_s = 0.25;         // [s] the shortest fade of the correction at the record's ends
  InverseSettings inverse;
};

struct IterationRecord {
  int index = 0;              // 1-based
  std::vector<double> drive;  // played
  std::vector<double> response;
  MatchMetrics match;
  DrivePeaks peaks;           // the drive's, and its predicted motion (corrected by the last measured ratio)
  PredictionCorrection correction;  // the ratio the prediction was corrected by
  MeasuredMotion measured;    // what the rig did
  double level = 1.0;         // the first drive's level
  double growth = 0.0;        // the drive's content in the band over the last one's (0: the first)
  double drive_scale = 1.0;   // < 1: scaled to fit the limits
  std::string limited_by;     // then the limit it was scaled for
  std::vector<double> gain;   // alpha per gain band the drive was made with
};

struct IterationOutcome {
  std::vector<IterationRecord> iterations;
  IterationEnd end = IterationEnd::kMaxIterations;
  std::string end_detail;     // the limit, the trip, the numbers
  std::size_t best = 0;       // index into iterations of the lowest error
  TestWindow window;          // where the error was judged
  std::vector<std::pair<double, double>> gated_bands_hz;  // bands the adaptation closed
};

struct IterationRig {
  const RigConfig* config = nullptr;
  double operating_point = 0.0;
  double command_hold = 0.0;  // the valve command that holds the rig at rest
  LoopPaths paths;            // drive -> rod and -> command, for the prediction
  DriveFrf channel;           // drive -> the target channel (the inverse's FRF)
  std::function<PlayResult(const std::vector<double>& drive, int iteration)> play;
  std::function<void(const IterationRecord&)> on_iteration;  // records, progress
};

// The part of the target the error is judged on: --window, or found.
TestWindow test_window_of(const std::vector<double>& target, double dt, const IterationSettings& settings);

IterationOutcome iterate_drive(const std::vector<double>& target, const IterationRig& rig,
                               const IterationSettings& settings);

}  // namespace rigctl
