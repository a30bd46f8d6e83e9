// Reader of the `operator:` section (config/operator_config.hpp).
#include "config/operator_config.hpp"

#include <filesystem>

#include "config/config_reader.hpp"

namespace rigctl {

OperatorConfig read_operator(ConfigReader r, const std::string& config_file) {
  OperatorConfig c;
  c.present = true;
  const std::filesystem::path key = r.text("key_file");
  if (key.empty()) r.fail("key_file", "must name the rig's key file");
  c.key_file = key.is_absolute() ? key.string() : (std::filesystem::path(config_file).parent_path() / key).string();
  if (r.has("lcm_url")) {
    c.lcm_url = r.text("lcm_url");
    // The receiver refuses LCM's implicit default group: a URL must say where.
    if (c.lcm_url.find("://") == std::string::npos) r.fail("lcm_url", "expected a URL such as udpm://239.255.76.67:7667?ttl=1");
  }
  if (r.has("channel")) {
    c.channel = r.text("channel");
    // The receiver subscribes to it literally; LCM channel names are plain.
    for (char ch : c.channel) {
      const bool plain = (ch >= 'A' && ch <= 'Z') || (ch >= 'a' && ch <= 'z') || (ch >= '0' && ch <= '9') || ch == '_';
      if (!plain) r.fail("channel", "only letters, digits and '_' (got '" + c.channel + "')");
    }
    if (c.channel.empty()) r.fail("channel", "must not be empty");
  }
  // Below ~0.1 s NTP jitter alone would refuse genuine commands; above a
  // minute a captured command stays replayable after a restart for too long.
  c.staleness_s = r.number("staleness_s", 0.1, 60.0);
  r.reject_unknown_keys();
  return c;
}

}  // namespace rigctl
