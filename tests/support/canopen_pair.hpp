// The CANopen valve client (drivers/canopen/canopen_valve.hpp) against the
// simulated valve node (drivers/sim/sim_canopen_valve.hpp) over
// socketpair(AF_UNIX, SOCK_SEQPACKET) or a seqpacket socket path, for the
// unit tests in tests/unit/drivers/test_canopen_*.cpp. This kernel has no
// CAN; the transport carries the same struct can_frame records.
//
// Robust on a loaded 2-core machine: conditions are polled with generous
// deadlines, time bounds are asserted from the recorded timestamps (never
// "this took less than x ms of wall time"), a timeout under test fires
// against a peer that cannot answer in time whatever the scheduler does,
// and every other timeout is long enough that a thread left waiting for a
// CPU does not trip it.
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "drivers/canopen/can_transport.hpp"
#include "drivers/canopen/canopen_valve.hpp"
#include "drivers/sim/sim_canopen_valve.hpp"
#include "wait_until.hpp"

namespace rigctl::test {

constexpr int64_t kMs = 1'000'000;

inline int64_t now_ns() { return CanopenValve::clock_ns(); }

inline bool wait_for(const std::function<bool()>& cond, double timeout_s = 30.0) { return wait_until(cond, timeout_s); }

struct TempDir {
  std::string path;
  TempDir() {
    char templ[] = "/tmp/rigctl-can-XXXXXX";
    const char* p = mkdtemp(templ);
    path = p ? p : "/tmp";
  }
  ~TempDir() { std::filesystem::remove_all(path); }
  std::string socket() const { return path + "/valve.sock"; }
};

// Generous times: the tests of a timeout set their own tighter ones. The
// client sets up the PDOs itself; the one start-up write left is the
// device mode, as in the shipped config.
inline CanopenValveConfig client_config() {
  CanopenValveConfig c;
  c.node_id = 1;
  c.master_node_id = 127;
  c.heartbeat_timeout_s = 1.0;
  c.heartbeat_period_s = 0.05;
  c.valve_heartbeat_period_s = 0.05;
  c.valve_consumer_time_s = 1.0;
  c.sdo_timeout_s = 1.0;
  c.startup_timeout_s = 10.0;
  c.device_state_timeout_s = 5.0;
  c.actual_max_age_s = 0.5;
  c.actual_period_s = 0.002;
  c.setpoint_timeout_s = 1.0;
  c.startup_sdo = {{"device_mode", 0x6042, 0, 1, 1}};
  return c;
}

inline SimCanopenValveConfig sim_config() {
  SimCanopenValveConfig s;
  s.node_id = 1;
  s.spool_time_constant_s = 0.004;
  s.tpdo_period_s = 0.002;
  return s;
}

// Client and simulated node over a socketpair, started.
struct Pair {
  std::unique_ptr<SimCanopenValve> sim;
  CanopenValve valve;
  explicit Pair(CanopenValveConfig c = client_config(), SimCanopenValveConfig s = sim_config()) : valve(std::move(c)) {
    auto [a, b] = socketpair_seqpacket();
    sim = std::make_unique<SimCanopenValve>(std::move(b), s);
    valve.start(std::move(a));
  }
};

// start() against a fresh node with `s`: the error it throws ("" if none).
inline std::string start_error(CanopenValve& valve, const SimCanopenValveConfig& s,
                               std::unique_ptr<SimCanopenValve>* keep = nullptr) {
  auto [a, b] = socketpair_seqpacket();
  auto sim = std::make_unique<SimCanopenValve>(std::move(b), s);
  std::string error;
  try {
    valve.start(std::move(a));
  } catch (const std::runtime_error& e) {
    error = e.what();
  }
  if (keep) *keep = std::move(sim);
  return error;
}

inline Sample read(const CanopenValve& v, std::size_t first = 0) {
  Sample s;
  v.read_actual(s, first, now_ns());
  return s;
}
inline bool valid(const CanopenValve& v) { return (read(v).status & 1U) == 0; }
inline bool flagged(const CanopenValve& v) { return !valid(v); }

// Collects diagnostics (which drain events) so tests can look at both.
struct Diag {
  explicit Diag(CanopenValve& v) : valve(v) {}
  CanopenValve& valve;
  std::vector<std::string> events;
  DriverDiagnostics last;
  void refresh() {
    last = valve.diagnostics();
    events.insert(events.end(), last.events.begin(), last.events.end());
  }
  int64_t counter(const std::string& name) {
    refresh();
    for (const auto& [n, v] : last.counters) {
      if (n == name) return v;
    }
    ADD_FAILURE() << "no counter " << name;
    return -1;
  }
  bool has_event(const std::vector<std::string>& fragments) {
    refresh();
    for (const auto& e : events) {
      bool all = true;
      for (const auto& f : fragments) all = all && e.find(f) != std::string::npos;
      if (all) return true;
    }
    return false;
  }
  std::string dump() const {
    std::string s;
    for (const auto& e : events) s += "  " + e + "\n";
    return s;
  }
};

// Keeps writing a setpoint every 2 ms (as the loop would) until `cond`.
inline bool drive_until(CanopenValve& v, double setpoint, const std::function<bool()>& cond, double timeout_s = 30.0) {
  return wait_for(
      [&] {
        v.write_setpoint(setpoint);
        return cond();
      },
      timeout_s);
}

}  // namespace rigctl::test
