// What the Foxglove tests check about the JSON messages a client received:
// each one is the run log's sample of its tick, field by field (the
// run-file column names, the same doubles).
#pragma once

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <map>
#include <string>

#include <nlohmann/json.hpp>

#include "rigctl/sample_t.hpp"

namespace rigctl::test {

inline std::map<int64_t, rigctl::sample_t> samples_by_tick(const std::string& log_path, const std::string& channel = "RIGCTL_SAMPLE") {
  lcm::LogFile log(log_path, "r");
  std::map<int64_t, rigctl::sample_t> out;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != channel) continue;
    rigctl::sample_t s;
    if (s.decode(e->data, 0, e->datalen) >= 0) out[s.tick] = s;
  }
  return out;
}

// Every message is the log's sample of the same tick; returns how many were compared.
inline int expect_samples_match_log(const nlohmann::json& messages, const std::map<int64_t, rigctl::sample_t>& log) {
  int compared = 0;
  for (const auto& m : messages) {
    const int64_t tick = m.at("tick").get<int64_t>();
    const auto it = log.find(tick);
    if (it == log.end()) {
      ADD_FAILURE() << "tick " << tick << " received but not in the run log";
      continue;
    }
    const rigctl::sample_t& s = it->second;
    EXPECT_EQ(m.at("t").get<double>(), s.t) << "tick " << tick;
    for (std::size_t i = 0; i < s.names.size(); ++i) {
      if (!m.contains(s.names[i])) {
        ADD_FAILURE() << "tick " << tick << " has no field " << s.names[i];
        continue;
      }
      EXPECT_EQ(m.at(s.names[i]).get<double>(), s.values[i]) << "tick " << tick << " " << s.names[i];
    }
    ++compared;
  }
  return compared;
}

}  // namespace rigctl::test
