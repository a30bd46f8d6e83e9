// The `operator:` section: where `rigctl run` listens for authenticated
// operator commands (docs/operator-commands.md, docs/deployment.md). Used
// when the rig runs in operator mode (`safety.auto_sequence: false` or
// `rigctl run --operator`); with the automatic sequence it is checked but not
// used, so one file serves the bench and the service.
#pragma once

#include <string>

namespace rigctl {

class ConfigReader;

struct OperatorConfig {
  bool present = false;  // the section is in the file
  std::string key_file;  // the rig's key (mode 600); a relative path is taken from the config's folder
  std::string lcm_url;   // "": the telemetry URL (after --lcm-url)
  std::string channel;   // "": <telemetry.channel_prefix>OPERATOR; acks on <channel>_ACK
  double staleness_s = 2.0;  // commands dated further from the rig's clock (either way) are refused
};

// Strict: unknown keys and bad values are ConfigErrors naming operator.KEY.
OperatorConfig read_operator(ConfigReader r, const std::string& config_file);

}  // namespace rigctl
