// `rigctl run`: the control loop on a rig (tools/run/run_command.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/stop_signal.hpp"
#include "tools/cli/subcommand.hpp"
#include "tools/run/run_command.hpp"

namespace rigctl::cli {

namespace {

class RunSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("run", "Run the control loop on a rig (simulated by default) with LCM telemetry and a run log");
    c->add_option("config", run_.config_path, "Rig config (YAML), e.g. config/quarter_car.yaml")->required()->check(CLI::ExistingFile);
    c->add_option("--case", run_.case_name, "Apply a named variant from the config's `cases:` (e.g. fig4c)");
    duration_option_ = c->add_option("--duration", duration_, "Run length [s] (default: the profile's length)")->check(CLI::PositiveNumber);
    c->add_flag("--fast", run_.fast, "Simulated plant only: run as fast as the CPU allows, same results as paced");
    c->add_flag("--lock-step", run_.lock_step, "Tests: Modbus driver against `rig-sim --lock-step`, one DAQ exchange per tick, simulated time");
    c->add_option("--log", run_.log_path, "LCM log file to write (default: a new file in the config's log_dir)");
    c->add_option("--csv", run_.csv_path, "Also write the run as a CSV run file");
    c->add_option("--events", run_.events_path, "Event log to append to (default: <log>.events; SAFETY.md)");
    c->add_option("--telemetry-queue", run_.telemetry_queue_records,
                  "Records the loop can hand to the publisher before its queue is full (default: 10 s of ticks); "
                  "full: a paced run drops and counts, a --fast run waits")->check(CLI::PositiveNumber);
    c->add_option("--lcm-url", run_.lcm_url, "LCM URL, overrides telemetry.lcm_url (e.g. udpm://239.255.76.67:7667?ttl=1)");
    c->add_flag("--no-realtime{false}", run_.realtime, "Do not try mlockall/SCHED_FIFO");
    c->add_flag("--operator", run_.operator_mode, "Operator mode whatever safety.auto_sequence says: power up faulted, move only on `rigctl cmd` (docs/deployment.md)");
    c->add_option("--key", run_.key_path, "Operator key file, overrides operator.key_file (mode 600)");
    c->add_option("--ws", ws_, "Serve the telemetry to Foxglove/Lichtblick on a WebSocket, [ADDR:]PORT (default address 127.0.0.1; port 0: any free port); overrides telemetry.websocket (docs/foxglove.md)");
    c->add_option("--catalog", run_.catalog_path, "Run catalog to enter the run into (SQLite, created on first use); overrides the config's catalog.path (docs/rig-health.md)");
    c->add_option("--procedure", run_.procedure_path, "Run a test procedure (sine, blocks, drive, repeat; docs/procedures.md)")->check(CLI::ExistingFile);
    c->add_option("--resume", run_.resume_path, "Continue the procedure from its recovery file (after a crash, kill or power cut)")->check(CLI::ExistingFile);
    c->add_option("--recovery", run_.recovery_path, "Where the procedure's recovery file is written (default: <log>.recovery)");
    c->add_option("--fault", fault_texts_, "Inject a fault in the simulated driver, KIND@TIME[:ARG...] (stuck, rail, noise, nan, offset, overrun, supply, burst; SAFETY.md); repeatable");
    return *c;
  }

  // Exit 3: the run ended faulted.
  int run(const Invocation& invocation) override {
    if (duration_option_->count() > 0) run_.duration_s = duration_;
    for (const auto& f : fault_texts_) run_.faults.push_back(parse_fault_spec(f));
    if (!ws_.empty()) run_.websocket = parse_ws_endpoint(ws_);
    const auto report = run_rig(run_, stop_on_signals(), invocation.out);
    return report.loop.final_state == RigState::kFaulted ? 3 : 0;
  }

 private:
  RunOptions run_;
  double duration_ = 0.0;
  CLI::Option* duration_option_ = nullptr;
  std::vector<std::string> fault_texts_;
  std::string ws_;
};

}  // namespace

std::unique_ptr<Subcommand> make_run_subcommand() { return std::make_unique<RunSubcommand>(); }

}  // namespace rigctl::cli
