// `rigctl run` with the CANopen valve against `rigctl rig-sim` whose
// simulated valve behaves as independent CiA 301/408 valves do (issue 20):
// its power-on PDO mapping and a boot-up delay, segmented uploads, another
// spool reference value (each: started, configured and driven); a drop to
// HOLD mid-run (faulted at once, exit 3, the device state named, no wind-up);
// a device state machine that stalls short of DEVICE MODE ACTIVE, a CiA 401
// device, a fixed mapping (each: refused before the loop drives the valve).
//
// Timing as in test_hardware_in_the_loop (tests/support/wire_config.hpp):
// start-up in seconds, 100 ms of sample age while running; every wait is on
// an event, with a deadline only reached when the test fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "rig_sim_fixture.hpp"

using namespace rigctl::test;

namespace {

constexpr double kPeriod = 0.0025;

class CanopenValveRun : public RigSimTest {
 protected:
  // A short paced run against rig-sim's valve with `valve_options`.
  ProcessResult run_against(const std::vector<std::string>& rig_sim_args, double duration_s) {
    const int port = start_rig_sim_with_valve(rig_sim_args);
    EXPECT_GT(port, 0);
    return run_command(kRigctl + " run " + write_config("modbus_canopen", port) + " --duration " +
                       std::to_string(duration_s) + " --log " + path("r.lcm") + " --csv " + path("r.csv"));
  }

  // Ran to its end, and the valve followed the loop: the spool actual value
  // it reported tracks the command (rig-sim passes the setpoint on at once).
  void expect_driven(const ProcessResult& run) {
    ASSERT_EQ(run.exit_code, 0) << run.output << sim_->output();
    EXPECT_NE(run.output.find("ended: stopped"), std::string::npos) << run.output;
    const RunFile f = read_run_file(path("r.csv"));
    const auto u = f.column("u");
    const auto x_s = f.column("x_s");
    ASSERT_GT(u.size(), 100u);
    double max_u = 0.0, max_gap = 0.0;
    for (std::size_t i = 50; i < u.size(); ++i) {
      max_u = std::max(max_u, std::abs(u[i]));
      max_gap = std::max(max_gap, std::abs(x_s[i] - u[i - 1]));
    }
    EXPECT_GT(max_u, 0.01) << "the loop never drove the valve";
    // The actual value is the setpoint of a tick or two before, quantised.
    EXPECT_LT(max_gap, 0.05) << "the valve did not follow its setpoint";
  }

  // Refused at start-up: the program's error names every fragment, and
  // rig-sim's valve was never driven off null.
  void expect_refused(const ProcessResult& run, const std::vector<std::string>& fragments) {
    EXPECT_EQ(run.exit_code, 1) << run.output;
    for (const auto& f : fragments) EXPECT_NE(run.output.find(f), std::string::npos) << f << "\n" << run.output;
    EXPECT_EQ(run.output.find("ended:"), std::string::npos) << "the loop ran:\n" << run.output;
    const auto commands = valve_commands_after_the_run(*sim_, 0.0);
    ASSERT_FALSE(commands.empty()) << sim_->output();
    for (double u : commands) EXPECT_EQ(u, 0.0) << sim_->output();
  }
};

}  // namespace

TEST_F(CanopenValveRun, ValveWithItsPowerOnMappingAndA20msBootDelayIsStartedAndDriven) {
  const auto run = run_against({"--valve", "power_on_mapping=minimal", "--valve", "boot_delay=0.02"}, 3.0);
  expect_driven(run);
  // The driver's events in the run log: the mapping written and read back.
  const std::string log = read_file(path("r.lcm"));
  EXPECT_NE(log.find("RPDO1 configured and read back"), std::string::npos);
  EXPECT_NE(log.find("TPDO1 configured and read back"), std::string::npos);
  EXPECT_NE(log.find("after NMT reset communication"), std::string::npos);
  EXPECT_NE(log.find("device state DEVICE_MODE_ACTIVE"), std::string::npos);
}

TEST_F(CanopenValveRun, SegmentedUploadsAndAnotherSpoolReferenceAreTaken) {
  const auto run = run_against({"--valve", "segmented_uploads", "--valve", "spool_reference=8192"}, 2.0);
  expect_driven(run);
  EXPECT_NE(read_file(path("r.lcm")).find("spool scale: 8192 counts = 100 %"), std::string::npos);
}

TEST_F(CanopenValveRun, DropToHoldMidRunFaultsAtOnceNamingTheDeviceStateWithoutWindUp) {
  // rig-sim's valve goes to HOLD at 3 s of its clock for 0.5 s, then back to
  // DEVICE MODE ACTIVE by itself.
  const auto run = run_against({"--fault", "hold@3:0.5"}, 10.0);
  EXPECT_EQ(run.exit_code, 3) << run.output << sim_->output();
  EXPECT_NE(run.output.find("faulted (canopen valve node 1: left DEVICE MODE ACTIVE: device state HOLD (status word "
                            "0x000B); input x_s flagged invalid)"),
            std::string::npos)
      << run.output;
  // At once: within the next actual value (1 ms) and a tick, plus this VM's
  // stalls of the SCHED_FIFO threads (24 periods, as the fault matrix
  // allows). rig-sim started before the run, so in the run's rig time the
  // fault came before 3 s: a late start only adds margin.
  const double t_end = last_time(path("r.csv"));
  EXPECT_GT(t_end, 0.0);
  EXPECT_LT(t_end, 3.0 + 26 * kPeriod) << run.output;
  // No wind-up: the loop never saw the valve not following and went on, so
  // the command stayed what the step test needs...
  const auto u = read_run_file(path("r.csv")).column("u");
  ASSERT_FALSE(u.empty());
  for (double v : u) EXPECT_LT(std::abs(v), 0.5);
  // ... and when the valve came back to ACTIVE (3.5 s on rig-sim's clock)
  // it found the null setpoint and kept it.
  const auto after = valve_commands_after_the_run(*sim_, 3.5);
  ASSERT_FALSE(after.empty()) << sim_->output();
  for (double v : after) EXPECT_EQ(v, 0.0) << sim_->output();
}

TEST_F(CanopenValveRun, ValveThatNeverReachesDeviceModeActiveIsRefusedBeforeTheLoopDrivesIt) {
  const auto run = run_against({"--valve", "stall=disabled"}, 3.0);
  expect_refused(run, {"canopen valve node 1", "does not reach DEVICE MODE ACTIVE", "device state DISABLED",
                       "status word 0x0009", "control word 0x0003", "refused before the loop drives it"});
}

TEST_F(CanopenValveRun, CiA401DeviceIsRefusedWithTheProfileItReports) {
  const auto run = run_against({"--valve", "device_type=0x000F0191"}, 3.0);
  expect_refused(run, {"device type 0x000F0191", "names device profile CiA 401, not CiA 408", "refused"});
}

TEST_F(CanopenValveRun, ValveThatRefusesTheMappingIsRefusedNamingTheObjectAndTheAbortCode) {
  const auto run = run_against({"--valve", "fixed_mapping"}, 3.0);
  expect_refused(run, {"'RPDO1 mapping cleared (count 0)' 0x1600:00", "aborted with 0x06010002",
                       "attempt to write a read-only object"});
}
