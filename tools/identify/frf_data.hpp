// A measured frequency response, as `rigctl identify` writes it and
// `rigctl tune` (and the drive iteration) read it: docs/frf-files.md is the
// contract. SI units; frequencies in Hz.
#pragma once

#include <complex>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace rigctl {

struct FrfChannel {
  std::string name;  // run-file name, e.g. "x_r"
  std::string unit;  // SI unit, e.g. "m"
};

// One response channel's frequency response on the file's frequencies.
struct FrfCurve {
  std::string response;                     // the output channel's name
  std::vector<std::complex<double>> value;  // [response unit / input unit]
  std::vector<double> coherence;            // 0..1; empty for a model
};

struct OperatingPoint {
  double demand = 0.0;          // the held demand [feedback unit]
  double response_mean = 0.0;   // the feedback's mean over the analysed records
  double command_mean = 0.0;    // the valve command's mean (what holds the rig there)
};

struct ExcitationRecord {
  std::string kind;              // multisine, chirp, pink_noise
  double band_min_hz = 0.0, band_max_hz = 0.0;
  double amplitude = 0.0;        // the peak used [feedback unit]
  double amplitude_requested = 0.0;  // what was asked for (0: none, the clamp was used)
  double amplitude_clamp = 0.0;  // the rig's limit on it
  std::string clamp_reason;      // the limit that binds
  double duration_s = 0.0;       // excitation time in the run
  double start_s = 0.0;          // run-file time of its first tick
  double end_s = 0.0;            // and the end of its last tick
  double logged_peak = 0.0;      // max |demand - operating point| over the excitation, from the log
};

struct EstimationRecord {
  std::string method = "welch";
  std::string window;      // rectangular or hann
  double segment_s = 0.0;  // one segment: resolution 1 / segment_s
  double overlap = 0.0;    // fraction of a segment
  int averages = 0;
  double analysed_from_s = 0.0, analysed_to_s = 0.0;  // run-file times of the analysed records
};

struct FrfData {
  std::string rig;          // quarter_car, pneumatic_rotary
  std::string config;       // the config file the loop ran
  std::string run_log;      // the identification run's LCM log
  double sample_rate_hz = 0.0;
  FrfChannel demand;        // the loop's demand (the instrument)
  FrfChannel command;       // the valve command
  std::vector<FrfChannel> responses;  // the controller's feedback channels, the controlled one first
  OperatingPoint operating_point;
  std::string controller_type;               // the controller in the loop during the measurement
  std::map<std::string, double> controller_gains;  // its gains, by their config keys
  ExcitationRecord excitation;
  EstimationRecord estimation;
  std::vector<double> frequency_hz;
  std::vector<FrfCurve> closed_loop;  // demand -> response, H1 = S_ry / S_rr, coherence demand-response
  std::vector<FrfCurve> plant;        // command -> response, S_ry / S_ru; coherence min(demand-response, demand-command)
  std::vector<double> command_coherence;  // demand -> command
  // Incoherent part of each response's and the command's spectrum,
  // (1 - coherence with the demand) x auto-spectrum [unit^2 / Hz].
  std::map<std::string, std::vector<double>> noise_floor;
  std::map<std::string, std::vector<double>> response_psd;  // auto-spectra, same units
  // Multisine only: each response's mean power on the non-excited bins
  // within three of a line over its power on the line. The rig's nonlinearity
  // (friction, hysteresis, the valve's edges) puts power there that noise
  // alone would not (the noise floor is the same on both): a line where
  // this ratio is not small measured a nonlinear response, however coherent.
  std::map<std::string, std::vector<double>> distortion;
  std::vector<FrfCurve> model;  // optional: the simulated plant's linearisation, command -> response

  const FrfCurve& plant_of(const std::string& response) const;
  const FrfCurve* model_of(const std::string& response) const;
};

}  // namespace rigctl
