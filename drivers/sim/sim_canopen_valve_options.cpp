#include <cmath>
#include <stdexcept>

#include "drivers/sim/sim_canopen_valve_config.hpp"
#include "rt/parse_number.hpp"

namespace rigctl {

namespace {

[[noreturn]] void bad(const std::string& option, const std::string& why) {
  throw std::invalid_argument("valve option '" + option + "': " + why);
}

long integer(const std::string& option, const std::string& text, long min, long max) {
  std::size_t used = 0;
  long v = 0;
  try {
    v = std::stol(text, &used, 0);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || v < min || v > max) {
    bad(option, "'" + text + "' is not an integer " + std::to_string(min) + ".." + std::to_string(max));
  }
  return v;
}

canopen::cia408::ValveState stall_state(const std::string& option, const std::string& text) {
  using S = canopen::cia408::ValveState;
  if (text == "init") return S::kInit;
  if (text == "disabled") return S::kDisabled;
  if (text == "hold") return S::kHold;
  bad(option, "unknown state '" + text + "' (init, disabled, hold)");
}

}  // namespace

void apply_sim_valve_option(const std::string& option, SimCanopenValveConfig& c) {
  const auto eq = option.find('=');
  const std::string key = option.substr(0, eq);
  const bool has_value = eq != std::string::npos;
  const std::string value = has_value ? option.substr(eq + 1) : "";
  const auto need_value = [&] {
    if (!has_value || value.empty()) bad(option, "expected " + key + "=VALUE");
  };
  const auto no_value = [&] {
    if (has_value) bad(option, key + " takes no value");
  };
  if (key == "device_type") {
    need_value();
    c.device_type = static_cast<uint32_t>(integer(option, value, 0, 0xFFFFFFFFL));
  } else if (key == "spool_reference") {
    need_value();
    c.spool_reference = static_cast<int16_t>(integer(option, value, 1, 32767));
  } else if (key == "boot_delay") {
    need_value();
    const auto s = parse_finite(value);
    if (!s || *s < 0.0 || *s > 10.0) bad(option, "'" + value + "' is not a time in seconds 0..10");
    c.boot_delay_s = *s;
  } else if (key == "power_on_mapping") {
    need_value();
    if (value == "profile") {
      c.power_on_mapping = SimPowerOnMapping::kProfile;
    } else if (value == "minimal") {
      c.power_on_mapping = SimPowerOnMapping::kMinimal;
    } else {
      bad(option, "unknown mapping '" + value + "' (profile, minimal)");
    }
  } else if (key == "fixed_mapping") {
    no_value();
    c.fixed_mapping = true;
  } else if (key == "segmented_uploads") {
    no_value();
    c.segmented_uploads = true;
  } else if (key == "stall") {
    need_value();
    c.stall_at = stall_state(option, value);
  } else {
    bad(option, "unknown key '" + key +
                    "' (device_type, spool_reference, boot_delay, power_on_mapping, fixed_mapping, segmented_uploads, stall)");
  }
}

}  // namespace rigctl
