// Faults of the CANopen valve as its client sees them, against the
// simulated node over a socketpair or a socket path
// (tests/support/canopen_pair.hpp): heartbeat lost, the real-time checks on
// the loop's clock, a silent or late valve, EMCY, malformed frames, a lost
// connection, a valve reset, a valve that leaves DEVICE MODE ACTIVE, a
// setpoint deadline in the valve, and the null setpoint repeated while the
// loop holds the valve safe; each flags the inputs with its own cause.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

#include "canopen_pair.hpp"
#include "drivers/canopen/protocol/cia408.hpp"
#include "drivers/canopen/protocol/emcy.hpp"
#include "drivers/canopen/protocol/nmt.hpp"
#include "drivers/canopen/protocol/sdo.hpp"

using namespace rigctl;
using namespace rigctl::test;
using canopen::CanFrame;
using canopen::make_frame;
using canopen::NmtState;
using State = canopen::cia408::ValveState;

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
  // The event follows the counter from the I/O thread: wait for it too.
  EXPECT_TRUE(wait_for([&] { return d.has_event({"heartbeat lost", "timeout 1000.0 ms"}); })) << d.dump();
  EXPECT_TRUE(p.valve.faults() & CanopenValve::kFaultHeartbeatLost);
  EXPECT_NE(p.valve.flag_cause().find("canopen valve node 1: heartbeat lost"), std::string::npos) << p.valve.flag_cause();

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
  EXPECT_EQ(p.valve.flag_cause(), "");  // a new session
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
    const uint64_t values = p.valve.latest_actual().count;
    const bool inside = p.valve.healthy(hb + timeout);
    const bool past = p.valve.healthy(hb + timeout + 1);
    // A heartbeat came in between, or an actual value (healthy() says false
    // while the I/O thread is inside its store): again.
    if (p.valve.last_valve_heartbeat_ns() != hb || values == 0 || p.valve.latest_actual().count != values) continue;
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
  EXPECT_NE(p.valve.flag_cause().find("EMCY 0x2310 (current), error register 0x03 (generic, current)"),
            std::string::npos)
      << p.valve.flag_cause();

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
  // The I/O thread raises the fault first (the loop acts on it) and then
  // writes the event: wait for the event rather than assume it is there.
  Diag d(valve);  // it keeps what each look drains
  EXPECT_TRUE(wait_for([&] { return d.has_event({"connection lost"}); })) << d.dump();
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
  // The event follows the fault from the I/O thread: wait for it too.
  EXPECT_TRUE(wait_for([&] { return d.has_event({"valve reset"}); })) << d.dump();
  EXPECT_NE(p.valve.flag_cause().find("valve reset"), std::string::npos) << p.valve.flag_cause();
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


// ---------------------------------------------------------------- device state and setpoint deadline

TEST(CanopenValve, DropToHoldMidRunIsFlaggedAtOnceLatchedAndNamed) {
  Pair p;
  ASSERT_TRUE(drive_until(p.valve, 0.3, [&] { return std::fabs(p.sim->spool() - 0.3) < 1e-3 && valid(p.valve); }));
  p.sim->drop_to_hold(0.5);  // its spool goes to the hold setpoint; the bus setpoint is ignored
  ASSERT_TRUE(drive_until(p.valve, 0.3, [&] { return flagged(p.valve); }));
  EXPECT_TRUE(p.valve.faults() & CanopenValve::kFaultDeviceState);
  EXPECT_EQ(p.valve.first_flag_reason(), CanopenValve::FlagReason::kDeviceState);
  EXPECT_NE(p.valve.flag_cause().find("canopen valve node 1: left DEVICE MODE ACTIVE: device state HOLD (status word 0x000B)"),
            std::string::npos)
      << p.valve.flag_cause();
  // The loop faults and makes the valve safe; the valve comes back to
  // ACTIVE by itself and finds the null setpoint, not the 0.3 it had.
  p.valve.make_safe();
  ASSERT_TRUE(wait_for([&] { return p.sim->device_state() == State::kActive; }));
  Diag d(p.valve);
  const int64_t repeats = d.counter("canopen_null_setpoint_repeats");
  ASSERT_TRUE(wait_for([&] { return d.counter("canopen_null_setpoint_repeats") >= repeats + 2; }));
  EXPECT_EQ(p.sim->od_value(0x6300, 1), 0U);
  EXPECT_LT(std::fabs(p.sim->spool()), 1e-3);
  EXPECT_TRUE(flagged(p.valve)) << "a departure from ACTIVE stays latched until a restart";
  EXPECT_EQ(d.counter("canopen_left_device_mode_active"), 1);
  EXPECT_TRUE(d.has_event({"device state HOLD", "left DEVICE MODE ACTIVE"})) << d.dump();
}

TEST(CanopenValve, SetpointsThatStopWhileDrivingLapseAtTheValvesDeadline) {
  CanopenValveConfig c = client_config();
  c.setpoint_timeout_s = 0.5;
  Pair p(c);
  EXPECT_EQ(p.sim->od_value(0x1400, 5), 500U);
  ASSERT_TRUE(drive_until(p.valve, 0.4, [&] { return std::fabs(p.sim->spool() - 0.4) < 1e-3; }));
  // The loop stalls while driving (no setpoint, no make_safe) and the I/O
  // thread keeps our heartbeat going: only the valve's deadline helps.
  ASSERT_TRUE(wait_for([&] { return std::fabs(p.sim->spool()) < 1e-3; })) << p.sim->spool();
  EXPECT_EQ(p.sim->stats().rpdo_timeouts, 1U);
  EXPECT_TRUE(wait_for([&] { return flagged(p.valve); }));
  EXPECT_NE(p.valve.flag_cause().find("EMCY 0x8250 (RPDO timeout)"), std::string::npos) << p.valve.flag_cause();
}

TEST(CanopenValve, NullSetpointIsRepeatedWhileTheLoopHoldsTheValveSafe) {
  CanopenValveConfig c = client_config();
  c.setpoint_timeout_s = 1.0;  // repeated every 250 ms
  Pair p(c);
  Diag d(p.valve);
  // No setpoint from the loop yet: five repeats span more than the deadline.
  ASSERT_TRUE(wait_for([&] { return d.counter("canopen_null_setpoint_repeats") >= 5; }));
  EXPECT_EQ(p.sim->stats().rpdo_timeouts, 0U);
  EXPECT_TRUE(valid(p.valve)) << p.valve.flag_cause();
  // Driving: the loop's setpoints, none repeated by the I/O thread.
  ASSERT_TRUE(drive_until(p.valve, 0.2, [&] { return std::fabs(p.sim->spool() - 0.2) < 1e-3; }));
  const int64_t while_driving = d.counter("canopen_null_setpoint_repeats");
  const uint64_t actual_before = p.valve.latest_actual().count;
  ASSERT_TRUE(drive_until(p.valve, 0.2, [&] { return p.valve.latest_actual().count > actual_before + 300; }));  // > 0.6 s
  EXPECT_LE(d.counter("canopen_null_setpoint_repeats"), while_driving + 1);
  // Held safe again: null, and repeated.
  p.valve.make_safe();
  ASSERT_TRUE(wait_for([&] { return d.counter("canopen_null_setpoint_repeats") >= while_driving + 5; }));
  EXPECT_LT(std::fabs(p.sim->spool()), 1e-3);
  EXPECT_EQ(p.sim->stats().rpdo_timeouts, 0U);
}
