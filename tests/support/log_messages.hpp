// What two runs of the same config and seed must agree on: the log's data
// messages (sample, command, controller) with their wall-clock utime cleared,
// re-encoded. Timing and driver-status messages are left out: they carry
// wall-clock measurements and are published on wall-clock intervals.
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <stdexcept>
#include <string>
#include <vector>

#include "rigctl/command_t.hpp"
#include "rigctl/controller_t.hpp"
#include "rigctl/sample_t.hpp"

namespace rigctl::test {

template <typename Msg>
void append_normalised(const lcm::LogEvent& e, std::vector<std::string>& out) {
  Msg m;
  if (m.decode(e.data, 0, e.datalen) < 0) throw std::runtime_error("cannot decode " + e.channel);
  m.utime = 0;
  std::string bytes(static_cast<std::size_t>(m.getEncodedSize()), '\0');
  m.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  out.push_back(e.channel + ":" + bytes);
}

inline std::vector<std::string> data_messages(const std::string& log_path) {
  lcm::LogFile log(log_path, "r");
  if (!log.good()) throw std::runtime_error("cannot open LCM log " + log_path);
  std::vector<std::string> out;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel == "RIGCTL_SAMPLE") append_normalised<rigctl::sample_t>(*e, out);
    if (e->channel == "RIGCTL_COMMAND") append_normalised<rigctl::command_t>(*e, out);
    if (e->channel == "RIGCTL_CONTROLLER") append_normalised<rigctl::controller_t>(*e, out);
  }
  return out;
}

}  // namespace rigctl::test
