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
#include "tools/hidden_effects/make_run.hpp"
#include "tools/runfile/log2csv.hpp"
#include "tools/runfile/run_file_rig.hpp"
#include "tools/suspension/optimize_command.hpp"
#include "tools/rig_sim/rig_sim.hpp"
#include "tools/run/run_command.hpp"
#include "tools/suspension/compare_command.hpp"

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

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rigctl: real-time controller and simulator for servo-hydraulic and pneumatic test rigs"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "rigctl 0.1.0");

  rigctl::RunOptions run;
  double duration = 0.0;
  auto* run_cmd = app.add_subcommand("run", "Run the control loop on a rig (simulated by default) with LCM telemetry and a run log");
  run_cmd->add_option("config", run.config_path, "Rig config (YAML), e.g. config/quarter_car.yaml")->required()->check(CLI::ExistingFile);
  run_cmd->add_option("--case", run.case_name, "Apply a named variant from the config's `cases:` (e.g. fig4c)");
  auto* duration_opt = run_cmd->add_option("--duration", duration, "Run length [s] (default: the profile's length)")->check(CLI::PositiveNumber);
  run_cmd->add_flag("--fast", run.fast, "Simulated plant only: run as fast as the CPU allows, same results as paced");
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
  run_cmd->add_option("--fault", run_fault_texts, "Inject a fault in the simulated driver, KIND@TIME[:ARG...] (stuck, rail, noise, nan, offset, overrun, supply, burst; SAFETY.md); repeatable");

  std::string log_in, csv_out, prefix = "RIGCTL_";
  auto* l2c = app.add_subcommand("log2csv", "Convert a run's LCM log into a CSV run file (docs/run-files.md)");
  l2c->add_option("log", log_in, "LCM log written by rigctl run")->required();
  l2c->add_option("csv", csv_out, "CSV file to write")->required();
  l2c->add_option("--channel-prefix", prefix, "Telemetry channel prefix used by the run");

  rigctl::RigSimOptions sim;
  double sim_duration = 0.0;
  std::vector<std::string> fault_texts;
  auto* sim_cmd = app.add_subcommand("rig-sim", "Simulate the rig's hardware on the far side of the wire (Modbus DAQ, CANopen valve)");
  sim_cmd->add_option("config", sim.config_path, "Rig config (YAML) with modbus: (and canopen:) sections")->required()->check(CLI::ExistingFile);
  sim_cmd->add_option("--case", sim.case_name, "Apply a named variant from the config's `cases:`");
  auto* modbus_opt = sim_cmd->add_option("--modbus", sim.modbus_tcp, "Serve Modbus TCP on HOST:PORT (port 0: any free port)");
  sim_cmd->add_option("--modbus-rtu", sim.modbus_rtu, "Serve Modbus RTU on this serial device")->excludes(modbus_opt);
  sim_cmd->add_option("--can-socket", sim.can_socket, "Serve the CANopen valve on this seqpacket socket path");
  auto* sim_duration_opt = sim_cmd->add_option("--duration", sim_duration, "Stop after this many seconds (default: at SIGINT/SIGTERM)")->check(CLI::PositiveNumber);
  sim_cmd->add_option("--output-watchdog", sim.output_watchdog_s, "DAQ output watchdog [s]: no write for this long and the outputs go to their safe values; 0: off")->capture_default_str();
  sim_cmd->add_option("--fault", fault_texts, "Inject a fault, KIND@TIME[:ARG...] (silence, drop, late, exception, stuck, rail, heartbeat, emcy); repeatable");

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

  CLI11_PARSE(app, argc, argv);

  try {
    if (run_cmd->parsed()) {
      if (duration_opt->count() > 0) run.duration_s = duration;
      for (const auto& f : run_fault_texts) run.faults.push_back(rigctl::parse_fault_spec(f));
      install_stop_handlers();
      const auto report = rigctl::run_rig(run, g_stop, std::cout);
      return report.loop.final_state == rigctl::RigState::kFaulted ? 3 : 0;
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
      for (const auto& e : effect_texts) {
        const auto colon = e.find(':');
        make.effects.emplace_back(e.substr(0, colon),
                                  colon == std::string::npos ? 1.0 : rigctl::parse_effect_level(e.substr(colon + 1)));
      }
      rigctl::make_run(make, std::cerr);
      return 0;
    }
    if (bench_cmd->parsed()) {
      for (int i = 0; i < argc; ++i) bench.command_line += (i > 0 ? " " : "") + std::string(argv[i]);
      install_stop_handlers();
      return rigctl::run_bench(bench, g_stop, std::cout);
    }
    if (diag_cmd->parsed()) return rigctl::run_diagnose(diag, std::cout, std::cerr);
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
