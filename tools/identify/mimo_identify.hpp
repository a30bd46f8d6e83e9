// `rigctl identify` on a rig with several control channels (`channels:`,
// the two-poster's posts): every channel's demand excited at once about its
// operating point by orthogonal multisines (mimo_excitation.hpp: the drives
// uncorrelated on every line), through the same assembly, loop and safety
// machinery as `rigctl run` (every trip an interlock), and the matrix of
// closed-loop frequency responses from the demands to the channels'
// feedbacks, valve commands and the --response channels, H1 with multiple
// and partial coherence per line, written as a matrix FRF file
// (frf_matrix_file.hpp, docs/frf-files.md 2.2).
#pragma once

#include <atomic>
#include <ostream>
#include <string>
#include <vector>

#include "tools/identify/frf_matrix_file.hpp"
#include "tools/identify/identify_command.hpp"
#include "tools/identify/mimo_excitation.hpp"

namespace rigctl {

struct MimoIdentifyPlan {
  RigConfig config;                  // every channel's loop as identify runs it
  std::vector<IdentifyPlan> channels;  // per channel: operating point, amplitude and its clamp
  std::vector<std::string> drives;     // x_ref_1, x_ref_2, ...
  std::vector<std::string> responses;  // feedbacks, outputs, then the extra ones
  double band_min_hz = 0.0, band_max_hz = 0.0;
  std::size_t period_ticks = 0;      // one multisine period: lines every 1 / (period_ticks dt)
  std::vector<std::size_t> lines;    // every bin of the period in the band
  std::size_t realisations = 0;      // max(2 x drives, duration / (2 periods)): averages beyond the drives' number
  std::size_t settle_periods = 1;
  double settle_s = 0.0;
};

// Throws ConfigError as plan_identification does, per channel.
MimoIdentifyPlan plan_mimo_identification(const RigConfig& config, const IdentifySettings& settings);

struct MimoIdentifyResult {
  bool aborted = false;
  std::string abort_reason;
  MimoIdentifyPlan plan;
  FrfMatrixData matrix;
  RunReport run;
};

MimoIdentifyResult run_mimo_identify(const IdentifyOptions& options, const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl
