// `rigctl rig-sim`: the rig's hardware on the far side of the wire (tools/rig_sim/rig_sim.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/stop_signal.hpp"
#include "tools/cli/subcommand.hpp"
#include "tools/rig_sim/rig_sim.hpp"

namespace rigctl::cli {

namespace {

class RigSimSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("rig-sim", "Simulate the rig's hardware on the far side of the wire (Modbus DAQ, CANopen valve)");
    c->add_option("config", options_.config_path, "Rig config (YAML) with modbus: (and canopen:) sections")->required()->check(CLI::ExistingFile);
    c->add_option("--case", options_.case_name, "Apply a named variant from the config's `cases:`");
    auto* modbus = c->add_option("--modbus", options_.modbus_tcp, "Serve Modbus TCP on HOST:PORT (port 0: any free port)");
    c->add_option("--modbus-rtu", options_.modbus_rtu, "Serve Modbus RTU on this serial device")->excludes(modbus);
    c->add_option("--can-socket", options_.can_socket, "Serve the CANopen valve on this seqpacket socket path");
    c->add_option("--valve", options_.valve_options,
                  "A behaviour of the simulated CANopen valve, KEY[=VALUE]: device_type=401, spool_reference=N, "
                  "boot_delay=S, power_on_mapping=profile|minimal, fixed_mapping, segmented_uploads, "
                  "stall=init|disabled|hold; repeatable");
    duration_option_ = c->add_option("--duration", duration_, "Stop after this many seconds (default: at SIGINT/SIGTERM)")->check(CLI::PositiveNumber);
    c->add_option("--output-watchdog", options_.output_watchdog_s, "DAQ output watchdog [s]: no write for this long and the outputs go to their safe values; 0: off")->capture_default_str();
    c->add_flag("--lock-step", options_.lock_step, "Tests: step the plant one loop period per DAQ exchange (`run --lock-step`), not by the clock");
    c->add_option("--fault", fault_texts_, "Inject a fault, KIND@TIME[:ARG...] (silence, drop, late, exception, stuck, rail, heartbeat, emcy, hold); repeatable");
    return *c;
  }

  int run(const Invocation& invocation) override {
    if (duration_option_->count() > 0) options_.duration_s = duration_;
    for (const auto& f : fault_texts_) options_.faults.push_back(parse_fault_spec(f));
    run_rig_sim(options_, stop_on_signals(), invocation.out);
    return 0;
  }

 private:
  RigSimOptions options_;
  double duration_ = 0.0;
  CLI::Option* duration_option_ = nullptr;
  std::vector<std::string> fault_texts_;
};

}  // namespace

std::unique_ptr<Subcommand> make_rig_sim_subcommand() { return std::make_unique<RigSimSubcommand>(); }

}  // namespace rigctl::cli
