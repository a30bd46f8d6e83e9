// `rigctl tune CONFIG --frf FRF.json`: gains for the rig's controller from a
// measured FRF (tools/tune/loop_design.hpp) or, with --method relay, from a
// relay experiment (tools/tune/relay_experiment.hpp); the predicted margins
// and standard step; optionally the config with the gains (--out) and the
// design as JSON (--json).
#pragma once

#include <array>
#include <atomic>
#include <optional>
#include <ostream>
#include <string>

#include "config/kind_names.hpp"
#include "tools/tune/feedforward.hpp"
#include "tools/tune/loop_design.hpp"
#include "tools/tune/step_prediction.hpp"

namespace rigctl {

enum class TuneMethod : uint8_t {
  kFrf,    // loop shaping on the measured FRF
  kRelay,  // Astrom-Hagglund relay experiment, Ziegler-Nichols rules
};

constexpr std::string_view to_string(TuneMethod m) {
  switch (m) {
    case TuneMethod::kFrf: return "frf";
    case TuneMethod::kRelay: return "relay";
  }
  return "unknown";
}

template <>
struct KindNames<TuneMethod> {
  static constexpr std::string_view noun = "tuning method";
  static constexpr std::array known{TuneMethod::kFrf, TuneMethod::kRelay};
};

struct RelayOptions {
  double amplitude = 0.0;   // relay output about the hold command [command unit]; 0: the config's identify default
  double hysteresis = 0.0;  // [feedback unit]; 0: 3 x the feedback sensor's noise
  double duration_s = 12.0; // relay time
  std::string log_path;
  bool fast = false;
  bool realtime = true;
};

struct TuneOptions {
  std::string config_path;
  std::string case_name;
  std::string frf_path;
  std::string out_path;   // tuned config (YAML)
  std::string json_path;  // design and predictions
  std::string plot_path;  // Bode plot of the tuned loop (PNG)
  std::string evaluate_path;  // a run file of the config's standard step: its metrics, no design
  TuneMethod method = TuneMethod::kFrf;
  DesignTarget target;
  bool feedforward = true;  // PI: the demand's velocity feedforward from the FRF (--no-feedforward: PI alone)
  RelayOptions relay;
};

struct TuneResult {
  LoopGains gains;
  std::optional<Margins> margins;          // predicted on the measured plant (FRF method)
  std::optional<Margins> present_margins;  // of the gains the FRF was measured with
  std::optional<StepPrediction> step;      // predicted standard step
  std::optional<FeedforwardDesign> feedforward;  // FRF method
  std::string note;
};

TuneResult run_tune(const TuneOptions& options, const std::atomic<bool>& stop, std::ostream& out);

}  // namespace rigctl
