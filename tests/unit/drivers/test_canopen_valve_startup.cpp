// The CANopen valve client's start-up against the simulated node over a
// socketpair or a socket path (tests/support/canopen_pair.hpp): what it
// configures, the boot-up after the reset, the PDO set-up by the CiA 301
// sequence and its read-back, the device type and the spool scale, the walk
// of the device state machine to DEVICE MODE ACTIVE, SDO aborts, time-outs
// and the retry, and segmented uploads.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "canopen_pair.hpp"
#include "drivers/canopen/protocol/cia408.hpp"
#include "drivers/canopen/protocol/nmt.hpp"
#include "drivers/canopen/protocol/sdo.hpp"

using namespace rigctl;
using namespace rigctl::test;
using canopen::NmtState;
using State = canopen::cia408::ValveState;

// ---------------------------------------------------------------- configuration

TEST(CanopenValve, StartUpConfiguresTheValveAndReachesOperational) {
  Pair p;
  EXPECT_TRUE(p.valve.running());
  EXPECT_EQ(p.sim->nmt_state(), NmtState::kOperational);
  EXPECT_EQ(p.valve.valve_nmt_state(), NmtState::kOperational);
  // The start-up writes landed in the node's dictionary: heartbeats (2),
  // the setpoint RPDO and the actual-value TPDO by the CiA 301 sequence
  // (disable, clear, 2 entries, count, transmission type, event timer,
  // enable: 8 each), the config's device mode (1).
  EXPECT_EQ(p.sim->od_value(0x6042, 0), 1U);
  EXPECT_EQ(p.sim->od_value(0x1017, 0), 50U);
  EXPECT_EQ(p.sim->od_value(0x1016, 1), canopen::consumer_heartbeat_entry(127, 1000));
  EXPECT_EQ(p.sim->od_value(0x1800, 5), 2U);     // actual_period_s
  EXPECT_EQ(p.sim->od_value(0x1400, 5), 1000U);  // setpoint_timeout_s
  EXPECT_EQ(p.sim->stats().sdo_writes, 19U);
  // The device state machine was walked to DEVICE MODE ACTIVE by the RPDO.
  EXPECT_EQ(p.sim->device_state(), canopen::cia408::ValveState::kActive);
  EXPECT_EQ(p.sim->od_value(0x6040, 0), 0x0007U);
  EXPECT_EQ(p.valve.spool_full_scale(), 16384);
  const ValveIdentity id = p.valve.identity();
  EXPECT_EQ(id.device_type & 0xFFFF, 408U);
  EXPECT_EQ(id.product_code, 0x0408U);
  EXPECT_EQ(id.serial, 1U);
  EXPECT_GE(p.sim->stats().nmt_commands, 2U);  // reset communication, start
  EXPECT_TRUE(wait_for([&] { return p.valve.healthy(now_ns()); })) << "faults " << p.valve.faults();
  Diag d(p.valve);
  EXPECT_TRUE(d.has_event({"started", "operational"})) << d.dump();
  EXPECT_TRUE(d.has_event({"identity: device type 0x00000198", "serial 0x00000001"})) << d.dump();
  EXPECT_TRUE(d.has_event({"RPDO1 configured and read back", "0x60400010 0x63000110", "event timer 1000 ms"})) << d.dump();
  EXPECT_TRUE(d.has_event({"TPDO1 configured and read back", "0x60410010 0x63010110", "event timer 2 ms"})) << d.dump();
  EXPECT_TRUE(d.has_event({"device state INIT", "control word 0x0001"})) << d.dump();
  EXPECT_TRUE(d.has_event({"device state DISABLED", "control word 0x0003"})) << d.dump();
  EXPECT_TRUE(d.has_event({"device state HOLD", "control word 0x0007"})) << d.dump();
  EXPECT_EQ(d.counter("canopen_sdo_aborts"), 0);
  EXPECT_EQ(d.counter("canopen_sdo_retries"), 0);
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
    EXPECT_NE(msg.find("twice"), std::string::npos) << msg;
  }
  Diag d(valve);
  EXPECT_EQ(d.counter("canopen_sdo_retries"), 1);
  EXPECT_TRUE(d.has_event({"0x1000:00", "sent once more"})) << d.dump();
}

TEST(CanopenValve, SdoRequestThatTimedOutIsSentOnceMore) {
  CanopenValveConfig c = client_config();
  c.sdo_timeout_s = 0.2;
  CanopenValve valve(c);
  auto [a, b] = socketpair_seqpacket();
  SimCanopenValve sim(std::move(b), sim_config());
  sim.lose_sdo_answers(1);  // the answer to the first request (the device type)
  valve.start(std::move(a));
  EXPECT_TRUE(valve.running());
  Diag d(valve);
  EXPECT_EQ(d.counter("canopen_sdo_retries"), 1);
  EXPECT_EQ(d.counter("canopen_sdo_aborts"), 0);
  EXPECT_TRUE(d.has_event({"device type 0x1000:00", "sent once more"})) << d.dump();
  valve.stop();

  // Two lost in a row: start-up fails naming the object.
  auto [a2, b2] = socketpair_seqpacket();
  SimCanopenValve sim2(std::move(b2), sim_config());
  sim2.lose_sdo_answers(2);
  try {
    valve.start(std::move(a2));
    FAIL() << "start() succeeded";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("0x1000:00"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("twice"), std::string::npos) << e.what();
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
  // A start-up write of the config's own that disables the TPDO again.
  c.startup_sdo.push_back({"tpdo1_off", 0x1800, 1, 4, 0x80000181});
  // The whole start-up runs against this deadline (it always expires here):
  // long enough for the SDO exchange before the TPDO wait on a loaded machine.
  c.startup_timeout_s = 3.0;
  CanopenValve valve(c);
  const std::string error = start_error(valve, sim_config());
  EXPECT_NE(error.find("TPDO1, COB-ID 0x181"), std::string::npos) << error;
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


// ---------------------------------------------------------------- boot-up after the reset

TEST(CanopenValve, BootUpQueuedBeforeTheResetIsNotTakenAsItsAnswer) {
  SimCanopenValveConfig s = sim_config();
  s.boot_delay_s = 0.02;
  auto [a, b] = socketpair_seqpacket();
  SimCanopenValve sim(std::move(b), s);
  // The node's power-on boot-up is waiting in our socket before we start.
  ASSERT_TRUE(wait_for([&] { return sim.stats().boot_ups == 1; }));
  CanopenValve valve(client_config());
  valve.start(std::move(a));
  EXPECT_TRUE(valve.running());
  EXPECT_EQ(sim.stats().boot_ups, 2U);  // power-on, and the one after our reset
  // Nothing was asked of it while it re-initialised after the reset: the
  // first SDO request followed the second boot-up.
  EXPECT_EQ(sim.stats().sdo_while_booting, 0U);
  Diag d(valve);
  EXPECT_GE(d.counter("canopen_discarded_before_reset"), 1);
  EXPECT_EQ(d.counter("canopen_sdo_retries"), 0);
  EXPECT_TRUE(d.has_event({"boot-up", "after NMT reset communication", "discarded"})) << d.dump();
}

TEST(CanopenValve, NoBootUpAfterTheResetFailsNamingBootTimeout) {
  CanopenValveConfig c = client_config();
  c.boot_timeout_s = 0.2;
  CanopenValve valve(c);
  SimCanopenValveConfig s = sim_config();
  s.boot_delay_s = 600.0;  // longer than the test lasts
  const std::string error = start_error(valve, s);
  EXPECT_NE(error.find("no boot-up message after NMT reset communication within boot_timeout_s = 0.2 s"),
            std::string::npos)
      << error;
}

// ---------------------------------------------------------------- PDOs

TEST(CanopenValve, ValveWithItsPowerOnMappingAndA20msBootDelayIsConfiguredAndDriven) {
  SimCanopenValveConfig s = sim_config();
  s.power_on_mapping = SimPowerOnMapping::kMinimal;  // control word only, status word only
  s.boot_delay_s = 0.02;
  Pair p(client_config(), s);
  EXPECT_TRUE(p.valve.running());
  EXPECT_EQ(p.sim->od_value(0x1600, 0), 2U);
  EXPECT_EQ(p.sim->od_value(0x1600, 2), 0x63000110U);
  EXPECT_EQ(p.sim->od_value(0x1A00, 0), 2U);
  EXPECT_EQ(p.sim->od_value(0x1A00, 2), 0x63010110U);
  EXPECT_TRUE(drive_until(p.valve, 0.5, [&] {
    const Sample smp = read(p.valve);
    return std::fabs(p.sim->spool() - 0.5) < 1e-3 && (smp.status & 1U) == 0 && std::fabs(smp.value[0] - 0.5) < 2e-3;
  })) << "spool " << p.sim->spool();
  EXPECT_EQ(p.sim->stats().pdo_length_errors, 0U);
}

TEST(CanopenValve, RefusedMappingNamesTheObjectAndTheAbortCode) {
  struct Case {
    std::string what;
    bool with_pressure_input;
    bool fixed_mapping;
    std::vector<std::string> fragments;
  };
  const std::vector<Case> cases = {
      // The client maps the pressure actual value; this valve has none.
      {"no pressure object", true, false, {"TPDO1 mapping entry 3 (0x63810110)", "0x1A00:03", "0x06040041", "cannot be mapped"}},
      // A valve with a static mapping.
      {"fixed mapping", false, true, {"RPDO1 mapping cleared", "0x1600:00", "0x06010002", "read-only"}},
  };
  for (const auto& k : cases) {
    CanopenValveConfig c = client_config();
    if (k.with_pressure_input) {
      c.pressure_input = "p_v";
      c.pressure_scale_pa = 1000.0;
    }
    SimCanopenValveConfig s = sim_config();
    s.fixed_mapping = k.fixed_mapping;
    CanopenValve valve(c);
    std::unique_ptr<SimCanopenValve> sim;
    const std::string error = start_error(valve, s, &sim);
    for (const auto& f : k.fragments) EXPECT_NE(error.find(f), std::string::npos) << k.what << ": " << error;
    EXPECT_FALSE(valve.running()) << k.what;
    EXPECT_NE(sim->nmt_state(), NmtState::kOperational) << k.what;
  }
}

TEST(CanopenValve, WithConfigurePdosOffTheValvesMappingIsOnlyCheckedAgainstTheConfig) {
  CanopenValveConfig c = client_config();
  c.configure_pdos = false;
  c.setpoint_timeout_s = 0.0;  // what the node holds at power-on
  {
    Pair p(c);  // the profile's mapping at power-on: as configured
    EXPECT_TRUE(p.valve.running());
    EXPECT_EQ(p.sim->stats().sdo_writes, 3U);  // heartbeats and the device mode only
  }
  SimCanopenValveConfig s = sim_config();
  s.power_on_mapping = SimPowerOnMapping::kMinimal;
  CanopenValve valve(c);
  const std::string error = start_error(valve, s);
  for (const std::string f : {"RPDO1 read back", "0x1600:00", "holds 0x01, expected 0x02", "configure_pdos is off"}) {
    EXPECT_NE(error.find(f), std::string::npos) << error;
  }
}

// ---------------------------------------------------------------- identity, scale, segmented uploads

TEST(CanopenValve, DeviceOfAnotherProfileIsRefusedNamingIt) {
  SimCanopenValveConfig s = sim_config();
  s.device_type = 0x000F0191;  // CiA 401, a generic I/O module
  CanopenValve valve(client_config());
  std::unique_ptr<SimCanopenValve> sim;
  const std::string error = start_error(valve, s, &sim);
  for (const std::string f : {"device type 0x000F0191", "CiA 401", "not CiA 408", "refused"}) {
    EXPECT_NE(error.find(f), std::string::npos) << error;
  }
  EXPECT_FALSE(valve.running());
  EXPECT_EQ(sim->stats().sdo_writes, 0U);  // refused before anything was written
  EXPECT_NE(sim->nmt_state(), NmtState::kOperational);
}

TEST(CanopenValve, SegmentedUploadsAreTaken) {
  SimCanopenValveConfig s = sim_config();
  s.segmented_uploads = true;
  Pair p(client_config(), s);
  EXPECT_TRUE(p.valve.running());
  const ValveIdentity id = p.valve.identity();
  EXPECT_EQ(id.device_type, 408U);
  EXPECT_EQ(id.product_code, 0x0408U);
  EXPECT_EQ(id.serial, 1U);
  EXPECT_EQ(p.valve.spool_full_scale(), 16384);
  EXPECT_TRUE(wait_for([&] { return valid(p.valve); }));
}

TEST(CanopenValve, SpoolScaleIsTheValvesReferenceValueAndAConfiguredOneMustAgree) {
  SimCanopenValveConfig s = sim_config();
  s.spool_reference = 8192;
  {
    Pair p(client_config(), s);
    EXPECT_EQ(p.valve.spool_full_scale(), 8192);
    EXPECT_TRUE(drive_until(p.valve, 0.5, [&] {
      const Sample smp = read(p.valve);
      return std::fabs(p.sim->spool() - 0.5) < 1e-3 && (smp.status & 1U) == 0 && std::fabs(smp.value[0] - 0.5) < 2e-3;
    })) << "spool " << p.sim->spool();
    EXPECT_EQ(p.sim->od_value(0x6300, 1), 4096U);  // 0.5 x 8192
  }
  CanopenValveConfig c = client_config();
  c.spool_full_scale = 16384;
  CanopenValve valve(c);
  const std::string error = start_error(valve, s);
  EXPECT_NE(error.find("spool_full_scale is 16384 but the valve's reference value 0x6311:01 is 8192"), std::string::npos)
      << error;
}

// ---------------------------------------------------------------- device state machine

TEST(CanopenValve, ValveThatNeverReachesDeviceModeActiveIsRefusedBeforeTheLoopDrivesIt) {
  CanopenValveConfig c = client_config();
  c.device_state_timeout_s = 0.3;
  SimCanopenValveConfig s = sim_config();
  s.stall_at = State::kDisabled;  // an enable input that is not wired
  CanopenValve valve(c);
  std::unique_ptr<SimCanopenValve> sim;
  const std::string error = start_error(valve, s, &sim);
  for (const std::string f : {"does not reach DEVICE MODE ACTIVE", "device state DISABLED", "status word 0x0009",
                              "control word 0x0003", "device_state_timeout_s = 0.3 s", "refused"}) {
    EXPECT_NE(error.find(f), std::string::npos) << error;
  }
  EXPECT_FALSE(valve.running());
  valve.write_setpoint(0.8);  // the loop cannot drive it
  EXPECT_EQ(sim->od_value(0x6300, 1), 0U);
  EXPECT_EQ(sim->spool(), 0.0);
}

TEST(CanopenValve, ValveInAFaultStateGetsAFaultResetOnTheWayToDeviceModeActive) {
  CanopenValveConfig c = client_config();
  c.reset_on_start = false;  // the fault survives: no reset of the node before
  auto [a, b] = socketpair_seqpacket();
  SimCanopenValve sim(std::move(b), sim_config());
  sim.fault_device(0x5000);  // e.g. left from a previous session
  ASSERT_EQ(sim.device_state(), State::kFaultDisabled);
  CanopenValve valve(c);
  valve.start(std::move(a));
  EXPECT_EQ(sim.device_state(), State::kActive);
  EXPECT_TRUE(wait_for([&] { return valid(valve); })) << valve.flag_cause();
  Diag d(valve);
  EXPECT_TRUE(d.has_event({"device state FAULT_DISABLED", "control word 0x0009"})) << d.dump();  // D with the reset bit
  EXPECT_TRUE(d.has_event({"EMCY 0x0000"})) << d.dump();  // the valve's "no error" after the reset
}
