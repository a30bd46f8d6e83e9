// rigctl: one program, one subcommand per job.
#include <CLI/CLI.hpp>
#include <spdlog/spdlog.h>

#include <atomic>
#include <csignal>
#include <iostream>

#include "config/config_reader.hpp"
#include "tools/bench/bench_command.hpp"
#include "tools/cmd/cmd_command.hpp"
#include "tools/diagnosis/diagnose_command.hpp"
#include "tools/health/health_command.hpp"
#include "tools/health/make_series.hpp"
#include "tools/hidden_effects/make_run.hpp"
#include "tools/bridge/bridge_command.hpp"
#include "tools/catalog/catalog_command.hpp"
#include "tools/identify/identify_command.hpp"
#include "tools/iterate/iterate_command.hpp"
#include "tools/iterate/road_target_command.hpp"
#include "tools/tune/tune_command.hpp"
#include "tools/runfile/log2csv.hpp"
#include "tools/runfile/log2mcap.hpp"
#include "tools/procedure/rainflow_files.hpp"
#include "tools/runfile/run_file_rig.hpp"
#include "tools/suspension/optimize_command.hpp"
#include "tools/rig_sim/rig_sim.hpp"
#include "tools/run/run_command.hpp"
#include "tools/suspension/compare_command.hpp"
#include "generated/rigctl_version.hpp"  // cmake/version.cmake: the version
#include "tools/common/revision.hpp"

namespace {

std::atomic<bool> g_stop{false};

extern "C" void request_stop(int) { g_stop.store(true); }

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = request_stop;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

// CAUSE[:weak|strong|LEVEL] per text (make-run, iterate --effect).
std::vector<std::pair<std::string, double>> parse_effects(const std::vector<std::string>& texts) {
  std::vector<std::pair<std::string, double>> out;
  for (const auto& e : texts) {
    const auto colon = e.find(':');
    out.emplace_back(e.substr(0, colon), colon == std::string::npos ? 1.0 : rigctl::parse_effect_level(e.substr(colon + 1)));
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rigctl: real-time controller and simulator for servo-hydraulic and pneumatic test rigs"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("rigctl ") + RIGCTL_VERSION + " (git " + rigctl::rigctl_revision() + ")");

  rigctl::RunOptions run;
  double duration = 0.0;
  auto* run_cmd = app.add_subcommand("run", "Run the control loop on a rig (simulated by default) with LCM telemetry and a run log");
  run_cmd->add_option("config", run.config_path, "Rig config (YAML), e.g. config/quarter_car.yaml")->required()->check(CLI::ExistingFile);
  run_cmd->add_option("--case", run.case_name, "Apply a named variant from the config's `cases:` (e.g. fig4c)");
  auto* duration_opt = run_cmd->add_option("--duration", duration, "Run length [s] (default: the profile's length)")->check(CLI::PositiveNumber);
  run_cmd->add_flag("--fast", run.fast, "Simulated plant only: run as fast as the CPU allows, same results as paced");
  run_cmd->add_flag("--lock-step", run.lock_step, "Tests: Modbus driver against `rig-sim --lock-step`, one DAQ exchange per tick, simulated time");
  run_cmd->add_option("--log", run.log_path, "LCM log file to write (default: a new file in the config's log_dir)");
  run_cmd->add_option("--csv", run.csv_path, "Also write the run as a CSV run file");
  run_cmd->add_option("--events", run.events_path, "Event log to append to (default: <log>.events; SAFETY.md)");
  run_cmd->add_option("--telemetry-queue", run.telemetry_queue_records,
                      "Records the loop can hand to the publisher before its queue is full (default: 10 s of ticks); "
                      "full: a paced run drops and counts, a --fast run waits")->check(CLI::PositiveNumber);
  run_cmd->add_option("--lcm-url", run.lcm_url, "LCM URL, overrides telemetry.lcm_url (e.g. udpm://239.255.76.67:7667?ttl=1)");
  run_cmd->add_flag("--no-realtime{false}", run.realtime, "Do not try mlockall/SCHED_FIFO");
  run_cmd->add_flag("--operator", run.operator_mode, "Operator mode whatever safety.auto_sequence says: power up faulted, move only on `rigctl cmd` (docs/deployment.md)");
  run_cmd->add_option("--key", run.key_path, "Operator key file, overrides operator.key_file (mode 600)");
  std::vector<std::string> run_fault_texts;
  std::string run_ws;
  run_cmd->add_option("--ws", run_ws, "Serve the telemetry to Foxglove/Lichtblick on a WebSocket, [ADDR:]PORT (default address 127.0.0.1; port 0: any free port); overrides telemetry.websocket (docs/foxglove.md)");
  run_cmd->add_option("--catalog", run.catalog_path, "Run catalog to enter the run into (SQLite, created on first use); overrides the config's catalog.path (docs/rig-health.md)");
  run_cmd->add_option("--procedure", run.procedure_path, "Run a test procedure (sine, blocks, drive, repeat; docs/procedures.md)")->check(CLI::ExistingFile);
  run_cmd->add_option("--resume", run.resume_path, "Continue the procedure from its recovery file (after a crash, kill or power cut)")->check(CLI::ExistingFile);
  run_cmd->add_option("--recovery", run.recovery_path, "Where the procedure's recovery file is written (default: <log>.recovery)");
  run_cmd->add_option("--fault", run_fault_texts, "Inject a fault in the simulated driver, KIND@TIME[:ARG...] (stuck, rail, noise, nan, offset, overrun, supply, burst; SAFETY.md); repeatable");

  std::string log_in, csv_out, prefix = "RIGCTL_";
  auto* l2c = app.add_subcommand("log2csv", "Convert a run's LCM log into a CSV run file (docs/run-files.md)");
  l2c->add_option("log", log_in, "LCM log written by rigctl run")->required();
  l2c->add_option("csv", csv_out, "CSV file to write")->required();
  l2c->add_option("--channel-prefix", prefix, "Telemetry channel prefix used by the run");

  std::string mcap_in, mcap_out, mcap_prefix = "RIGCTL_";
  auto* l2m = app.add_subcommand("log2mcap", "Convert a run's LCM log into an MCAP file for Foxglove, Lichtblick and PlotJuggler (docs/foxglove.md)");
  l2m->add_option("log", mcap_in, "LCM log written by rigctl run")->required();
  l2m->add_option("mcap", mcap_out, "MCAP file to write")->required();
  l2m->add_option("--channel-prefix", mcap_prefix, "Telemetry channel prefix used by the run");

  rigctl::RainflowFileOptions rainflow;
  auto* rainflow_cmd = app.add_subcommand("rainflow", "Rainflow count (ASTM E1049) and pseudo-damage of a recorded run's channel (docs/procedures.md)");
  rainflow_cmd->add_option("run", rainflow.run_path, "Run file (CSV) or a run's LCM log (.lcm)")->required()->check(CLI::ExistingFile);
  rainflow_cmd->add_option("--channel", rainflow.channel, "Column to count, e.g. x_r")->required();
  rainflow_cmd->add_option("--matrix", rainflow.matrix_path, "Write the range-mean matrix as CSV");
  rainflow_cmd->add_option("--basquin", rainflow.basquin_exponent, "Basquin exponent of the pseudo-damage")->capture_default_str()->check(CLI::PositiveNumber);
  rainflow_cmd->add_option("--reference-range", rainflow.reference_range, "Range of unit damage (default: the largest range)")->check(CLI::PositiveNumber);

  rigctl::BridgeOptions bridge;
  std::string bridge_ws;
  double bridge_duration = 0.0;
  auto* bridge_cmd = app.add_subcommand("bridge", "Serve a rig network's LCM telemetry (or lcm-logplayer's) to Foxglove/Lichtblick on a WebSocket (docs/foxglove.md)");
  bridge_cmd->add_option("--lcm-url", bridge.lcm_url, "LCM URL of the rig network, e.g. udpm://239.255.76.67:7667?ttl=1")->required();
  bridge_cmd->add_option("--ws", bridge_ws, "[ADDR:]PORT to serve on (default address 127.0.0.1; port 0: any free port)")->required();
  bridge_cmd->add_option("--channel-prefix", bridge.channel_prefix, "Telemetry channel prefix of the rig")->capture_default_str();
  bridge_cmd->add_option("--config", bridge.config_path, "The rig's config: its gains and limits as read-only parameters")->check(CLI::ExistingFile);
  bridge_cmd->add_option("--client-queue", bridge.client_queue_messages, "Messages queued per client before the oldest is dropped")->capture_default_str()->check(CLI::PositiveNumber);
  auto* bridge_duration_opt = bridge_cmd->add_option("--duration", bridge_duration, "Stop after this many seconds (default: at SIGINT/SIGTERM)")->check(CLI::PositiveNumber);

  rigctl::RigSimOptions sim;
  double sim_duration = 0.0;
  std::vector<std::string> fault_texts;
  auto* sim_cmd = app.add_subcommand("rig-sim", "Simulate the rig's hardware on the far side of the wire (Modbus DAQ, CANopen valve)");
  sim_cmd->add_option("config", sim.config_path, "Rig config (YAML) with modbus: (and canopen:) sections")->required()->check(CLI::ExistingFile);
  sim_cmd->add_option("--case", sim.case_name, "Apply a named variant from the config's `cases:`");
  auto* modbus_opt = sim_cmd->add_option("--modbus", sim.modbus_tcp, "Serve Modbus TCP on HOST:PORT (port 0: any free port)");
  sim_cmd->add_option("--modbus-rtu", sim.modbus_rtu, "Serve Modbus RTU on this serial device")->excludes(modbus_opt);
  sim_cmd->add_option("--can-socket", sim.can_socket, "Serve the CANopen valve on this seqpacket socket path");
  sim_cmd->add_option("--valve", sim.valve_options,
                      "A behaviour of the simulated CANopen valve, KEY[=VALUE]: device_type=401, spool_reference=N, "
                      "boot_delay=S, power_on_mapping=profile|minimal, fixed_mapping, segmented_uploads, "
                      "stall=init|disabled|hold; repeatable");
  auto* sim_duration_opt = sim_cmd->add_option("--duration", sim_duration, "Stop after this many seconds (default: at SIGINT/SIGTERM)")->check(CLI::PositiveNumber);
  sim_cmd->add_option("--output-watchdog", sim.output_watchdog_s, "DAQ output watchdog [s]: no write for this long and the outputs go to their safe values; 0: off")->capture_default_str();
  sim_cmd->add_flag("--lock-step", sim.lock_step, "Tests: step the plant one loop period per DAQ exchange (`run --lock-step`), not by the clock");
  sim_cmd->add_option("--fault", fault_texts, "Inject a fault, KIND@TIME[:ARG...] (silence, drop, late, exception, stuck, rail, heartbeat, emcy, hold); repeatable");

  rigctl::CompareOptions compare;
  auto* compare_cmd = app.add_subcommand("compare", "Half car: passive, fuzzy, skyhook and LQR on the configured road, metrics beside the paper's");
  compare_cmd->add_option("config", compare.config_path, "Half-car config (YAML), e.g. config/half_car.yaml")->required()->check(CLI::ExistingFile);
  compare_cmd->add_option("--case", compare.case_name, "Apply a named variant from the config's `cases:` (e.g. iso_c)");
  compare_cmd->add_option("--out", compare.out_dir, "Folder for the CSV run files and metrics.json (default: <log_dir>/half_car-compare[-CASE])");

  rigctl::OptimizeOptions optimize;
  int optimize_evaluations = 0;
  auto* optimize_cmd = app.add_subcommand("optimize", "Half car: search springs and dampers within Table 2 (NLopt) for the weighted comfort/handling cost");
  optimize_cmd->add_option("config", optimize.config_path, "Half-car config (YAML) with an optimize: section")->required()->check(CLI::ExistingFile);
  optimize_cmd->add_option("--case", optimize.case_name, "Apply a named variant from the config's `cases:`");
  auto* evaluations_opt = optimize_cmd->add_option("--evaluations", optimize_evaluations, "Simulation runs of the search (overrides optimize.evaluations)")->check(CLI::PositiveNumber);
  optimize_cmd->add_option("--out", optimize.out_path, "JSON file for the optimum (default: <log_dir>/half_car-optimum[-CASE].json)");
  optimize_cmd->add_flag("--quiet{false}", optimize.progress, "No progress display on stderr");

  rigctl::BenchOptions bench;
  auto* bench_cmd = app.add_subcommand("bench", "Benchmarks: loop timing vs cyclictest, plant speed and accuracy vs a reference integrator, I/O, scaling (BENCHMARKS.md)");
  bench_cmd->add_flag("--quick", bench.quick, "Seconds instead of minutes: checks that every section runs (rough numbers)");
  bench_cmd->add_option("--json", bench.json_path, "Write every result to this JSON file");
  bench_cmd->add_option("--config-dir", bench.config_dir, "Folder with quarter_car.yaml and pneumatic_rotary.yaml (default: config)")->check(CLI::ExistingDirectory);
  bench_cmd->add_option("--sweep-rig", bench.sweep_rig, "diagnosis_sweep: only this rig kind");
  bench_cmd->add_option("--sweep-jobs", bench.sweep_jobs, "diagnosis_sweep: runs diagnosed at a time (default 2; 1: each its own wall time)")->check(CLI::Range(1, 8));
  bench_cmd->add_option("--section", bench.sections, "Run only this section; repeatable")->check(CLI::IsMember(rigctl::bench_section_names()));

  rigctl::DiagnoseCommandOptions diag;
  auto* diag_cmd = app.add_subcommand("diagnose", "Model-discrepancy diagnosis of a run file (docs/run-files.md, docs/diagnosis.md)");
  diag_cmd->add_option("--rig", diag.rig, "Rig kind: " + rigctl::known_kind_names<rigctl::RunFileRig>())->required();
  diag_cmd->add_option("--data", diag.data_path, "Run file (CSV)")->required();
  diag_cmd->add_option("--config", diag.config_path, "Rig config (default: nominal parameters)");
  diag_cmd->add_option("--json", diag.json_path, "Write the diagnosis as JSON");
  diag_cmd->add_option("--report", diag.report_path, "Write a self-contained HTML report with plots");
  diag_cmd->add_flag("--drop-bad-rows", diag.drop_bad_rows, "Drop (and count) rows with bad cells instead of failing");
  diag_cmd->add_option("--decimate", diag.decimate, "Keep every Nth sample (default: the rig's choice)");
  diag_cmd->add_flag("--quiet", diag.quiet, "No progress on stderr");
  diag_cmd->add_option("--catalog", diag.catalog_path, "Also write the diagnosis into this run catalog, linked to the run (docs/rig-health.md)");
  diag_cmd->add_option("--rig-name", diag.rig_name, "With --catalog: the rig's name for a run not yet entered (default: the rig kind)");
  diag_cmd->add_option("--threads", diag.threads, "Threads of the whole diagnosis (default 2)")->check(CLI::Range(1, 64));

  rigctl::MakeRunOptions make;
  std::string make_rig;
  std::vector<std::string> effect_texts;
  auto* make_cmd = app.add_subcommand("make-run", "Hidden-effect generator: a run file from the simulated closed loop with chosen effects switched on (diagnosis tests)");
  make_cmd->add_option("--rig", make_rig, "Rig kind: " + rigctl::known_kind_names<rigctl::RigKind>())->required();
  make_cmd->add_option("--config", make.config_path, "Rig config (default: config/<rig>.yaml)");
  make_cmd->add_option("--case", make.case_name, "Excitation case of the config (default: the rig's diagnosis case)");
  make_cmd->add_option("--effect", effect_texts, "CAUSE[:weak|strong|LEVEL], repeatable; none or absent: a clean run");
  make_cmd->add_option("--duration", make.duration_s, "Run length [s] (default: the profile's)");
  make_cmd->add_option("--seed", make.seed, "Seed of the sensor noise, the parameter draw and (without --form) the form");
  make_cmd->add_option("--tolerance", make.tolerance,
                       "Half-width of every plant parameter's draw, a fraction (default 0.05: +-5 %); 0: nominal plant, "
                       "nominal controller and demand");
  make_cmd->add_option("--form", make.form, "Physical form of the effects, 0 or 1 (default: seed % 2)");
  make_cmd->add_option("--out", make.out_csv, "Run file to write (CSV)")->required();
  make_cmd->add_option("--truth", make.truth_json, "Write what was hidden (JSON)");

  // Authenticated operator commands (issue 7; tools/cmd/cmd_command.hpp).
  rigctl::CmdOptions opcmd;
  auto* opcmd_cmd = app.add_subcommand("cmd", "Send an authenticated operator command to a rig and wait for its acknowledgement (docs/operator-commands.md)");
  opcmd_cmd->add_option("command", opcmd.command, "arm|start|hold|resume|stop|reset|hydraulics-low|hydraulics-high|hydraulics-off|setpoint")->required();
  opcmd_cmd->add_option("value", opcmd.value, "setpoint only: the new setpoint (SI units)");
  opcmd_cmd->add_option("--key", opcmd.key_path, "Key file shared with the rig (mode 600, at least 32 bytes)")->required();
  opcmd_cmd->add_option("--lcm-url", opcmd.lcm_url, "LCM URL of the rig network")->capture_default_str();
  opcmd_cmd->add_option("--channel", opcmd.channel, "Command channel (replies on <channel>_ACK)")->capture_default_str();
  opcmd_cmd->add_option("--sender", opcmd.sender, "Sender id (default USER@HOSTNAME)");
  opcmd_cmd->add_option("--wait-ack", opcmd.wait_ack_s, "Seconds to wait for the rig's reply; 0: do not wait")->capture_default_str();
  opcmd_cmd->add_option("--state-file", opcmd.state_path, "Sequence state file (default $XDG_STATE_HOME/rigctl/<sender>.seq)");

  // Commissioning (issue 18): the loop's frequency response (docs/frf-files.md).
  rigctl::IdentifyOptions ident;
  std::string ident_excitation;
  std::vector<double> ident_band;
  double ident_amplitude = 0, ident_duration = 0, ident_resolution = 0, ident_op = 0, ident_settle = 0, ident_gain = 0;
  auto* ident_cmd = app.add_subcommand("identify", "Measure the loop's and the plant's frequency response with an excitation about an operating point (docs/frf-files.md)");
  ident_cmd->add_option("config", ident.config_path, "Rig config (YAML); its optional identify: section sets the defaults")->required()->check(CLI::ExistingFile);
  ident_cmd->add_option("--case", ident.case_name, "Apply a named variant from the config's `cases:`");
  ident_cmd->add_option("--out", ident.out_path, "FRF file to write (JSON)")->required();
  ident_cmd->add_option("--plot", ident.plot_path, "Also plot the FRF with its coherence (PNG; needs matplotlib: setup.sh --plots)");
  ident_cmd->add_option("--log", ident.log_path, "LCM log of the run (default: a new file in the config's log_dir)");
  ident_cmd->add_option("--csv", ident.csv_path, "Run file of the run (default: next to the FRF, -run.csv)");
  ident_cmd->add_flag("--fast", ident.fast, "Simulated plant only: simulated time, as fast as the CPU allows");
  ident_cmd->add_flag("--no-realtime{false}", ident.realtime, "Do not try mlockall/SCHED_FIFO");
  auto* ex_opt = ident_cmd->add_option("--excitation", ident_excitation, "Excitation: " + rigctl::known_kind_names<rigctl::ExcitationKind>());
  auto* band_opt = ident_cmd->add_option("--band", ident_band, "Band LOW HIGH [Hz]")->expected(2);
  auto* amp_opt = ident_cmd->add_option("--amplitude", ident_amplitude, "Peak of the excitation [feedback unit]; clamped by the rig's limits (default: the clamp)")->check(CLI::PositiveNumber);
  auto* dur_opt = ident_cmd->add_option("--duration", ident_duration, "Excitation time [s], the first (settling) segment included")->check(CLI::PositiveNumber);
  auto* res_opt = ident_cmd->add_option("--resolution", ident_resolution, "Frequency resolution [Hz]: one Welch segment lasts 1/resolution")->check(CLI::PositiveNumber);
  auto* op_opt = ident_cmd->add_option("--operating-point", ident_op, "Demand held while exciting [feedback unit] (default: mid-stroke, the middle of safety.setpoint_range)");
  auto* settle_opt = ident_cmd->add_option("--settle", ident_settle, "Hold at the operating point before the excitation [s]")->check(CLI::NonNegativeNumber);
  ident_cmd->add_option("--response", ident.settings.extra_responses, "Also measure this response channel after the controller's feedback (e.g. x_w for rigctl iterate); repeatable");
  auto* gain_opt = ident_cmd->add_option("--stabiliser-gain", ident_gain, "Replace the controller by a proportional one of this gain (PI: kp, P+V+dP: Ke): a rig without gains")->check(CLI::PositiveNumber);

  rigctl::TuneOptions tune;
  std::string tune_method = "frf";
  double tune_bandwidth = 0;
  auto* tune_cmd = app.add_subcommand("tune", "Gains for the rig's controller from a measured FRF (or a relay experiment), with predicted margins and step (docs/frf-files.md)");
  tune_cmd->add_option("config", tune.config_path, "Rig config (YAML)")->required()->check(CLI::ExistingFile);
  tune_cmd->add_option("--case", tune.case_name, "Apply a named variant from the config's `cases:`");
  tune_cmd->add_option("--frf", tune.frf_path, "FRF file from rigctl identify")->check(CLI::ExistingFile);
  tune_cmd->add_option("--method", tune_method, "frf: loop shaping on the FRF; relay: Astrom-Hagglund relay experiment, Ziegler-Nichols gains")->check(CLI::IsMember({"frf", "relay"}));
  tune_cmd->add_option("--phase-margin", tune.target.phase_margin_deg, "Target phase margin [deg]")->capture_default_str()->check(CLI::Range(10.0, 89.0));
  auto* bw_opt = tune_cmd->add_option("--bandwidth", tune_bandwidth, "Target crossover frequency [Hz] (default: the stiffest design with 6 dB gain margin and sensitivity peak 2)")->check(CLI::PositiveNumber);
  tune_cmd->add_flag("--no-feedforward{false}", tune.feedforward, "PI: no velocity feedforward of the demand (by default it is 1 / the measured plant's velocity gain)");
  tune_cmd->add_option("--out", tune.out_path, "Write the config with the tuned gains (YAML, comments kept)");
  tune_cmd->add_option("--json", tune.json_path, "Write the design and its predictions (JSON)");
  tune_cmd->add_option("--plot", tune.plot_path, "Bode plot of the measured plant and the tuned loop (PNG)");
  tune_cmd->add_option("--evaluate", tune.evaluate_path, "Only measure a run of the config's standard step (rigctl run --csv): overshoot, settling, IAE")->check(CLI::ExistingFile);
  tune_cmd->add_option("--relay-amplitude", tune.relay.amplitude, "Relay output about the hold command [command unit] (default: a tenth of the output limit)")->check(CLI::PositiveNumber);
  tune_cmd->add_option("--relay-hysteresis", tune.relay.hysteresis, "Relay hysteresis [feedback unit] (default: 3 x the sensor noise)")->check(CLI::PositiveNumber);
  tune_cmd->add_option("--relay-duration", tune.relay.duration_s, "Relay time [s]")->capture_default_str()->check(CLI::PositiveNumber);
  tune_cmd->add_option("--log", tune.relay.log_path, "LCM log of the relay run");
  tune_cmd->add_flag("--fast", tune.relay.fast, "Relay on a simulated plant: simulated time");
  tune_cmd->add_flag("--no-realtime{false}", tune.relay.realtime, "Do not try mlockall/SCHED_FIFO");

  // Road-simulator drive iteration (issue 19): docs/drive-iteration.md.
  rigctl::IterateOptions iter;
  std::vector<std::string> iter_effects;
  auto* iter_cmd = app.add_subcommand("iterate", "Iterate the rig's drive until a channel's response matches a target (road simulator; docs/drive-iteration.md)");
  iter_cmd->add_option("config", iter.config_path, "Rig config (YAML)")->required()->check(CLI::ExistingFile);
  iter_cmd->add_option("--case", iter.case_name, "Apply a named variant from the config's `cases:`");
  iter_cmd->add_option("--target", iter.target_path, "Target: a run file (t and the channel) or an RPC III file (.rsp, .tim)")->required()->check(CLI::ExistingFile);
  iter_cmd->add_option("--channel", iter.channel, "The rig's channel the target is for, e.g. x_w")->required();
  iter_cmd->add_option("--target-channel", iter.target_channel, "The target file's channel: a name or a 1-based number (default: --channel)");
  iter_cmd->add_option("--max-length", iter.max_length_s, "Longest target played [s]; a longer one is refused")->capture_default_str()->check(CLI::PositiveNumber);
  std::string iter_window;
  iter_cmd->add_option("--window", iter_window, "T0:T1, the part of the target the error is judged on [s] (default: where it departs from its lead-in and lead-out)");
  iter_cmd->add_option("--first-level", iter.settings.first_level, "The first drive's level in the band, a share of the inverse's")->capture_default_str()->check(CLI::Range(0.05, 1.0));
  iter_cmd->add_option("--max-growth", iter.settings.max_growth, "Refuse a drive whose content in the band grew more than this over the last one")->capture_default_str()->check(CLI::Range(1.0, 100.0));
  iter_cmd->add_option("--out", iter.out_dir, "Folder for summary.json and each iteration's drive and response")->required();
  auto* frf_opt = iter_cmd->add_option("--frf", iter.frf_path, "FRF file from rigctl identify (with the channel: identify --response NAME)")->check(CLI::ExistingFile);
  iter_cmd->add_option("--model", iter.model_path, "Diagnosis JSON (rigctl diagnose --json): the inverse from the model it extended (default: the config's nominal model)")->check(CLI::ExistingFile)->excludes(frf_opt);
  iter_cmd->add_option("--max-iterations", iter.settings.max_iterations, "Drives played at most")->capture_default_str()->check(CLI::PositiveNumber);
  iter_cmd->add_option("--tolerance", iter.settings.tolerance_percent, "Stop at this relative RMS error [%] over the band")->capture_default_str()->check(CLI::PositiveNumber);
  iter_cmd->add_option("--gain", iter.settings.initial_gain, "The update's gain alpha at the start, 0..1")->capture_default_str()->check(CLI::Range(0.05, 1.0));
  iter_cmd->add_option("--band", iter.settings.inverse.band_min_hz, "Low end of the band [Hz]")->capture_default_str();
  iter_cmd->add_option("--band-max", iter.settings.inverse.band_max_hz, "High end of the band [Hz]")->capture_default_str();
  iter_cmd->add_flag("--scale", iter.settings.scale_to_fit, "Scale a drive beyond the rig's limits until it fits, instead of refusing it");
  iter_cmd->add_flag("--fast", iter.fast, "Simulated plant only: simulated time, as fast as the CPU allows");
  iter_cmd->add_flag("--no-realtime{false}", iter.realtime, "Do not try mlockall/SCHED_FIFO");
  iter_cmd->add_flag("--plot", iter.plot, "Also plot target, responses and errors per iteration (DIR/iterations.png; needs matplotlib)");
  iter_cmd->add_option("--effect", iter_effects, "Simulated rig only: a hidden effect, CAUSE[:weak|strong|LEVEL] as for make-run; repeatable");

  rigctl::RoadTargetOptions road;
  std::string road_class = "C";
  auto* road_cmd = app.add_subcommand("road-target", "A target for rigctl iterate: a quarter car's wheel displacement over an ISO 8608 road (docs/drive-iteration.md)");
  road_cmd->add_option("config", road.config_path, "Quarter-car config: its wheel, body, tyre and mid-stroke")->required()->check(CLI::ExistingFile);
  road_cmd->add_option("--class", road_class, "ISO 8608 road class A..E")->capture_default_str()->check(CLI::IsMember({"A", "B", "C", "D", "E"}));
  road_cmd->add_option("--speed", road.spec.speed_m_s, "Road speed [m/s]")->capture_default_str()->check(CLI::PositiveNumber);
  road_cmd->add_option("--duration", road.spec.duration_s, "Length [s]")->capture_default_str()->check(CLI::PositiveNumber);
  road_cmd->add_option("--seed", road.spec.seed, "Seed of the road's random phases")->capture_default_str();
  road_cmd->add_option("--channel", road.channel, "Column name of the wheel displacement")->capture_default_str();
  road_cmd->add_option("--out", road.out_path, "Run file to write (CSV), or RPC III (.rsp, .tim)")->required();

  // The run catalog (issue 32, docs/rig-health.md): one subcommand each, shared options.
  rigctl::CatalogCommandOptions cat;
  auto* cat_cmd = app.add_subcommand("catalog", "The rig's run catalog (SQLite): add, list, show, query, repair (docs/rig-health.md)");
  cat_cmd->require_subcommand(1);
  std::vector<std::pair<CLI::App*, rigctl::CatalogAction>> cat_actions;
  auto cat_sub = [&](const char* name, const char* what, rigctl::CatalogAction action) {
    auto* c = cat_cmd->add_subcommand(name, what);
    c->add_option("--catalog", cat.catalog_path, "Catalog file (default: the --config's catalog.path)");
    c->add_option("--config", cat.config_path, "Rig config: its catalog.path and catalog.rig_name")->check(CLI::ExistingFile);
    cat_actions.emplace_back(c, action);
    return c;
  };
  auto* cat_add = cat_sub("add", "Enter recorded runs (RUN.lcm or RUN.csv)", rigctl::CatalogAction::kAdd);
  cat_add->add_option("records", cat.records, "LCM logs or CSV run files")->required()->check(CLI::ExistingFile);
  for (auto* c : {cat_add, cat_sub("repair", "Complete killed runs from their logs; enter the logs of --log-dir not in the catalog", rigctl::CatalogAction::kRepair)}) {
    c->add_option("--rig-name", cat.rig_name, "The rig's name in the catalog (default: the config's, else the rig kind)");
    c->add_option("--channel-prefix", cat.channel_prefix, "Telemetry channel prefix of the logs")->capture_default_str();
  }
  cat_actions.back().first->add_option("--log-dir", cat.log_dir, "Folder of the rig's run logs")->check(CLI::ExistingDirectory);
  cat_sub("show", "One run in full: fields, channel statistics, diagnoses", rigctl::CatalogAction::kShow)
      ->add_option("id", cat.run_id, "Run id")->required();
  for (auto* c : {cat_sub("list", "Runs as a table, oldest first", rigctl::CatalogAction::kList),
                  cat_sub("query", "Runs as JSON with their channel statistics", rigctl::CatalogAction::kQuery)}) {
    c->add_option("--rig", cat.rig, "Rig name or kind");
    c->add_option("--since", cat.since, "Started at or after (UTC, e.g. 2026-11-01 or 2026-11-01T08:00)");
    c->add_option("--until", cat.until, "Started before (UTC)");
    c->add_option("--end-reason", cat.end_reason, "completed, faulted, interrupted, killed, running, unknown");
    c->add_option("--where", cat.where, "CHANNEL.STAT<VALUE or >VALUE (stat: min, max, mean, std, rms), e.g. x_r.max>0.05; repeatable");
  }

  // Rig health (issue 32, docs/rig-health.md): windows of long runs into the catalog, trends and alarms.
  rigctl::health::AnalyseOptions hana;
  rigctl::health::ReportOptions hrep;
  auto* health_cmd = app.add_subcommand("health", "Rig health: diagnose long runs in windows, trend the rig's parameters, raise alarms (docs/rig-health.md)");
  health_cmd->require_subcommand(1);
  auto* hana_cmd = health_cmd->add_subcommand("analyse", "Calibrate the rig's model in windows of a run (RUN.lcm or RUN.csv) into the catalog");
  hana_cmd->add_option("record", hana.record_path, "LCM log or CSV run file")->required()->check(CLI::ExistingFile);
  hana_cmd->add_option("--catalog", hana.catalog_path, "Run catalog (SQLite)")->required();
  hana_cmd->add_option("--window", hana.window_s, "Window length [s]")->capture_default_str()->check(CLI::PositiveNumber);
  hana_cmd->add_option("--rig-name", hana.rig_name, "The rig's name for a run not yet in the catalog (default: the rig kind)");
  hana_cmd->add_option("--config", hana.config_path, "Rig config: the model's nominal parameters and controller")->check(CLI::ExistingFile);
  hana_cmd->add_option("--decimate", hana.decimate, "Keep every Nth sample (default: the rig's choice)");
  hana_cmd->add_flag("--full", hana.full_diagnosis, "Screen the candidate causes in every window too (the whole diagnosis; slow)");
  hana_cmd->add_flag("--follow", hana.follow, "The LCM log is still being written: analyse windows as they complete, until the run ends");
  auto* hrep_cmd = health_cmd->add_subcommand("report", "Parameter trends with uncertainty bands, CUSUM change detection and alarms");
  hrep_cmd->add_option("--catalog", hrep.catalog_path, "Run catalog (SQLite)")->required()->check(CLI::ExistingFile);
  hrep_cmd->add_option("--rig", hrep.rig_name, "The rig's name in the catalog")->required();
  hrep_cmd->add_option("--json", hrep.json_path, "Write the trends and alarms as JSON");
  hrep_cmd->add_option("--html", hrep.html_path, "Write a self-contained HTML page with the trends");
  hrep_cmd->add_option("--png", hrep.png_path, "Plot the trends (PNG; needs matplotlib: setup.sh --plots)");
  hrep_cmd->add_option("--reference", hrep.trends.reference_points, "Windows that set each parameter's reference")->capture_default_str()->check(CLI::PositiveNumber);
  hrep_cmd->add_option("--cusum-k", hrep.trends.cusum.k, "CUSUM allowance [sd]")->capture_default_str()->check(CLI::PositiveNumber);
  hrep_cmd->add_option("--cusum-h", hrep.trends.cusum.h, "CUSUM threshold [sd]")->capture_default_str()->check(CLI::PositiveNumber);

  rigctl::health::SeriesOptions series;
  std::string series_rig = "quarter_car";
  auto* series_cmd = app.add_subcommand("make-series", "A simulated durability series: blocks of runs of one drawn rig while its leakage and friction grow (rig health tests)");
  series_cmd->add_option("--rig", series_rig, "Rig kind (drifts: quarter_car)")->capture_default_str();
  series_cmd->add_option("--config", series.config_path, "Rig config (default: config/<rig>.yaml)");
  series_cmd->add_option("--case", series.case_name, "Excitation case (default: the rig's diagnosis case)");
  series_cmd->add_option("--out", series.out_dir, "Folder for block-NNN.csv and series.json")->required();
  series_cmd->add_option("--blocks", series.blocks, "Runs in the series")->capture_default_str()->check(CLI::PositiveNumber);
  series_cmd->add_option("--block-hours", series.block_spacing_h, "Hours between block starts")->capture_default_str()->check(CLI::PositiveNumber);
  series_cmd->add_option("--start", series.start_utc, "Start of the first block (UTC)")->capture_default_str();
  series_cmd->add_option("--seed", series.seed, "Seed of the rig's draw (each block's noise is its own)")->capture_default_str();
  series_cmd->add_option("--tolerance", series.tolerance, "Half-width of the rig's parameter draw")->capture_default_str();
  series_cmd->add_option("--leakage-growth", series.leakage_growth, "Leakage conductance growth over the series, a fraction (0.5: +50 %)")->capture_default_str();
  series_cmd->add_option("--friction-growth", series.friction_growth, "Rod friction growth over the series, a fraction")->capture_default_str();
  series_cmd->add_option("--duration", series.duration_s, "Block length [s] (default: the excitation's)");

  CLI11_PARSE(app, argc, argv);

  try {
    if (run_cmd->parsed()) {
      if (duration_opt->count() > 0) run.duration_s = duration;
      for (const auto& f : run_fault_texts) run.faults.push_back(rigctl::parse_fault_spec(f));
      if (!run_ws.empty()) run.websocket = rigctl::parse_ws_endpoint(run_ws);
      install_stop_handlers();
      const auto report = rigctl::run_rig(run, g_stop, std::cout);
      return report.loop.final_state == rigctl::RigState::kFaulted ? 3 : 0;
    }
    if (ident_cmd->parsed()) {
      auto& st = ident.settings;
      if (ex_opt->count() > 0) st.excitation = rigctl::parse_kind<rigctl::ExcitationKind>(ident_excitation);
      if (band_opt->count() > 0) {
        st.band_min_hz = ident_band[0];
        st.band_max_hz = ident_band[1];
      }
      if (amp_opt->count() > 0) st.amplitude = ident_amplitude;
      if (dur_opt->count() > 0) st.duration_s = ident_duration;
      if (res_opt->count() > 0) st.resolution_hz = ident_resolution;
      if (op_opt->count() > 0) st.operating_point = ident_op;
      if (settle_opt->count() > 0) st.settle_s = ident_settle;
      if (gain_opt->count() > 0) st.stabiliser_gain = ident_gain;
      install_stop_handlers();
      return rigctl::run_identify(ident, g_stop, std::cout).aborted ? 3 : 0;
    }
    if (iter_cmd->parsed()) {
      iter.effects = parse_effects(iter_effects);
      if (!iter_window.empty()) iter.settings.window_s = rigctl::parse_time_window(iter_window);
      install_stop_handlers();
      const auto result = rigctl::run_iterate(iter, g_stop, std::cout);
      return result.outcome.end == rigctl::IterationEnd::kRunEnded ? 3 : 0;
    }
    if (road_cmd->parsed()) {
      road.spec.road_class = rigctl::iso_road_class_from_letter(road_class);
      rigctl::run_road_target(road, std::cout);
      return 0;
    }
    if (tune_cmd->parsed()) {
      tune.method = rigctl::parse_kind<rigctl::TuneMethod>(tune_method);
      if (bw_opt->count() > 0) tune.target.crossover_hz = tune_bandwidth;
      install_stop_handlers();
      rigctl::run_tune(tune, g_stop, std::cout);
      return 0;
    }
    if (sim_cmd->parsed()) {
      if (sim_duration_opt->count() > 0) sim.duration_s = sim_duration;
      for (const auto& f : fault_texts) sim.faults.push_back(rigctl::parse_fault_spec(f));
      install_stop_handlers();
      rigctl::run_rig_sim(sim, g_stop, std::cout);
      return 0;
    }
    if (compare_cmd->parsed()) {
      rigctl::run_compare(compare, std::cout);
      return 0;
    }
    if (optimize_cmd->parsed()) {
      if (evaluations_opt->count() > 0) optimize.evaluations = optimize_evaluations;
      rigctl::run_optimize(optimize, std::cout, std::cerr);
      return 0;
    }
    if (opcmd_cmd->parsed()) return rigctl::run_cmd_command(opcmd, std::cout, std::cerr);
    if (make_cmd->parsed()) {
      make.rig = rigctl::parse_kind<rigctl::RigKind>(make_rig);
      make.effects = parse_effects(effect_texts);
      rigctl::make_run(make, std::cerr);
      return 0;
    }
    if (bench_cmd->parsed()) {
      for (int i = 0; i < argc; ++i) bench.command_line += (i > 0 ? " " : "") + std::string(argv[i]);
      install_stop_handlers();
      return rigctl::run_bench(bench, g_stop, std::cout);
    }
    if (diag_cmd->parsed()) return rigctl::run_diagnose(diag, std::cout, std::cerr);
    if (hana_cmd->parsed()) {
      install_stop_handlers();
      return rigctl::health::run_health_analyse(hana, g_stop, std::cout, std::cerr);
    }
    if (series_cmd->parsed()) {
      series.rig = rigctl::parse_kind<rigctl::RigKind>(series_rig);
      rigctl::health::make_series(series, std::cerr);
      return 0;
    }
    if (hrep_cmd->parsed()) return rigctl::health::run_health_report(hrep, std::cout, std::cerr);
    for (const auto& [c, action] : cat_actions)
      if (c->parsed()) return rigctl::run_catalog_command(action, cat, std::cout, std::cerr);
    if (l2m->parsed()) {
      const auto result = rigctl::log_to_mcap(mcap_in, mcap_out, mcap_prefix);
      std::cout << "log2mcap: " << result.messages << " messages in " << result.chunks << " chunks written to " << mcap_out;
      if (result.skipped > 0) std::cout << " (" << result.skipped << " events of other channels or undecodable skipped)";
      std::cout << "\n";
      for (const auto& [channel, n] : result.per_channel) std::cout << "  " << channel << ": " << n << "\n";
      if (!result.warning.empty()) std::cerr << "rigctl log2mcap: warning: " << result.warning << "\n";
      return 0;
    }
    if (bridge_cmd->parsed()) {
      bridge.ws = rigctl::parse_ws_endpoint(bridge_ws);
      if (bridge_duration_opt->count() > 0) bridge.duration_s = bridge_duration;
      install_stop_handlers();
      return rigctl::run_bridge(bridge, g_stop, std::cout);
    }
    if (rainflow_cmd->parsed()) return rigctl::run_rainflow_command(rainflow, std::cout);
    if (l2c->parsed()) {
      const auto result = rigctl::log_to_csv(log_in, csv_out, prefix);
      std::cout << "log2csv: " << result.rows << " rows of " << result.rig << " written to " << csv_out;
      if (result.skipped > 0) std::cout << " (" << result.skipped << " incomplete ticks skipped)";
      std::cout << "\n";
      return 0;
    }
  } catch (const rigctl::ConfigError& e) {
    std::cerr << "rigctl: config error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "rigctl: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
