// The rig's frequency response from the drive (the loop's demand) to the
// target channel, where the iteration's inverse comes from: measured by
// `rigctl identify` (its closed-loop curve of that channel) or computed
// from a model of the plant (plant/quarter_car linearised at the operating
// point, tools/identify/plant_linearisation.hpp) closed with the config's
// controller in its discrete form (tools/tune/loop_response.hpp).
#pragma once

#include <complex>
#include <string>
#include <vector>

#include "config/rig_config.hpp"
#include "tools/identify/frf_data.hpp"

namespace rigctl {

struct DriveFrf {
  std::string source;                        // "frf FILE", "nominal model", "diagnosis model FILE"
  std::vector<double> frequency_hz;          // ascending
  std::vector<std::complex<double>> value;   // [target unit / demand unit]
  std::vector<double> coherence;             // 0..1 per line; all 1 for a model

  // Linear interpolation between lines (real and imaginary parts); below
  // the first line the first line's value, above the last the last's.
  std::complex<double> at(double f_hz) const;
  double coherence_at(double f_hz) const;
};

// The closed-loop curve of `channel` in an FRF file, its coherence lowered
// by the distortion beside each line (a nonlinear response is coherent but
// not linear). Throws std::invalid_argument naming the channels the file has.
DriveFrf drive_frf_from_file(const FrfData& frf, const std::string& channel, const std::string& name);

// demand -> channel of the config's plant (its parameters as given: the
// nominal ones, or those a diagnosis found) under the config's controller,
// linearised at `operating_point`. Throws std::invalid_argument for a rig
// or controller without a model (only the quarter car's PI loop has one).
DriveFrf drive_frf_from_model(const RigConfig& config, const std::string& channel, double operating_point,
                              const std::vector<double>& frequency_hz, const std::string& source);

// Where the rig's own limits are met: the drive's paths through the closed
// loop to the controlled position (the rod: stroke and rate detector) and
// to the valve command (the output limit; its deviation from the hold). The
// same FRF source as the inverse's: a model's T = L / (1 + L) and T / G, or
// a measured file's closed-loop curve of the feedback and that over its
// plant curve (demand -> command = T / G).
struct LoopPaths {
  DriveFrf feedback;  // drive -> controller.feedback
  DriveFrf command;   // drive -> controller.output
};
LoopPaths loop_paths_from_model(const RigConfig& config, double operating_point, const std::vector<double>& frequency_hz,
                                const std::string& source);
// Throws std::invalid_argument when the file lacks the feedback's curves.
LoopPaths loop_paths_from_file(const FrfData& frf, const std::string& feedback, const std::string& name);

// The model's frequencies: every `step_hz` from step_hz to high_hz.
std::vector<double> model_frequencies(double step_hz, double high_hz);

}  // namespace rigctl
