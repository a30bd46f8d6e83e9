// The hardware path end to end over real protocols: `rigctl run` with the
// Modbus DAQ driver (and the CANopen valve driver) against `rigctl rig-sim`
// on 127.0.0.1 and a seqpacket socket path, compared with the in-process
// simulation; and injected faults, each detected and leading to a safe rig.
//
// The comparisons run in lock-step (`run --lock-step`, `rig-sim
// --lock-step`): rig-sim's plant steps one period per DAQ exchange, so its
// time is the loop's tick count whatever the scheduler does, and the two
// runs differ only by what the wire itself does to the signals. One paced
// run shows the free-running behaviour with assertions that do not depend on
// how long a loaded machine kept the loop away: it completes, its events come
// in the simulated run's order, the rod reaches every step.
//
// The fault tests run paced. Timing on a loaded 2-core machine:
// tests/support/wire_config.hpp sizes the test config's times (start-up in
// seconds; 10 ms replies and 100 ms, 40 periods, of sample age while
// running); the fault assertions are stated in those terms, and every wait is
// on an event (a line of output), with a deadline that is only reached when
// the test fails.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <regex>
#include <sstream>

#include "rig_sim_fixture.hpp"

using namespace rigctl::test;
namespace fs = std::filesystem;

namespace {

const std::string kConfig = kShippedConfig;
constexpr double kPeriod = 0.0025;
constexpr double kMaxAge = kWireMaxAge;


// Max and RMS of the difference between two runs' column, row by row at
// equal rig time (both runs in simulated time: the same ticks).
struct Difference {
  double max = 0.0, rms = 0.0;
  std::size_t rows = 0;
};
Difference difference(const RunFile& a, const RunFile& b, const std::string& column) {
  const auto ta = a.column("t"), tb = b.column("t"), va = a.column(column), vb = b.column(column);
  Difference d;
  double sum = 0.0;
  for (std::size_t i = 0, j = 0; i < ta.size(); ++i) {
    while (j < tb.size() && tb[j] < ta[i] - 1e-9) ++j;
    if (j >= tb.size()) break;
    if (std::abs(tb[j] - ta[i]) > 1e-9) continue;  // no row at this time in the other run
    const double e = std::abs(va[i] - vb[j]);
    d.max = std::max(d.max, e);
    sum += e * e;
    ++d.rows;
  }
  d.rms = std::sqrt(sum / static_cast<double>(std::max<std::size_t>(d.rows, 1)));
  return d;
}

// One LSB of the DAQ's 16-bit position registers (and of the in-process
// ADC over the same +-0.2 m): 0.4 m / 2^16.
constexpr double kPositionLsb = 0.4 / 65536.0;

void print(const std::string& what, const Difference& d, double unit, const char* unit_name) {
  std::printf("%s: lock-step hardware path vs in-process, %zu rows: max %.4g %s, rms %.4g %s\n", what.c_str(), d.rows,
              d.max / unit, unit_name, d.rms / unit, unit_name);
}

// The rig's state changes in order, from a run's event log.
std::vector<std::string> state_changes(const std::string& events_path) {
  std::vector<std::string> out;
  const std::string text = read_file(events_path);
  const std::regex re("code=state_changed.* message=\"([^\"]*)\"");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), re); it != std::sregex_iterator(); ++it) {
    out.push_back((*it)[1].str());
  }
  return out;
}

class HardwareInTheLoop : public RigSimTest {
 protected:
  // The lock-step run of `driver` against rig-sim --lock-step (started by
  // the test), and the in-process --fast run of the same config, as run files.
  std::pair<RunFile, RunFile> lock_step_and_in_process_runs(const std::string& driver, int port) {
    const std::string config = path(driver + "-lock-step.yaml");
    std::ofstream(config) << lock_step_wire_config(driver, port, path("valve.sock"));
    const auto run = run_command(kRigctl + " run " + config + " --lock-step --log " + path("hw.lcm") + " --csv " +
                                 path("hw.csv"));
    EXPECT_EQ(run.exit_code, 0) << run.output << sim_->output();
    EXPECT_NE(run.output.find("in lock-step with rig-sim"), std::string::npos) << run.output;
    const auto ref = run_command(kRigctl + " run " + kConfig + " --fast --log " + path("ref.lcm") + " --csv " +
                                 path("ref.csv"));
    EXPECT_EQ(ref.exit_code, 0) << ref.output;
    return {read_run_file(path("hw.csv")), read_run_file(path("ref.csv"))};
  }
};

}  // namespace

// What the wire does to the signals in lock-step. rig-sim's transducers draw
// their noise from the config's seed in the DAQ's input order, which is the
// simulated driver's sensor order, so both runs see the same noise; the
// DAQ's 16-bit position registers count in the LSB of the in-process ADC
// (0.4 m / 2^16 over +-0.2 m). What differs is how the count is reached:
// the in-process ADC rounds (x + 0.2 m) / LSB, the register x / gain, the
// valve command goes through the holding register or the CiA 408 setpoint
// instead of the DAC model, and the two computations differ in the last
// bits. With the body's stick-slip such a difference now and then moves a
// reading to the next count (1-2 % of the samples measured here). Both
// runs are deterministic: the same counts on every run, however busy the
// machine, so the bounds are what was measured (2026-11-27, printed by the
// tests): every position within one count of the in-process run, and the
// command within what one count does through the PI's proportional gain.
constexpr double kProportionalGain = 80.0;  // [1/m] kp of config/quarter_car.yaml

// Modbus all the way: measured max one count (6.1 um) on x_r, x_w, x_b; u
// max 4.94e-4 (kp times a count, 4.88e-4, plus the integral of that count
// over the ticks it lasted).
TEST_F(HardwareInTheLoop, StepTestOverModbusInLockStepMatchesTheInProcessSimulationToACount) {
  const int port = start_rig_sim({"--lock-step"});
  ASSERT_GT(port, 0);
  const auto [hw, ref] = lock_step_and_in_process_runs("modbus", port);
  ASSERT_GT(hw.rows.size(), 8000u);
  ASSERT_EQ(hw.rows.size(), ref.rows.size()) << "the same ticks in both runs";
  for (const char* ch : {"x_r", "x_w", "x_b", "x_ref"}) {
    const Difference d = difference(hw, ref, ch);
    print(ch, d, 1e-6, "um");
    EXPECT_EQ(d.rows, ref.rows.size()) << ch;
    EXPECT_LE(d.max, kPositionLsb * 1.001) << ch;
  }
  const Difference u = difference(hw, ref, "u");
  print("u", u, 1.0, "");
  EXPECT_LE(u.max, 1.05 * kProportionalGain * kPositionLsb) << "kp times one count, and its integral";
}

// With the CANopen valve the command travels as the CiA 408 spool setpoint,
// an int16 with 16384 counts for 100 % (one count 6.1e-5, twice the
// in-process DAC's LSB). Measured: max one count on every position, rms at
// most 0.22 counts (x_b); u max 5.01e-4. Bounds: two counts (one of margin:
// the driver's own thread sends null setpoints while the loop holds the
// valve safe, and one sent just before the loop's first driven setpoint
// could reach the valve after it), and kp times a count plus one setpoint
// count for u.
TEST_F(HardwareInTheLoop, StepTestWithTheCanopenValveInLockStepMatchesTheInProcessSimulationToACount) {
  const int port = start_rig_sim_with_valve({"--lock-step"});
  ASSERT_GT(port, 0);
  const auto [hw, ref] = lock_step_and_in_process_runs("modbus_canopen", port);
  ASSERT_GT(hw.rows.size(), 8000u);
  ASSERT_EQ(hw.rows.size(), ref.rows.size()) << "the same ticks in both runs";
  for (const char* ch : {"x_r", "x_w", "x_b", "x_ref"}) {
    const Difference d = difference(hw, ref, ch);
    print(ch, d, 1e-6, "um");
    EXPECT_EQ(d.rows, ref.rows.size()) << ch;
    EXPECT_LE(d.rms, 0.5 * kPositionLsb) << ch;
    EXPECT_LE(d.max, 2 * kPositionLsb * 1.001) << ch;
  }
  const Difference u = difference(hw, ref, "u");
  print("u", u, 1.0, "");
  EXPECT_LE(u.max, 1.05 * kProportionalGain * kPositionLsb + 1.0 / 16384.0);
  // The valve's own spool actual value comes back as an input.
  EXPECT_FALSE(hw.column("x_s").empty());
}

// Free-running: rig-sim on its own clock, the loop paced by the monotonic
// clock. A loaded machine can keep the loop away for a while (184 ms seen)
// while the plant runs on, so the run's values depend on the load; these
// assertions do not: the run completes, the summary reports the loop's
// period keeping and the wire's latency, the rig's state changes come in the
// order of the simulated run's, the rod reaches every step of the profile,
// and after the run rig-sim's valve is back at null.
TEST_F(HardwareInTheLoop, PacedStepTestOverModbusTcpCompletesWithTheSimulatedRunsEvents) {
  const int port = start_rig_sim({});
  ASSERT_GT(port, 0);
  // A paced run beside other tests on a shared 2-core machine: a reply or a
  // wake-up the scheduler holds past the wire's deadlines (a 99 ms stall was
  // seen beside the diagnosis tests) is the machine's, not the wire's. This
  // test is about a whole paced run over TCP, so the DAQ waits and a sample
  // may age half a second; the fault tests below keep the deadlines they test.
  const std::string config = write_config("modbus", port);
  std::string text = read_file(config);
  for (const char* key : {"response_timeout_s", "max_sample_age_s"})
    text = std::regex_replace(text, std::regex(std::string(key) + ": [0-9.]+"), std::string(key) + ": 0.5");
  std::ofstream(config) << text;
  const auto run = run_command(kRigctl + " run " + config + " --log " + path("hw.lcm") + " --csv " + path("hw.csv"));
  ASSERT_EQ(run.exit_code, 0) << run.output << sim_->output();
  EXPECT_NE(run.output.find("ended: stopped"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("wake-up latency: p50"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("I/O round trip: p50"), std::string::npos) << run.output;
  ASSERT_EQ(run_command(kRigctl + " run " + kConfig + " --fast --log " + path("ref.lcm") + " --csv " + path("ref.csv"))
                .exit_code,
            0);
  const auto changes = state_changes(path("hw.lcm.events"));
  EXPECT_EQ(changes, state_changes(path("ref.lcm.events")));
  EXPECT_GE(changes.size(), 6u);
  // The profile's steps are +-50 mm about mid-stroke (config/quarter_car.yaml);
  // the rod holds each long enough to settle, so it comes within 5 mm of both.
  const auto x_r = read_run_file(path("hw.csv")).column("x_r"), ref_x_r = read_run_file(path("ref.csv")).column("x_r");
  ASSERT_FALSE(x_r.empty());
  EXPECT_NEAR(*std::max_element(x_r.begin(), x_r.end()), *std::max_element(ref_x_r.begin(), ref_x_r.end()), 5e-3);
  EXPECT_NEAR(*std::min_element(x_r.begin(), x_r.end()), *std::min_element(ref_x_r.begin(), ref_x_r.end()), 5e-3);
  const auto after = valve_commands_after_the_run(*sim_, 0.0);
  ASSERT_FALSE(after.empty()) << sim_->output();
  EXPECT_EQ(after.back(), 0.0) << sim_->output();
}

TEST_F(HardwareInTheLoop, ModbusExceptionOnTheSensorsMakesTheRigSafeAndSaysWhy) {
  // From 3 s rig-sim answers reads of x_r's registers (the whole input block)
  // with exception 0x04; the writes of the valve command still get through.
  const int port = start_rig_sim({"--fault", "exception@3:x_r:4"});
  ASSERT_GT(port, 0);
  const auto run = run_command(kRigctl + " run " + write_config("modbus", port) + " --duration 10 --log " +
                               path("f.lcm") + " --csv " + path("f.csv"));
  EXPECT_EQ(run.exit_code, 3) << run.output;
  EXPECT_NE(run.output.find("faulted (input_invalid"), std::string::npos) << run.output;
  // Detected within the sample age plus a poll and a tick after the fault
  // began (rig-sim started before the run, so the fault comes early in the
  // run's rig time: a run that starts late only adds margin).
  const double t_end = last_time(path("f.csv"));
  EXPECT_LT(t_end, 3.0 + kMaxAge + 4 * kPeriod) << run.output;
  // The driver's event names the registers and the exception, in the log too.
  const std::string log = read_file(path("f.lcm"));
  EXPECT_NE(log.find("Slave device or server failure"), std::string::npos);
  EXPECT_NE(log.find("input registers 0-7 of unit 1"), std::string::npos);
  // The valve went to null and stays there: no jump back to an old command
  // (a new run is the re-arm).
  const auto after = valve_commands_after_the_run(*sim_, 3.0 + 0.5);
  ASSERT_FALSE(after.empty()) << sim_->output();
  for (double u : after) EXPECT_EQ(u, 0.0) << sim_->output();
}

TEST_F(HardwareInTheLoop, SilentDaqIsStaleDataAndFaultsTheLoop) {
  const int port = start_rig_sim({"--fault", "silence@3:1"});
  ASSERT_GT(port, 0);
  const auto run = run_command(kRigctl + " run " + write_config("modbus", port) + " --duration 10 --log " +
                               path("f.lcm") + " --csv " + path("f.csv"));
  EXPECT_EQ(run.exit_code, 3) << run.output;
  EXPECT_TRUE(run.output.find("faulted (input_invalid") != std::string::npos ||
              run.output.find("faulted (driver_read_failed") != std::string::npos)
      << run.output;
  EXPECT_NE(read_file(path("f.lcm")).find("timeout"), std::string::npos);
}

TEST_F(HardwareInTheLoop, LostValveHeartbeatFaultsTheLoopAndNullsTheValve) {
  const int port = start_rig_sim({"--can-socket", path("valve.sock"), "--fault", "heartbeat@4:2"});
  ASSERT_GT(port, 0);
  ASSERT_TRUE(sim_->wait_for("canopen valve on", 60.0)) << sim_->output();
  // The shipped heartbeat timeout, 50 ms: its loss is what is tested.
  constexpr double kHeartbeatTimeout = 0.05;
  const auto run = run_command(kRigctl + " run " + write_config("modbus_canopen", port, kHeartbeatTimeout) +
                               " --duration 10 --log " + path("f.lcm") + " --csv " + path("f.csv"));
  EXPECT_EQ(run.exit_code, 3) << run.output;
  // The fault line names the CANopen cause, not only the flagged input.
  EXPECT_NE(run.output.find("faulted (canopen valve node 1: heartbeat lost"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("input x_s flagged invalid"), std::string::npos) << run.output;
  // Faulted within 21 periods of the last heartbeat. The run's rig time
  // started after rig-sim's (rig-sim was up first), so in the run's time
  // the fault came before 4 s: a run that starts late only adds margin.
  EXPECT_LT(last_time(path("f.csv")), 4.0 + kHeartbeatTimeout + 22 * kPeriod);
  EXPECT_NE(read_file(path("f.lcm")).find("heartbeat"), std::string::npos);
  const auto after = valve_commands_after_the_run(*sim_, 4.5);
  ASSERT_FALSE(after.empty()) << sim_->output();
  for (double u : after) EXPECT_EQ(u, 0.0) << sim_->output();
}

TEST_F(HardwareInTheLoop, EmcyFromTheValveIsDecodedAndFaultsTheLoop) {
  const int port = start_rig_sim({"--can-socket", path("valve.sock"), "--fault", "emcy@4:0x5000:1"});
  ASSERT_GT(port, 0);
  ASSERT_TRUE(sim_->wait_for("canopen valve on", 60.0)) << sim_->output();
  const auto run = run_command(kRigctl + " run " + write_config("modbus_canopen", port) + " --duration 10 --log " +
                               path("f.lcm"));
  EXPECT_EQ(run.exit_code, 3) << run.output;
  EXPECT_NE(run.output.find("faulted (canopen valve node 1: EMCY 0x5000 (device hardware), error register 0x01 (generic)"),
            std::string::npos)
      << run.output;
  EXPECT_NE(read_file(path("f.lcm")).find("0x5000"), std::string::npos) << "EMCY code in the log";
}

TEST_F(HardwareInTheLoop, OpenCircuitTransducerAtTheRailTripsTheStrokeLimit) {
  // x_r's register forced to the top of its range: 0.19999 m, beyond the
  // configured stroke limit of 0.172 m.
  const int port = start_rig_sim({"--fault", "rail@3:x_r"});
  ASSERT_GT(port, 0);
  const auto run = run_command(kRigctl + " run " + write_config("modbus", port) + " --duration 10 --log " + path("f.lcm"));
  EXPECT_EQ(run.exit_code, 3) << run.output;
  EXPECT_NE(run.output.find("faulted (limit_tripped: x_r = 0.1999"), std::string::npos) << run.output;
}

TEST_F(HardwareInTheLoop, DroppedConnectionAndLateRepliesAreStaleDataAndFaultTheLoop) {
  for (const std::string fault : {"drop@3", "late@3:0.03:1"}) {
    const int port = start_rig_sim({"--fault", fault});
    ASSERT_GT(port, 0);
    const auto run = run_command(kRigctl + " run " + write_config("modbus", port) + " --duration 10 --log " +
                                 path("f.lcm"));
    EXPECT_EQ(run.exit_code, 3) << fault << ": " << run.output;
    EXPECT_TRUE(run.output.find("faulted (input_invalid") != std::string::npos ||
                run.output.find("faulted (driver_read_failed") != std::string::npos)
        << fault << ": " << run.output;
    sim_->stop();
  }
}
