// The CANopen servovalve I/O end to end: CanopenValve (client) against
// SimCanopenValve (node) over socketpair(AF_UNIX, SOCK_SEQPACKET) and over a
// seqpacket socket path, the frame transport itself, the SocketCAN error
// path, and the `canopen:` config reader. This kernel has no CAN, so nothing
// here touches a CAN_RAW socket beyond its failure.
//
// Robust on a loaded 2-core machine: conditions are polled with generous
// deadlines, time bounds are asserted from the recorded timestamps (never
// "this took less than x ms of wall time"), a timeout under test fires
// against a peer that cannot answer in time whatever the scheduler does,
// and every other timeout is long enough that a thread left waiting for a
// CPU does not trip it.
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <string>
#include <thread>
#include <vector>

#include "config/canopen_reader.hpp"
#include "drivers/canopen/can_transport.hpp"
#include "drivers/canopen/protocol/cia408.hpp"
#include "drivers/canopen/protocol/cob_id.hpp"
#include "drivers/canopen/protocol/emcy.hpp"
#include "drivers/canopen/protocol/nmt.hpp"
#include "drivers/canopen/protocol/sdo.hpp"
#include "drivers/canopen/canopen_valve.hpp"
#include "drivers/sim/sim_canopen_valve.hpp"
#include "drivers/canopen/socketcan.hpp"

using namespace rigctl;
using canopen::CanFrame;
using canopen::make_frame;
using canopen::NmtState;

namespace {

constexpr int64_t kMs = 1'000'000;

int64_t now_ns() { return CanopenValve::clock_ns(); }

// Polls `cond` every 2 ms until it holds or `timeout_s` passes (a deadline
// only reached when the test fails).
bool wait_for(const std::function<bool()>& cond, double timeout_s = 30.0) {
  const int64_t deadline = now_ns() + static_cast<int64_t>(timeout_s * 1e9);
  while (!cond()) {
    if (now_ns() > deadline) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

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

// Generous times: the tests of a timeout set their own tighter ones.
CanopenValveConfig client_config() {
  CanopenValveConfig c;
  c.node_id = 1;
  c.master_node_id = 127;
  c.heartbeat_timeout_s = 1.0;
  c.heartbeat_period_s = 0.05;
  c.valve_heartbeat_period_s = 0.05;
  c.valve_consumer_time_s = 1.0;
  c.sdo_timeout_s = 1.0;
  c.startup_timeout_s = 10.0;
  c.actual_max_age_s = 0.5;
  c.startup_sdo = {{"device_mode", 0x6042, 0, 1, 1},
                   {"control_word", 0x6040, 0, 2, 0x0007},
                   {"tpdo1_transmission_type", 0x1800, 2, 1, 255},  // as for a real valve: event-driven TPDO
                   {"tpdo1_event_timer_ms", 0x1800, 5, 2, 2}};
  return c;
}

SimCanopenValveConfig sim_config() {
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

Sample read(const CanopenValve& v, std::size_t first = 0) {
  Sample s;
  v.read_actual(s, first, now_ns());
  return s;
}
bool valid(const CanopenValve& v) { return (read(v).status & 1U) == 0; }
bool flagged(const CanopenValve& v) { return !valid(v); }

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
bool drive_until(CanopenValve& v, double setpoint, const std::function<bool()>& cond, double timeout_s = 30.0) {
  return wait_for([&] {
    v.write_setpoint(setpoint);
    return cond();
  }, timeout_s);
}

}  // namespace

// ---------------------------------------------------------------- transport

TEST(CanTransport, SocketpairKeepsOneFramePerRecordAndSeesHangUp) {
  auto [a, b] = socketpair_seqpacket();
  const CanFrame f1 = make_frame(0x181, {1, 2, 3});
  const CanFrame f2 = make_frame(0x701, {5});
  ASSERT_TRUE(b.send(f1));
  ASSERT_TRUE(b.send(f2));
  CanFrame got;
  ASSERT_EQ(a.receive(got, 1000), CanTransport::Rx::kFrame);
  EXPECT_EQ(got.can_id, 0x181U);
  EXPECT_EQ(got.len, 3);
  EXPECT_EQ(got.data[2], 3);
  ASSERT_EQ(a.receive(got, 1000), CanTransport::Rx::kFrame);
  EXPECT_EQ(got.can_id, 0x701U);
  EXPECT_EQ(a.receive(got, 10), CanTransport::Rx::kTimeout);
  EXPECT_EQ(a.counters().rx, 2U);

  b.close();
  EXPECT_EQ(a.receive(got, 1000), CanTransport::Rx::kHangUp);
  EXPECT_FALSE(a.send(f1));  // EPIPE, and no SIGPIPE killing the test
  EXPECT_EQ(a.counters().tx_errors, 1U);
}

TEST(CanTransport, FullBufferDropsTheFrameInsteadOfBlocking) {
  auto [a, b] = socketpair_seqpacket();
  int sent = 0;
  bool dropped = false;
  for (int i = 0; i < 1'000'000 && !dropped; ++i) {
    if (a.send(make_frame(0x201, {0, 0, 0, 0}))) {
      ++sent;
    } else {
      dropped = true;
    }
  }
  EXPECT_TRUE(dropped) << "never full after " << sent << " frames";
  EXPECT_GT(sent, 0);
  EXPECT_EQ(a.counters().tx_dropped, 1U);
  EXPECT_EQ(a.counters().tx_errors, 0U);
}

TEST(CanTransport, RecordOfTheWrongSizeIsCountedAndDropped) {
  auto [a, b] = socketpair_seqpacket();
  const unsigned char five[5] = {1, 2, 3, 4, 5};
  ASSERT_EQ(::send(b.fd(), five, sizeof five, 0), 5);
  ASSERT_TRUE(b.send(make_frame(0x701, {5})));
  CanFrame got;
  EXPECT_EQ(a.receive(got, 1000), CanTransport::Rx::kBadSize);
  EXPECT_EQ(a.receive(got, 1000), CanTransport::Rx::kFrame);
  EXPECT_EQ(a.counters().rx_bad_size, 1U);
  EXPECT_EQ(a.counters().rx, 1U);
}

TEST(CanTransport, ListenerAcceptsAndConnectNamesAMissingPath) {
  TempDir dir;
  SeqpacketListener listener = listen_seqpacket(dir.socket());
  CanTransport client = connect_seqpacket(dir.socket());
  auto server = listener.accept(5000);
  ASSERT_TRUE(server.has_value());
  ASSERT_TRUE(client.send(make_frame(0x000, {1, 1})));
  CanFrame got;
  ASSERT_EQ(server->receive(got, 1000), CanTransport::Rx::kFrame);
  EXPECT_EQ(got.len, 2);

  try {
    connect_seqpacket(dir.path + "/nobody.sock");
    FAIL() << "connect to a missing socket succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nobody.sock"), std::string::npos) << e.what();
  }
}

TEST(SocketCan, OpenFailsCleanlyNamingTheInterface) {
  const int probe = ::socket(PF_CAN, SOCK_RAW, 1 /* CAN_RAW */);
  const int probe_errno = errno;
  if (probe >= 0) ::close(probe);
  const uint32_t ids[] = {0x181, 0x081, 0x581, 0x701};
  try {
    CanTransport t = open_socketcan("can0", ids);
    GTEST_SKIP() << "this machine has a working can0; only the failure path is tested here";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("'can0'"), std::string::npos) << msg;
    if (probe < 0 && probe_errno == EAFNOSUPPORT) {
      EXPECT_NE(msg.find("AF_CAN"), std::string::npos) << msg;
    }
  }
}

TEST(SocketCan, ValveConfiguredForCan0FailsToStartNamingIt) {
  CanopenValveConfig c = client_config();
  c.interface = "can0";
  CanopenValve valve(c);
  try {
    valve.start();
    GTEST_SKIP() << "a valve answered on can0";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("can0"), std::string::npos) << msg;
    EXPECT_NE(msg.find("node 1"), std::string::npos) << msg;
  }
  EXPECT_FALSE(valve.running());
}

// ---------------------------------------------------------------- start-up

TEST(CanopenValve, StartUpConfiguresTheValveAndReachesOperational) {
  Pair p;
  EXPECT_TRUE(p.valve.running());
  EXPECT_EQ(p.sim->nmt_state(), NmtState::kOperational);
  EXPECT_EQ(p.valve.valve_nmt_state(), NmtState::kOperational);
  // The start-up writes landed in the node's dictionary.
  EXPECT_EQ(p.sim->od_value(0x6042, 0), 1U);
  EXPECT_EQ(p.sim->od_value(0x6040, 0), 0x0007U);
  EXPECT_EQ(p.sim->od_value(0x1017, 0), 50U);
  EXPECT_EQ(p.sim->od_value(0x1016, 1), canopen::consumer_heartbeat_entry(127, 1000));
  EXPECT_EQ(p.sim->od_value(0x1800, 5), 2U);
  EXPECT_EQ(p.sim->stats().sdo_writes, 6U);
  const ValveIdentity id = p.valve.identity();
  EXPECT_EQ(id.device_type & 0xFFFF, 408U);
  EXPECT_EQ(id.product_code, 0x0408U);
  EXPECT_EQ(id.serial, 1U);
  EXPECT_GE(p.sim->stats().nmt_commands, 2U);  // reset communication, start
  EXPECT_TRUE(wait_for([&] { return p.valve.healthy(now_ns()); })) << "faults " << p.valve.faults();
  Diag d(p.valve);
  EXPECT_TRUE(d.has_event({"started", "operational"})) << d.dump();
  EXPECT_TRUE(d.has_event({"identity: device type 0x00000198", "serial 0x00000001"})) << d.dump();
  EXPECT_EQ(d.counter("canopen_sdo_aborts"), 0);
}

TEST(CanopenValve, SetpointMovesTheSpoolAndTheActualValueComesBackInSI) {
  TempDir dir;
  SimCanopenValve sim(dir.socket(), sim_config());
  CanopenValveConfig c = client_config();
  c.socket_path = dir.socket();
  CanopenValve valve(c);
  valve.start();

  auto settled_at = [&](double x) {
    const Sample s = read(valve);
    return std::fabs(sim.spool() - x) < 1e-3 && (s.status & 1U) == 0 && std::fabs(s.value[0] - x) < 2e-3;
  };
  EXPECT_TRUE(drive_until(valve, 0.5, [&] { return settled_at(0.5); })) << "spool " << sim.spool();
  EXPECT_EQ(sim.od_value(0x6300, 1), 8192U);  // 0.5 * 16384 counts
  EXPECT_TRUE(drive_until(valve, -0.25, [&] { return settled_at(-0.25); })) << "spool " << sim.spool();
  // NaN is the null command; beyond rated opening is clamped to it.
  EXPECT_TRUE(drive_until(valve, std::nan(""), [&] { return settled_at(0.0); })) << "spool " << sim.spool();
  EXPECT_TRUE(drive_until(valve, 1.7, [&] { return settled_at(1.0); })) << "spool " << sim.spool();
  EXPECT_EQ(sim.od_value(0x6300, 1), 16384U);

  // read_actual writes at the index it is given and flags only its own bits.
  Sample s;
  s.status = 0;
  valve.read_actual(s, 5, now_ns());
  EXPECT_NEAR(s.value[5], 1.0, 2e-3);
  EXPECT_EQ(s.status, 0U);
  // A time on another clock than CLOCK_MONOTONIC cannot look fresh.
  valve.read_actual(s, 5, 12345);
  EXPECT_EQ(s.status, 1U << 5);
  valve.stop();
}

TEST(CanopenValve, PressureIsReadInPascal) {
  CanopenValveConfig c = client_config();
  c.pressure_input = "p_v";
  c.pressure_scale_pa = 1000.0;
  SimCanopenValveConfig s = sim_config();
  s.with_pressure = true;
  s.pressure_scale_pa = 1000.0;
  Pair p(c, s);
  const auto channels = p.valve.input_channels();
  ASSERT_EQ(channels.size(), 2U);
  EXPECT_EQ(channels[0].name, "x_s");
  EXPECT_EQ(channels[1].name, "p_v");
  EXPECT_EQ(channels[1].unit, "Pa");
  p.sim->set_pressure(21.0e6);
  EXPECT_TRUE(wait_for([&] {
    const Sample smp = read(p.valve, 2);
    return (smp.status & (3U << 2)) == 0 && std::fabs(smp.value[3] - 21.0e6) <= 1000.0;
  }));
}

TEST(CanopenValve, SdoAbortAtStartUpNamesTheObjectAndTheAbortText) {
  struct Case {
    SdoWrite write;
    std::string address;
    std::string text;
  };
  const std::vector<Case> cases = {
      {{"vendor_gain", 0x2000, 0, 2, 5}, "0x2000:00", "object does not exist in the object dictionary"},
      {{"status_word", 0x6041, 0, 2, 1}, "0x6041:00", "attempt to write a read-only object"},
      {{"device_mode", 0x6042, 0, 2, 1}, "0x6042:00", "length of service parameter does not match"},
      {{"setpoint", 0x6300, 7, 2, 1}, "0x6300:07", "sub-index does not exist"},
  };
  for (const auto& k : cases) {
    CanopenValveConfig c = client_config();
    c.startup_sdo.push_back(k.write);
    CanopenValve valve(c);
    auto [a, b] = socketpair_seqpacket();
    SimCanopenValve sim(std::move(b), sim_config());
    try {
      valve.start(std::move(a));
      ADD_FAILURE() << k.address << ": start() succeeded";
    } catch (const std::runtime_error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(k.address), std::string::npos) << msg;
      EXPECT_NE(msg.find(k.text), std::string::npos) << msg;
      EXPECT_NE(msg.find("'" + k.write.name + "'"), std::string::npos) << msg;
      EXPECT_NE(msg.find("node 1"), std::string::npos) << msg;
    }
    EXPECT_FALSE(valve.running());
    EXPECT_NE(sim.nmt_state(), NmtState::kOperational);  // NMT start never sent
    Diag d(valve);
    EXPECT_EQ(d.counter("canopen_sdo_aborts"), 1);
    EXPECT_TRUE(d.has_event({k.address, k.text})) << d.dump();
    Sample s;
    valve.read_actual(s, 0, now_ns());
    EXPECT_EQ(s.status, 1U);
  }
}

TEST(CanopenValve, LateSdoAnswerTimesOutNamingTheObject) {
  CanopenValveConfig c = client_config();
  c.reset_on_start = false;
  c.sdo_timeout_s = 0.2;
  CanopenValve valve(c);
  auto [a, b] = socketpair_seqpacket();
  SimCanopenValve sim(std::move(b), sim_config());
  // Later than the test lasts: the 0.2 s timeout fires however late this
  // thread gets to check it.
  sim.set_response_delay(600.0);
  try {
    valve.start(std::move(a));
    FAIL() << "start() succeeded";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("0x1000:00"), std::string::npos) << msg;  // the first SDO: reading the device type
    EXPECT_NE(msg.find("SDO protocol timed out"), std::string::npos) << msg;
  }
}

TEST(CanopenValve, StartFailsClearlyWhenNothingAnswers) {
  CanopenValveConfig c = client_config();
  c.startup_timeout_s = 0.3;
  CanopenValve valve(c);
  auto [a, b] = socketpair_seqpacket();  // b is kept open but never answers
  try {
    valve.start(std::move(a));
    FAIL() << "start() succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("boot-up"), std::string::npos) << e.what();
  }
  TempDir dir;
  c.socket_path = dir.socket();
  CanopenValve nobody(c);
  try {
    nobody.start();
    FAIL() << "start() succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(dir.socket()), std::string::npos) << e.what();
  }
}

TEST(CanopenValve, StartWaitsForTheFirstActualValueAndNamesTheTpdoWhenNoneComes) {
  CanopenValveConfig c = client_config();
  c.actual_tpdo = 2;  // the node sends its actual value on TPDO1
  // The whole start-up runs against this deadline (it always expires here):
  // long enough for the SDO exchange before the TPDO wait on a loaded machine.
  c.startup_timeout_s = 3.0;
  CanopenValve valve(c);
  auto [a, b] = socketpair_seqpacket();
  SimCanopenValve sim(std::move(b), sim_config());
  try {
    valve.start(std::move(a));
    FAIL() << "start() succeeded";
  } catch (const std::runtime_error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("TPDO2, COB-ID 0x281"), std::string::npos) << msg;
  }
  EXPECT_FALSE(valve.running());
}

TEST(CanopenValve, RealTimeApiIsHarmlessBeforeStart) {
  CanopenValve valve(client_config());
  valve.write_setpoint(0.5);
  valve.make_safe();
  Sample s;
  valve.read_actual(s, 0, now_ns());
  EXPECT_EQ(s.status, 1U);
  EXPECT_FALSE(valve.healthy(now_ns()));
  valve.stop();
}

// ---------------------------------------------------------------- faults seen by the client

TEST(CanopenValve, LostValveHeartbeatFlagsTheInputsAfterTheTimeoutAndLatches) {
  // Timeout 1 s (client_config): a node thread that waits for a CPU must not
  // lose a heartbeat before the one this test suppresses. Suppressed for
  // 3 s: the I/O thread has two seconds to see the timeout and latch it.
  CanopenValveConfig c = client_config();
  c.valve_heartbeat_period_s = 0.02;
  Pair p(c);
  ASSERT_TRUE(wait_for([&] { return valid(p.valve); }));

  p.sim->miss_heartbeats(3.0);
  int64_t flagged_at = 0;
  ASSERT_TRUE(wait_for([&] {
    const int64_t now = now_ns();
    Sample s;
    p.valve.read_actual(s, 0, now);
    if (s.status & 1U) flagged_at = now;
    return flagged_at != 0;
  }));
  // Heartbeats are suppressed, so the last one is fixed now. Never flagged
  // early; how late is this thread's polling (the exact bound is the next
  // test's, on given times).
  const int64_t last = p.valve.last_valve_heartbeat_ns();
  const int64_t timeout = 1000 * kMs;
  EXPECT_GT(flagged_at - last, timeout) << "flagged before the heartbeat timeout";
  EXPECT_FALSE(p.valve.healthy(last + timeout + 1));

  Diag d(p.valve);
  EXPECT_TRUE(wait_for([&] { return d.counter("canopen_heartbeat_timeouts") == 1; }));
  EXPECT_TRUE(d.has_event({"heartbeat lost", "timeout 1000.0 ms"})) << d.dump();
  EXPECT_TRUE(p.valve.faults() & CanopenValve::kFaultHeartbeatLost);

  // Heartbeats come back; the fault stays until a restart.
  ASSERT_TRUE(wait_for([&] { return p.valve.last_valve_heartbeat_ns() != last; }));
  EXPECT_TRUE(flagged(p.valve));
  EXPECT_TRUE(wait_for([&] { return d.has_event({"heartbeat back"}); })) << d.dump();
  p.valve.stop();
  p.valve.start([&] {
    auto [a, b] = socketpair_seqpacket();
    p.sim = std::make_unique<SimCanopenValve>(std::move(b), sim_config());
    return std::move(a);
  }());
  EXPECT_TRUE(wait_for([&] { return valid(p.valve); })) << "faults " << p.valve.faults();
}

// The real-time checks on the loop's clock, at their exact bounds: with the
// valve healthy, a time just past the heartbeat timeout (or the actual
// value's maximum age) must flag, a time just inside must not.
TEST(CanopenValve, RealTimeChecksFlagExactlyPastTheHeartbeatTimeoutAndTheMaximumAge) {
  CanopenValveConfig c = client_config();  // heartbeat timeout 1 s: no heartbeat lost by a late thread
  c.valve_heartbeat_period_s = 0.02;
  c.actual_max_age_s = 2.0;  // longer than the heartbeat timeout: only the heartbeat decides
  Pair p(c);
  ASSERT_TRUE(wait_for([&] { return valid(p.valve); }));
  const int64_t timeout = 1000 * kMs;
  bool checked = false;
  for (int attempt = 0; attempt < 100 && !checked; ++attempt) {
    const int64_t hb = p.valve.last_valve_heartbeat_ns();
    const bool inside = p.valve.healthy(hb + timeout);
    const bool past = p.valve.healthy(hb + timeout + 1);
    if (p.valve.last_valve_heartbeat_ns() != hb) continue;  // a heartbeat came in between: again
    EXPECT_TRUE(inside) << "faults " << p.valve.faults();
    EXPECT_FALSE(past);
    checked = true;
  }
  EXPECT_TRUE(checked);

  CanopenValveConfig c2 = client_config();  // heartbeat timeout 1 s, maximum age 0.5 s
  Pair q(c2);
  ASSERT_TRUE(wait_for([&] { return valid(q.valve); }));
  const int64_t max_age = 500 * kMs;
  checked = false;
  for (int attempt = 0; attempt < 100 && !checked; ++attempt) {
    const ValveActual a = q.valve.latest_actual();
    const int64_t hb = q.valve.last_valve_heartbeat_ns();
    Sample inside, past;
    q.valve.read_actual(inside, 0, a.rx_ns + max_age);
    q.valve.read_actual(past, 0, a.rx_ns + max_age + 1);
    if (q.valve.latest_actual().count != a.count || a.rx_ns + max_age + 1 - hb > 1000 * kMs) continue;
    EXPECT_EQ(inside.status, 0U);
    EXPECT_EQ(past.status, 1U);
    checked = true;
  }
  EXPECT_TRUE(checked);
}

TEST(CanopenValve, SilentValveIsFlagged) {
  Pair p;
  ASSERT_TRUE(wait_for([&] { return valid(p.valve); }));
  p.sim->set_silent(true);
  EXPECT_TRUE(wait_for([&] { return flagged(p.valve); }));
  Diag d(p.valve);
  EXPECT_TRUE(wait_for([&] { return d.counter("canopen_heartbeat_timeouts") == 1; })) << d.dump();
}

TEST(CanopenValve, LateValveFramesMakeTheActualStaleUntilTheyFlowAgain) {
  CanopenValveConfig c = client_config();
  c.heartbeat_timeout_s = 3.0;  // the test is about the actual value's age, not the heartbeat
  c.actual_max_age_s = 0.1;
  Pair p(c);
  ASSERT_TRUE(wait_for([&] { return valid(p.valve); }));
  p.sim->set_response_delay(0.6);  // a 0.6 s gap, then the (late) stream resumes
  EXPECT_TRUE(wait_for([&] { return flagged(p.valve); }));
  EXPECT_EQ(p.valve.faults(), 0U) << "staleness is not a latched fault";
  EXPECT_TRUE(wait_for([&] { return valid(p.valve); }));
}

TEST(CanopenValve, EmcyIsDecodedAndFlagsTheInputsWhileTheErrorRegisterIsSet) {
  Pair p;
  ASSERT_TRUE(wait_for([&] { return valid(p.valve); }));
  p.sim->send_emcy(0x2310, canopen::error_register::kGeneric | canopen::error_register::kCurrent);
  EXPECT_TRUE(wait_for([&] { return flagged(p.valve); }));
  EXPECT_TRUE(p.valve.faults() & CanopenValve::kFaultEmcy);
  Diag d(p.valve);
  EXPECT_TRUE(wait_for([&] { return d.has_event({"EMCY 0x2310", "(current)", "error register 0x03", "generic, current"}); }))
      << d.dump();
  EXPECT_EQ(d.counter("canopen_emcy"), 1);

  p.sim->send_emcy(0x0000, 0x00);  // error reset
  EXPECT_TRUE(wait_for([&] { return valid(p.valve); })) << "faults " << p.valve.faults();
  EXPECT_TRUE(wait_for([&] { return d.has_event({"EMCY 0x0000", "no error active"}); })) << d.dump();
}

TEST(CanopenValve, MalformedFramesAreCountedAndIgnored) {
  Pair p;
  ASSERT_TRUE(wait_for([&] { return valid(p.valve); }));
  Diag d(p.valve);
  const int64_t ignored_before = d.counter("canopen_frames_ignored");
  CanFrame rtr = make_frame(0x181, {});
  rtr.can_id |= canopen::kCanRtrFlag;
  CanFrame nine = make_frame(0x181, {9, 0, 0, 0});
  nine.len = 9;
  p.sim->send_raw(make_frame(0x701, {0x05, 0x00}));         // heartbeat of 2 bytes: wrong length
  p.sim->send_raw(make_frame(0x081, {1, 2, 3}));            // EMCY of 3 bytes: wrong length
  p.sim->send_raw(nine);                                    // len 9: wrong length
  p.sim->send_raw(make_frame(0x681, {1, 2}));               // COB-ID outside the connection set
  p.sim->send_raw(make_frame(0x181, {0x09, 0x00}));         // actual-value TPDO of 2 bytes, mapping has 4
  p.sim->send_raw(rtr);                                     // remote frame
  p.sim->send_raw(make_frame(0x701, {0x33}));               // heartbeat with an undefined state
  p.sim->send_raw(canopen::sdo_abort(0x581, 0x6042, 0, 0)); // SDO answer with no transfer pending
  p.sim->send_raw_record({1, 2, 3, 4, 5});                  // not a CAN frame at all
  p.sim->send_raw(make_frame(0x705, {0x05}));               // heartbeat of another node: valid, not ours

  // The last frame sent is the other node's heartbeat: once it is counted
  // as ignored, every frame before it has been handled (one connection, in
  // order), so the counts below are final.
  ASSERT_TRUE(wait_for([&] { return d.counter("canopen_frames_ignored") > ignored_before; })) << d.dump();
  EXPECT_EQ(d.counter("canopen_malformed_frames"), 9);
  EXPECT_EQ(d.counter("canopen_malformed_wrong_length"), 3);
  EXPECT_EQ(d.counter("canopen_malformed_unknown_cob_id"), 1);
  EXPECT_EQ(d.counter("canopen_malformed_bad_pdo_length"), 1);
  EXPECT_EQ(d.counter("canopen_malformed_not_data_frame"), 1);
  EXPECT_EQ(d.counter("canopen_malformed_bad_content"), 1);
  EXPECT_EQ(d.counter("canopen_malformed_unexpected_sdo"), 1);
  EXPECT_EQ(d.counter("canopen_malformed_bad_record_size"), 1);
  EXPECT_GE(d.counter("canopen_frames_ignored"), 1);
  EXPECT_TRUE(d.has_event({"malformed frame dropped", "wrong length"})) << d.dump();

  // Still working: fresh actual values keep coming and nothing is flagged.
  const uint64_t before = p.valve.latest_actual().count;
  EXPECT_TRUE(wait_for([&] { return p.valve.latest_actual().count > before + 10; }));
  EXPECT_TRUE(valid(p.valve)) << "faults " << p.valve.faults();
  EXPECT_EQ(p.valve.faults(), 0U);
}

TEST(CanopenValve, DroppedConnectionFlagsTheInputsWithoutCrashingAndAllowsARestart) {
  TempDir dir;
  SimCanopenValve sim(dir.socket(), sim_config());
  CanopenValveConfig c = client_config();
  c.socket_path = dir.socket();
  CanopenValve valve(c);
  valve.start();
  ASSERT_TRUE(wait_for([&] { return valid(valve); }));

  sim.drop_connection();
  EXPECT_TRUE(wait_for([&] { return flagged(valve); }));
  EXPECT_TRUE(wait_for([&] { return (valve.faults() & CanopenValve::kFaultLinkLost) != 0; }));
  for (int i = 0; i < 100; ++i) valve.write_setpoint(0.3);  // the loop keeps running: no crash, no block
  Diag d(valve);
  EXPECT_TRUE(d.has_event({"connection lost"})) << d.dump();
  EXPECT_EQ(d.counter("canopen_link_lost"), 1);
  EXPECT_GE(d.counter("canopen_tx_errors"), 100);
  valve.stop();

  // The node serves the next connection as a fresh power-on.
  valve.start();
  EXPECT_TRUE(wait_for([&] { return valid(valve); })) << "faults " << valve.faults();
  EXPECT_EQ(sim.stats().connections, 2U);
  valve.stop();
}

TEST(CanopenValve, ValveResetWhileOperationalIsDetected) {
  Pair p;
  ASSERT_TRUE(wait_for([&] { return valid(p.valve); }));
  p.sim->reset_node();
  EXPECT_TRUE(wait_for([&] { return (p.valve.faults() & CanopenValve::kFaultValveReset) != 0; }));
  EXPECT_TRUE(flagged(p.valve));
  Diag d(p.valve);
  EXPECT_TRUE(d.has_event({"valve reset"})) << d.dump();
  EXPECT_EQ(d.counter("canopen_valve_resets"), 1);
}

TEST(CanopenValve, StopNullsTheSpoolAndLeavesTheValvePreOperational) {
  Pair p;
  ASSERT_TRUE(drive_until(p.valve, 0.5, [&] { return std::fabs(p.sim->spool() - 0.5) < 1e-3; }));
  p.valve.stop();
  EXPECT_FALSE(p.valve.running());
  EXPECT_TRUE(wait_for([&] { return std::fabs(p.sim->spool()) < 1e-3; })) << p.sim->spool();
  EXPECT_EQ(p.sim->od_value(0x6300, 1), 0U);
  EXPECT_TRUE(wait_for([&] { return p.sim->nmt_state() == NmtState::kPreOperational || !p.sim->connected(); }));
}

// ---------------------------------------------------------------- the node's own fail-safe

namespace {
// A bare master over the socketpair: what the node sees when the client
// process dies or hangs.
struct RawMaster {
  CanTransport t;
  std::vector<CanFrame> received;
  // Collects frames until one matches, or the timeout.
  bool expect(const std::function<bool(const CanFrame&)>& match, double timeout_s = 30.0) {
    const int64_t deadline = now_ns() + static_cast<int64_t>(timeout_s * 1e9);
    while (now_ns() < deadline) {
      CanFrame f;
      if (t.receive(f, 10) == CanTransport::Rx::kFrame) {
        received.push_back(f);
        if (match(f)) return true;
      }
    }
    return false;
  }
  bool sdo_write(uint16_t index, uint8_t sub, uint32_t value, uint8_t size) {
    t.send(canopen::sdo_download_request(1, index, sub, value, size));
    return expect([](const CanFrame& f) { return f.id() == 0x581 && f.data[0] == canopen::sdo::kDownloadResponse; });
  }
  void drain() {
    CanFrame f;
    while (t.receive(f, 0) == CanTransport::Rx::kFrame) received.push_back(f);
  }
};
}  // namespace

TEST(SimCanopenValve, LostMasterHeartbeatPutsTheSpoolToNullAfterItsConsumerTime) {
  auto [a, b] = socketpair_seqpacket();
  SimCanopenValve sim(std::move(b), sim_config());
  RawMaster m{std::move(a), {}};
  ASSERT_TRUE(m.expect([](const CanFrame& f) { return f.id() == 0x701 && f.len == 1 && f.data[0] == 0; }))
      << "no boot-up";
  constexpr uint16_t kConsumerMs = 200;
  ASSERT_TRUE(m.sdo_write(0x1017, 0, 20, 2));  // its own heartbeat, to see its NMT state below
  ASSERT_TRUE(m.sdo_write(0x1016, 1, canopen::consumer_heartbeat_entry(127, kConsumerMs), 4));
  ASSERT_TRUE(m.sdo_write(0x6042, 0, 1, 1));
  m.t.send(canopen::encode_nmt(canopen::NmtCommand::kStart, 1));

  const CanFrame setpoint = make_frame(0x201, {0x07, 0x00, 0x00, 0x20});  // control word ACTIVE, 0x2000 = 50 %
  const CanFrame heartbeat = canopen::encode_heartbeat(127, NmtState::kOperational);
  ASSERT_TRUE(wait_for([&] {
    m.t.send(heartbeat);
    m.t.send(setpoint);
    m.drain();
    return std::fabs(sim.spool() - 0.5) < 1e-3;
  })) << "spool " << sim.spool();
  EXPECT_FALSE(sim.fail_safe());

  // The master stops its heartbeat but (wrongly) keeps commanding 50 %.
  ASSERT_TRUE(wait_for([&] {
    m.t.send(setpoint);
    m.drain();
    return std::fabs(sim.spool()) < 1e-3;
  })) << "spool " << sim.spool();
  EXPECT_TRUE(sim.fail_safe());
  const int64_t lost_after = sim.fail_safe_ns() - sim.last_master_heartbeat_ns();
  EXPECT_GT(lost_after, kConsumerMs * kMs) << "fail-safe before the consumer time";
  EXPECT_LT(lost_after, kConsumerMs * kMs + 2000 * kMs);
  EXPECT_EQ(sim.stats().master_heartbeat_losses, 1U);
  EXPECT_EQ(sim.nmt_state(), NmtState::kPreOperational);
  EXPECT_EQ(sim.od_value(0x1001, 0), 0x11U);

  // It said so: EMCY 0x8130 with the communication bit, and its TPDO status
  // word (before leaving operational) or heartbeat shows the fault.
  m.drain();
  bool emcy = false;
  for (const auto& f : m.received) {
    canopen::Emcy e;
    if (canopen::decode_emcy(f, e) == canopen::Malformed::kNone && e.error_code == 0x8130 && e.error_register == 0x11) {
      emcy = true;
    }
  }
  EXPECT_TRUE(emcy);
  EXPECT_TRUE(m.expect([](const CanFrame& f) { return f.id() == 0x701 && f.len == 1 && f.data[0] == 0x7F; }));
}

TEST(SimCanopenValve, SpoolFollowsAsAFirstOrderLag) {
  auto [a, b] = socketpair_seqpacket();
  SimCanopenValveConfig s = sim_config();
  s.spool_time_constant_s = 0.15;  // slow enough to see the lag from a test thread
  SimCanopenValve sim(std::move(b), s);
  RawMaster m{std::move(a), {}};
  ASSERT_TRUE(m.sdo_write(0x6042, 0, 1, 1));
  m.t.send(canopen::encode_nmt(canopen::NmtCommand::kStart, 1));
  ASSERT_TRUE(wait_for([&] { return sim.nmt_state() == NmtState::kOperational; }));
  const int64_t t0 = now_ns();
  m.t.send(make_frame(0x201, {0x07, 0x00, 0x00, 0x40}));  // 100 %
  ASSERT_TRUE(wait_for([&] { return sim.spool() > 0.5; }));
  const double t_half = static_cast<double>(now_ns() - t0) * 1e-9;
  // 1 - exp(-t/tau) = 0.5 at t = tau ln 2 = 0.104 s; the test thread may see it late, never early.
  EXPECT_GT(t_half, 0.15 * std::log(2.0) * 0.9);
  ASSERT_TRUE(wait_for([&] { return sim.spool() > 0.999; }));
  EXPECT_LE(sim.spool(), 1.0);
}

TEST(SimCanopenValve, IgnoresTheBusSetpointUntilConfiguredAndOperational) {
  auto [a, b] = socketpair_seqpacket();
  SimCanopenValve sim(std::move(b), sim_config());
  RawMaster m{std::move(a), {}};
  const CanFrame setpoint = make_frame(0x201, {0x07, 0x00, 0x00, 0x20});
  m.t.send(setpoint);  // pre-operational: PDOs are not processed
  m.t.send(canopen::encode_nmt(canopen::NmtCommand::kStart, 1));
  m.t.send(setpoint);  // operational, but device mode is not "setpoint via bus"
  // The node answers in order: once this SDO write (device mode unchanged,
  // 0) is answered, both setpoints have been handled. Then time for a
  // wrongly taken one to move the spool (4 ms lag): any time does, a slow
  // machine's only more.
  ASSERT_TRUE(m.sdo_write(0x6042, 0, 0, 1));
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  EXPECT_EQ(sim.spool(), 0.0);
  ASSERT_TRUE(m.sdo_write(0x6042, 0, 1, 1));
  EXPECT_TRUE(wait_for([&] {
    m.t.send(setpoint);
    m.drain();
    return sim.spool() > 0.4;
  }));
}

// ---------------------------------------------------------------- config

namespace {
const char* kCanopenYaml = R"(canopen:
  socket_path: /run/rigctl/valve.sock
  node_id: 1
  heartbeat_timeout_s: 0.05
  heartbeat_period_s: 0.02
  sdo_timeout_s: 0.1
  actual_max_age_s: 0.0075
  setpoint_output: u
  actual_input: x_s
  startup_sdo:
    device_mode: {index: 0x6042, subindex: 0, size: 1, value: 1}
    control_word: {index: 0x6040, subindex: 0, size: 2, value: 0x0007}
)";

CanopenValveConfig parse(const std::string& yaml) {
  return read_canopen_valve(ConfigReader::from_string(yaml, "test.yaml").child("canopen"));
}

std::string error_of(const std::string& yaml) {
  try {
    parse(yaml);
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

std::string replace(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  EXPECT_NE(pos, std::string::npos) << from;
  if (pos != std::string::npos) text.replace(pos, from.size(), to);
  return text;
}

void expect_error(const std::string& yaml, const std::vector<std::string>& fragments) {
  const std::string e = error_of(yaml);
  ASSERT_FALSE(e.empty()) << "config was accepted";
  for (const auto& f : fragments) EXPECT_NE(e.find(f), std::string::npos) << "'" << f << "' not in: " << e;
}
}  // namespace

TEST(CanopenConfig, ExampleParsesWithDefaults) {
  const CanopenValveConfig c = parse(kCanopenYaml);
  EXPECT_EQ(c.socket_path, "/run/rigctl/valve.sock");
  EXPECT_TRUE(c.interface.empty());
  EXPECT_EQ(c.node_id, 1);
  EXPECT_EQ(c.master_node_id, 127);
  EXPECT_DOUBLE_EQ(c.heartbeat_timeout_s, 0.05);
  EXPECT_DOUBLE_EQ(c.valve_heartbeat_period_s, 0.016);  // timeout / 3, whole ms
  EXPECT_DOUBLE_EQ(c.valve_consumer_time_s, 0.05);      // 2.5 x our period
  EXPECT_TRUE(c.reset_on_start);
  EXPECT_TRUE(c.configure_heartbeats);
  ASSERT_EQ(c.startup_sdo.size(), 2U);
  EXPECT_EQ(c.startup_sdo[0].name, "device_mode");
  EXPECT_EQ(c.startup_sdo[0].index, 0x6042);
  EXPECT_EQ(c.startup_sdo[0].size, 1);
  EXPECT_EQ(c.startup_sdo[0].value, 1U);
  EXPECT_EQ(c.startup_sdo[1].index, 0x6040);
  EXPECT_EQ(c.startup_sdo[1].value, 7U);
  EXPECT_EQ(c.actual_input, "x_s");
  EXPECT_TRUE(c.pressure_input.empty());
  EXPECT_NO_THROW(CanopenValve v(c));

  const CanopenValveConfig can = parse(replace(kCanopenYaml, "socket_path: /run/rigctl/valve.sock", "interface: can0"));
  EXPECT_EQ(can.interface, "can0");
  EXPECT_TRUE(can.socket_path.empty());
}

TEST(CanopenConfig, NegativeValueIsStoredAsTwosComplementOfItsSize) {
  const auto c = parse(replace(kCanopenYaml, "value: 0x0007", "value: -2"));
  EXPECT_EQ(c.startup_sdo[1].value, 0xFFFEU);
}

TEST(CanopenConfig, ErrorsNameFileLineAndKey) {
  expect_error(replace(kCanopenYaml, "  node_id: 1\n", "  node_id: 1\n  interface: can0\n"),
               {"test.yaml:2:", "canopen.socket_path", "not both"});
  expect_error(replace(kCanopenYaml, "  socket_path: /run/rigctl/valve.sock\n", ""), {"test.yaml:", "canopen.interface", "missing"});
  expect_error(replace(kCanopenYaml, "node_id: 1", "node_id: 128"), {"test.yaml:3:", "canopen.node_id", "128"});
  expect_error(replace(kCanopenYaml, "node_id: 1", "node_id: 1\n  colour: red"), {"test.yaml:4:", "canopen.colour", "unknown key"});
  expect_error(replace(kCanopenYaml, "size: 1, value: 1}", "size: 1, value: 1, mode: rw}"),
               {"test.yaml:11:", "canopen.startup_sdo.device_mode.mode", "unknown key"});
  expect_error(replace(kCanopenYaml, "size: 1, value: 1}", "size: 1, value: 300}"),
               {"test.yaml:11:", "canopen.startup_sdo.device_mode.value", "must be in [-128, 255]"});
  expect_error(replace(kCanopenYaml, "size: 1, value: 1}", "size: 5, value: 1}"), {"canopen.startup_sdo.device_mode.size"});
  expect_error(replace(kCanopenYaml, "index: 0x6040", "index: 0x10000"), {"canopen.startup_sdo.control_word.index"});
  expect_error(replace(replace(kCanopenYaml, "    device_mode: {", "    - {"), "    control_word: {", "    - {"),
               {"canopen.startup_sdo", "expected a mapping", "named entry"});
  expect_error(replace(kCanopenYaml, "heartbeat_period_s: 0.02", "heartbeat_period_s: 0.02\n  valve_heartbeat_period_s: 0.0105"),
               {"canopen.valve_heartbeat_period_s", "whole number of milliseconds"});
  expect_error(replace(kCanopenYaml, "heartbeat_period_s: 0.02", "heartbeat_period_s: 0.02\n  valve_heartbeat_period_s: 0.06"),
               {"canopen.valve_heartbeat_period_s", "shorter than heartbeat_timeout_s"});
  expect_error(replace(kCanopenYaml, "heartbeat_period_s: 0.02", "heartbeat_period_s: 0.02\n  valve_consumer_time_s: 0.02"),
               {"canopen.valve_consumer_time_s", "longer than our heartbeat_period_s"});
  expect_error(replace(kCanopenYaml, "node_id: 1", "node_id: 1\n  master_node_id: 1"), {"canopen.master_node_id", "differ"});
  expect_error(replace(kCanopenYaml, "actual_input: x_s", "actual_input: x_s\n  pressure_scale_pa: 1000"),
               {"canopen.pressure_scale_pa", "pressure_input"});
  expect_error(replace(kCanopenYaml, "actual_input: x_s", "actual_input: x_s\n  pressure_input: p_v"),
               {"canopen.pressure_scale_pa", "missing"});
  expect_error(replace(kCanopenYaml, "sdo_timeout_s: 0.1", "sdo_timeout_s: soon"), {"canopen.sdo_timeout_s", "expected a number"});
}
