// `rigctl identify`: the loop's frequency response (tools/identify/identify_command.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/stop_signal.hpp"
#include "tools/cli/subcommand.hpp"
#include "tools/identify/identify_command.hpp"

namespace rigctl::cli {

namespace {

class IdentifySubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("identify", "Measure the loop's and the plant's frequency response with an excitation about an operating point (docs/frf-files.md)");
    c->add_option("config", options_.config_path, "Rig config (YAML); its optional identify: section sets the defaults")->required()->check(CLI::ExistingFile);
    c->add_option("--case", options_.case_name, "Apply a named variant from the config's `cases:`");
    c->add_option("--out", options_.out_path, "FRF file to write (JSON)")->required();
    c->add_option("--plot", options_.plot_path, "Also plot the FRF with its coherence (PNG; needs matplotlib: setup.sh --plots)");
    c->add_option("--log", options_.log_path, "LCM log of the run (default: a new file in the config's log_dir)");
    c->add_option("--csv", options_.csv_path, "Run file of the run (default: next to the FRF, -run.csv)");
    c->add_flag("--fast", options_.fast, "Simulated plant only: simulated time, as fast as the CPU allows");
    c->add_flag("--no-realtime{false}", options_.realtime, "Do not try mlockall/SCHED_FIFO");
    excitation_option_ = c->add_option("--excitation", excitation_, "Excitation: " + known_kind_names<ExcitationKind>());
    band_option_ = c->add_option("--band", band_, "Band LOW HIGH [Hz]")->expected(2);
    amplitude_option_ = c->add_option("--amplitude", amplitude_, "Peak of the excitation [feedback unit]; clamped by the rig's limits (default: the clamp)")->check(CLI::PositiveNumber);
    duration_option_ = c->add_option("--duration", duration_, "Excitation time [s], the first (settling) segment included")->check(CLI::PositiveNumber);
    resolution_option_ = c->add_option("--resolution", resolution_, "Frequency resolution [Hz]: one Welch segment lasts 1/resolution")->check(CLI::PositiveNumber);
    operating_point_option_ = c->add_option("--operating-point", operating_point_, "Demand held while exciting [feedback unit] (default: mid-stroke, the middle of safety.setpoint_range)");
    settle_option_ = c->add_option("--settle", settle_, "Hold at the operating point before the excitation [s]")->check(CLI::NonNegativeNumber);
    c->add_option("--response", options_.settings.extra_responses, "Also measure this response channel after the controller's feedback (e.g. x_w for rigctl iterate); repeatable");
    gain_option_ = c->add_option("--stabiliser-gain", gain_, "Replace the controller by a proportional one of this gain (PI: kp, P+V+dP: Ke): a rig without gains")->check(CLI::PositiveNumber);
    return *c;
  }

  // Exit 3: the measurement was aborted (a trip or a signal).
  int run(const Invocation& invocation) override {
    apply_given_settings();
    return run_identify(options_, stop_on_signals(), invocation.out).aborted ? 3 : 0;
  }

 private:
  // The options given on the command line over the config's identify: section.
  void apply_given_settings() {
    auto& st = options_.settings;
    if (excitation_option_->count() > 0) st.excitation = parse_kind<ExcitationKind>(excitation_);
    if (band_option_->count() > 0) {
      st.band_min_hz = band_[0];
      st.band_max_hz = band_[1];
    }
    if (amplitude_option_->count() > 0) st.amplitude = amplitude_;
    if (duration_option_->count() > 0) st.duration_s = duration_;
    if (resolution_option_->count() > 0) st.resolution_hz = resolution_;
    if (operating_point_option_->count() > 0) st.operating_point = operating_point_;
    if (settle_option_->count() > 0) st.settle_s = settle_;
    if (gain_option_->count() > 0) st.stabiliser_gain = gain_;
  }

  IdentifyOptions options_;
  std::string excitation_;
  std::vector<double> band_;
  double amplitude_ = 0, duration_ = 0, resolution_ = 0, operating_point_ = 0, settle_ = 0, gain_ = 0;
  CLI::Option* excitation_option_ = nullptr;
  CLI::Option* band_option_ = nullptr;
  CLI::Option* amplitude_option_ = nullptr;
  CLI::Option* duration_option_ = nullptr;
  CLI::Option* resolution_option_ = nullptr;
  CLI::Option* operating_point_option_ = nullptr;
  CLI::Option* settle_option_ = nullptr;
  CLI::Option* gain_option_ = nullptr;
};

}  // namespace

std::unique_ptr<Subcommand> make_identify_subcommand() { return std::make_unique<IdentifySubcommand>(); }

}  // namespace rigctl::cli
