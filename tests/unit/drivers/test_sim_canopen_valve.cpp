// The simulated CiA 408 valve node on its own, driven frame by frame by a
// bare master over a socketpair: its fail-safe when the master's heartbeat
// stops, the spool's lag, when it takes the bus setpoint, its device state
// machine, the CiA 301 rules for its PDO objects, its RPDO deadline, its
// boot-up delay and the options that give it the behaviours of real valves.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <thread>
#include <vector>

#include "canopen_pair.hpp"
#include "drivers/canopen/protocol/cia408.hpp"
#include "drivers/canopen/protocol/emcy.hpp"
#include "drivers/canopen/protocol/nmt.hpp"
#include "drivers/canopen/protocol/sdo.hpp"
#include "drivers/sim/sim_canopen_valve.hpp"
#include "drivers/sim/sim_valve_device_state.hpp"

using namespace rigctl;
using namespace rigctl::test;
using canopen::CanFrame;
using canopen::make_frame;
using canopen::NmtState;
using State = canopen::cia408::ValveState;

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
  // The node's answer to a download: 0 when done, else its abort code.
  uint32_t sdo_write_code(uint16_t index, uint8_t sub, uint32_t value, uint8_t size) {
    t.send(canopen::sdo_download_request(1, index, sub, value, size));
    CanFrame answer;
    const bool got = expect([&](const CanFrame& f) {
      answer = f;
      return f.id() == 0x581 && (f.data[0] == canopen::sdo::kDownloadResponse || f.data[0] == canopen::sdo::kAbort);
    });
    if (!got) return 0xFFFFFFFFU;
    return answer.data[0] == canopen::sdo::kAbort ? canopen::get_u32le(&answer.data[4]) : 0U;
  }
  bool sdo_write(uint16_t index, uint8_t sub, uint32_t value, uint8_t size) {
    return sdo_write_code(index, sub, value, size) == 0;
  }
  void drain() {
    CanFrame f;
    while (t.receive(f, 0) == CanTransport::Rx::kFrame) received.push_back(f);
  }
  bool emcy_seen(uint16_t code) {
    drain();
    for (const auto& f : received) {
      canopen::Emcy e;
      if (canopen::decode_emcy(f, e) == canopen::Malformed::kNone && e.error_code == code) return true;
    }
    return false;
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


// ---------------------------------------------------------------- device state machine

TEST(SimValveDeviceState, ControlWordWalksItUpAndDownAndAFaultNeedsARisingResetEdge) {
  SimValveDeviceState d;
  d.power_on();
  EXPECT_EQ(d.state(), State::kInit);
  EXPECT_EQ(d.status_word(), 0x0008);
  d.on_control_word(0x0001);
  EXPECT_EQ(d.state(), State::kDisabled);
  d.on_control_word(0x0003);
  EXPECT_EQ(d.state(), State::kHold);
  d.on_control_word(0x0007);
  EXPECT_EQ(d.state(), State::kActive);
  EXPECT_EQ(d.status_word(), 0x000F);
  d.on_control_word(0x0001);  // every transition down at once
  EXPECT_EQ(d.state(), State::kDisabled);
  d.on_control_word(0x0007);  // and up
  EXPECT_EQ(d.state(), State::kActive);

  d.fault();
  EXPECT_EQ(d.state(), State::kFaultHold);
  EXPECT_EQ(d.status_word(), 0x0003);  // ready bit clear
  EXPECT_FALSE(d.on_control_word(0x0007));  // no reset bit: stays faulted
  EXPECT_EQ(d.state(), State::kFaultHold);
  EXPECT_TRUE(d.on_control_word(0x000F));  // rising edge of bit 3
  EXPECT_EQ(d.state(), State::kActive);
  EXPECT_FALSE(d.on_control_word(0x000F));  // no edge, nothing to reset
  d.on_control_word(0x0001);
  d.fault();
  EXPECT_EQ(d.state(), State::kFaultDisabled);  // from DISABLED
}

TEST(SimValveDeviceState, StallsWhereToldAndAForcedHoldEndsOnTime) {
  SimValveDeviceState d;
  d.power_on();
  d.set_stall(State::kDisabled);
  d.on_control_word(0x0007);
  EXPECT_EQ(d.state(), State::kDisabled);
  d.set_stall(std::nullopt);
  d.on_control_word(0x0007);
  EXPECT_EQ(d.state(), State::kActive);
  d.step(1000);
  d.force_hold(2000);
  EXPECT_EQ(d.state(), State::kHold);
  EXPECT_EQ(d.status_word(), 0x000B);
  d.step(1999);
  EXPECT_EQ(d.state(), State::kHold);
  d.step(2000);
  EXPECT_EQ(d.state(), State::kActive);  // back to what the control word asks for
}

// ---------------------------------------------------------------- PDO objects, deadlines, boot-up

TEST(SimCanopenValve, PdoObjectsFollowTheCiA301RulesAndARemappedRpdoCarriesTheSetpoint) {
  auto [a, b] = socketpair_seqpacket();
  SimCanopenValveConfig s = sim_config();
  s.power_on_mapping = SimPowerOnMapping::kMinimal;
  SimCanopenValve sim(std::move(b), s);
  RawMaster m{std::move(a), {}};
  EXPECT_EQ(sim.od_value(0x1600, 0), 1U);  // control word only
  EXPECT_EQ(sim.od_value(0x1A00, 0), 1U);  // status word only
  // While the PDO is valid its mapping does not change.
  EXPECT_EQ(m.sdo_write_code(0x1600, 0, 0, 1), 0x06010000U);
  ASSERT_TRUE(m.sdo_write(0x1400, 1, 0x80000201U, 4));  // disable
  EXPECT_EQ(m.sdo_write_code(0x1600, 2, 0x63000110U, 4), 0x06010000U);  // count not 0 yet
  ASSERT_TRUE(m.sdo_write(0x1600, 0, 0, 1));
  EXPECT_EQ(m.sdo_write_code(0x1600, 2, 0x63010110U, 4), 0x06040041U);  // the actual value is not received
  EXPECT_EQ(m.sdo_write_code(0x1600, 2, 0x63000120U, 4), 0x06040041U);  // wrong length for an INTEGER16
  ASSERT_TRUE(m.sdo_write(0x1600, 1, 0x60400010U, 4));
  ASSERT_TRUE(m.sdo_write(0x1600, 2, 0x63000110U, 4));
  EXPECT_EQ(m.sdo_write_code(0x1600, 0, 9, 1), 0x06090031U);
  ASSERT_TRUE(m.sdo_write(0x1600, 0, 2, 1));
  ASSERT_TRUE(m.sdo_write(0x1400, 1, 0x00000201U, 4));  // enable
  ASSERT_TRUE(m.sdo_write(0x6042, 0, 1, 1));
  m.t.send(canopen::encode_nmt(canopen::NmtCommand::kStart, 1));
  EXPECT_TRUE(wait_for([&] {
    m.t.send(make_frame(0x201, {0x07, 0x00, 0x00, 0x20}));  // ACTIVE, 50 %
    m.drain();
    return std::fabs(sim.spool() - 0.5) < 1e-3;
  })) << sim.spool();
  EXPECT_EQ(sim.device_state(), State::kActive);
  // An RPDO of the old length is refused with EMCY 0x8210 (too short).
  m.t.send(make_frame(0x201, {0x07, 0x00}));
  EXPECT_TRUE(wait_for([&] { return m.emcy_seen(0x8210); }));
  EXPECT_EQ(sim.stats().pdo_length_errors, 1U);
}

TEST(SimCanopenValve, FixedMappingRefusesWritesAsReadOnly) {
  auto [a, b] = socketpair_seqpacket();
  SimCanopenValveConfig s = sim_config();
  s.fixed_mapping = true;
  SimCanopenValve sim(std::move(b), s);
  RawMaster m{std::move(a), {}};
  ASSERT_TRUE(m.sdo_write(0x1400, 1, 0x80000201U, 4));  // disabling is allowed
  EXPECT_EQ(m.sdo_write_code(0x1600, 0, 0, 1), 0x06010002U);
}

TEST(SimCanopenValve, MissedRpdoDeadlineFaultsTheValveWithEmcy8250) {
  auto [a, b] = socketpair_seqpacket();
  SimCanopenValve sim(std::move(b), sim_config());
  RawMaster m{std::move(a), {}};
  ASSERT_TRUE(m.sdo_write(0x1400, 5, 100, 2));  // 100 ms
  ASSERT_TRUE(m.sdo_write(0x6042, 0, 1, 1));
  m.t.send(canopen::encode_nmt(canopen::NmtCommand::kStart, 1));
  const CanFrame setpoint = make_frame(0x201, {0x07, 0x00, 0x00, 0x20});
  ASSERT_TRUE(wait_for([&] {
    m.t.send(setpoint);
    m.drain();
    return std::fabs(sim.spool() - 0.5) < 1e-3;
  }));
  EXPECT_EQ(sim.stats().rpdo_timeouts, 0U);
  // The master stops sending setpoints (a stalled loop): the valve goes to null.
  EXPECT_TRUE(wait_for([&] { return std::fabs(sim.spool()) < 1e-3; })) << sim.spool();
  EXPECT_EQ(sim.stats().rpdo_timeouts, 1U);
  EXPECT_EQ(sim.device_state(), State::kFaultHold);
  EXPECT_TRUE(sim.fail_safe());
  EXPECT_TRUE(wait_for([&] { return m.emcy_seen(0x8250); }));
}

TEST(SimCanopenValve, BootDelayKeepsTheNodeDeafUntilItsBootUp) {
  auto [a, b] = socketpair_seqpacket();
  SimCanopenValveConfig s = sim_config();
  s.boot_delay_s = 1.0;
  RawMaster m{std::move(a), {}};
  // Queued before the node powers on: it reads it while initialising and
  // ignores it (a second of boot-up delay: a thread is never that late).
  m.t.send(canopen::sdo_upload_request(1, 0x1000, 0));
  SimCanopenValve sim(std::move(b), s);
  ASSERT_TRUE(m.expect([](const CanFrame& f) { return f.id() == 0x701 && f.len == 1 && f.data[0] == 0; })) << "no boot-up";
  m.drain();
  for (const auto& f : m.received) EXPECT_NE(f.id(), 0x581U) << "answered while booting";
  EXPECT_EQ(sim.stats().sdo_while_booting, 1U);
  EXPECT_EQ(sim.stats().boot_ups, 1U);
  // Awake now: it answers, and an NMT reset makes it deaf again for the delay.
  EXPECT_TRUE(m.sdo_write(0x6042, 0, 1, 1));
  m.t.send(canopen::encode_nmt(canopen::NmtCommand::kResetCommunication, 1));
  ASSERT_TRUE(m.expect([](const CanFrame& f) { return f.id() == 0x701 && f.len == 1 && f.data[0] == 0; }));
  EXPECT_EQ(sim.stats().boot_ups, 2U);
}

TEST(SimCanopenValve, OptionsParseAndNameTheBadOne) {
  SimCanopenValveConfig c;
  apply_sim_valve_option("device_type=401", c);
  apply_sim_valve_option("spool_reference=0x2000", c);
  apply_sim_valve_option("boot_delay=0.02", c);
  apply_sim_valve_option("power_on_mapping=minimal", c);
  apply_sim_valve_option("fixed_mapping", c);
  apply_sim_valve_option("segmented_uploads", c);
  apply_sim_valve_option("stall=disabled", c);
  EXPECT_EQ(c.device_type, 401U);
  EXPECT_EQ(c.spool_reference, 8192);
  EXPECT_DOUBLE_EQ(c.boot_delay_s, 0.02);
  EXPECT_EQ(c.power_on_mapping, SimPowerOnMapping::kMinimal);
  EXPECT_TRUE(c.fixed_mapping);
  EXPECT_TRUE(c.segmented_uploads);
  ASSERT_TRUE(c.stall_at.has_value());
  EXPECT_EQ(*c.stall_at, State::kDisabled);
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"colour=red", "unknown key 'colour'"}, {"stall=active", "unknown state 'active'"},
      {"boot_delay", "expected boot_delay=VALUE"}, {"fixed_mapping=1", "takes no value"},
      {"spool_reference=0", "1..32767"},      {"power_on_mapping=vendor", "profile, minimal"},
  };
  for (const auto& [option, why] : bad) {
    try {
      apply_sim_valve_option(option, c);
      ADD_FAILURE() << option << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("'" + option + "'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
  }
}
