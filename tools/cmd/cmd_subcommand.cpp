// `rigctl cmd`: an authenticated operator command (tools/cmd/cmd_command.hpp).
#include <CLI/CLI.hpp>

#include "tools/cli/subcommand.hpp"
#include "tools/cmd/cmd_command.hpp"

namespace rigctl::cli {

namespace {

class CmdSubcommand final : public Subcommand {
 public:
  CLI::App& add_to(CLI::App& program) override {
    auto* c = program.add_subcommand("cmd", "Send an authenticated operator command to a rig and wait for its acknowledgement (docs/operator-commands.md)");
    c->add_option("command", options_.command, "arm|start|hold|resume|stop|reset|hydraulics-low|hydraulics-high|hydraulics-off|setpoint|stop-at-block-end (a running test procedure)")->required();
    c->add_option("value", options_.value, "setpoint only: the new setpoint (SI units)");
    c->add_option("--key", options_.key_path, "Key file shared with the rig (mode 600, at least 32 bytes)")->required();
    c->add_option("--lcm-url", options_.lcm_url, "LCM URL of the rig network")->capture_default_str();
    c->add_option("--channel", options_.channel, "Command channel (replies on <channel>_ACK)")->capture_default_str();
    c->add_option("--sender", options_.sender, "Sender id (default USER@HOSTNAME)");
    c->add_option("--wait-ack", options_.wait_ack_s, "Seconds to wait for the rig's reply; 0: do not wait")->capture_default_str();
    c->add_option("--state-file", options_.state_path, "Sequence state file (default $XDG_STATE_HOME/rigctl/<sender>.seq)");
    return *c;
  }

  int run(const Invocation& invocation) override { return run_cmd_command(options_, invocation.out, invocation.err); }

 private:
  CmdOptions options_;
};

}  // namespace

std::unique_ptr<Subcommand> make_cmd_subcommand() { return std::make_unique<CmdSubcommand>(); }

}  // namespace rigctl::cli
