// `rigctl make-series`: a simulated durability series to test rig health
// with (docs/rig-health.md 6). One rig (one seed's drawn world: plant,
// controller and demand within their tolerances, as make-run draws them)
// runs block after block of the diagnosis excitation, each block its own run
// file with its start time, while chosen parameters drift: the seal wears
// (the leakage conductance grows), the rod's friction grows. The sensor
// noise differs per block. series.json records every block's true values.
#pragma once

#include <ostream>
#include <string>

#include "config/rig_kind.hpp"

namespace rigctl::health {

struct SeriesOptions {
  RigKind rig = RigKind::kQuarterCar;
  std::string config_path;  // default: config/<rig>.yaml
  std::string case_name;    // default: the rig's diagnosis excitation
  std::string out_dir;
  int blocks = 20;
  double block_spacing_h = 10.0;  // hours between block starts (200 h over 20 blocks)
  std::string start_utc = "2026-01-05T08:00:00Z";
  int seed = 1;
  double tolerance = 0.05;     // the rig's draw, as make-run's
  double leakage_growth = 0.0;   // the leakage conductance at the last block over the first, minus one (0.5: +50 %)
  double friction_growth = 0.0;  // the rod's viscous friction likewise
  double duration_s = 0.0;       // per block; 0: the excitation's length
};

// Writes block-NNN.csv and series.json into out_dir; throws naming what failed.
void make_series(const SeriesOptions& options, std::ostream& progress);

}  // namespace rigctl::health
