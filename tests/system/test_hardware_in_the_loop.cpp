// The hardware path end to end over real protocols: `rigctl run` with the
// Modbus DAQ driver (and the CANopen valve driver) against `rigctl rig-sim`
// on 127.0.0.1 and a seqpacket socket path, compared with the in-process
// simulation; and injected faults, each detected and leading to a safe rig.
//
// Timing on a loaded 2-core machine: tests/support/wire_config.hpp sizes the test
// config's times (start-up in seconds; 10 ms replies and 100 ms, 40 periods,
// of sample age while running); the fault assertions are stated in those
// terms, and every wait is on an event (a line of output), with a deadline
// that is only reached when the test fails.
#include <gtest/gtest.h>

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

class HardwareInTheLoop : public RigSimTest {
 protected:
  // Waits until rig-sim's plant, which sits with the valve closed until the
  // loop starts, has settled (about 0.5 s; 1 s of its clock): the run then
  // starts from the same state however long a loaded machine takes to
  // start it.
  void wait_until_rig_sim_settled() {
    const std::regex report(R"(rig-sim: t = ([0-9.]+) s, valve)");
    EXPECT_TRUE(sim_->wait_until(
        [&](const std::string& out) {
          for (auto it = std::sregex_iterator(out.begin(), out.end(), report); it != std::sregex_iterator(); ++it) {
            if (std::stod((*it)[1].str()) >= 1.0) return true;
          }
          return false;
        },
        60.0))
        << sim_->output();
  }
};

// Max and RMS of the difference between a recording (t_a, a) and a
// reference (t_b, b), compared at the reference's times from t_from on. The
// hardware run is timed by the monotonic clock, so ticks skipped after an
// overrun shift its rows; comparing at equal rig time keeps that from
// looking like an error.
std::pair<double, double> difference(const std::vector<double>& t_a, const std::vector<double>& a,
                                     const std::vector<double>& t_b, const std::vector<double>& b,
                                     double t_from = 0.0) {
  double max = 0.0, sum = 0.0;
  std::size_t n = 0, j = 0;
  for (std::size_t i = 0; i < t_b.size(); ++i) {
    if (t_b[i] < t_from) continue;
    while (j + 1 < t_a.size() && t_a[j + 1] < t_b[i]) ++j;
    if (j + 1 >= t_a.size()) break;
    const double w = (t_b[i] - t_a[j]) / (t_a[j + 1] - t_a[j]);
    const double d = std::abs(a[j] + w * (a[j + 1] - a[j]) - b[i]);
    max = std::max(max, d);
    sum += d * d;
    ++n;
  }
  return {max, std::sqrt(sum / static_cast<double>(std::max<std::size_t>(n, 1)))};
}

std::vector<double> minus(std::vector<double> a, const std::vector<double>& b) {
  for (std::size_t i = 0; i < a.size() && i < b.size(); ++i) a[i] -= b[i];
  return a;
}

// The end of the profile's ramp (hold_s + ramp_target / ramp_rate): the
// demand starts where the rod stands (`start: measured`) and from here on is
// the same whatever that was.
constexpr double kRampEnd = 1.0 + 0.08 / 0.02;

// rig-sim's plant sits with the valve closed until the loop starts and
// settles 1.4 mm away from where the in-process plant starts (the test
// waits for that, so it is the same however late a loaded machine starts
// the run). Until the ramp's end the two runs' demands differ by that, so
// the loop is compared by its tracking error x_r - x_ref over the whole run,
// and the positions from the ramp's end on, through the steps.
//
// The wire adds up to a period of delay each way and the DAQ's 16-bit
// quantisation; the body's stick-slip turns small timing changes into a
// different stick position, so its bounds are wider. One period of wire
// delay at the step's peak rod speed (0.19 m/s) is 0.48 mm: the bound for
// the rms of the rod and wheel. Measured here, both paths, with stress-ng
// on both cores: tracking rms 0.07-0.09 mm, max 0.5-0.8 mm; x_r and x_w
// from the ramp's end rms 0.05-0.11 mm, max 0.3-0.9 mm; x_b rms 0.31-0.40
// mm, max 2.4-2.6 mm.
//
// A loop that woke late or missed ticks held the valve's command meanwhile
// while rig-sim's plant went on in real time: the two runs then differ by
// the rod's travel over that time, which is the machine's load and not the
// hardware path. So the peak bounds grow by the peak rod speed times the
// longest time the loop was away, as `rigctl run` measured and printed it
// (the largest wake-up latency plus every missed tick's period; an upper
// bound, the two can overlap). With stress-ng on both cores and another
// agent's builds beside it, one soak run's CANopen path peaked at 6.2 mm
// with its rms still 0.47 mm (its latencies were not printed by the test
// then; 6.2 mm is what 0.19 m/s gives in 33 ms).
double peak_allowance(const std::string& run_output) {
  constexpr double kPeakRodSpeed = 0.19;  // [m/s] the step test's, as above
  std::smatch m;
  double away_s = 0.0;
  if (std::regex_search(run_output, m, std::regex(R"(wake-up latency: .*max ([0-9.]+) us)"))) away_s += std::stod(m[1]) * 1e-6;
  if (std::regex_search(run_output, m, std::regex(R"(missed ticks ([0-9]+))"))) away_s += std::stod(m[1]) * kPeriod;
  const double allowance = kPeakRodSpeed * away_s;
  std::printf("the loop was away for up to %.1f ms: peak bounds widened by %.3f mm\n", away_s * 1e3, allowance * 1e3);
  return allowance;
}

void expect_matches_in_process_run(const std::string& hardware_csv, const std::string& reference_csv,
                                   const std::string& run_output) {
  const RunFile hw = read_run_file(hardware_csv), ref = read_run_file(reference_csv);
  ASSERT_GT(hw.rows.size(), 8000u);
  EXPECT_NE(run_output.find("wake-up latency: "), std::string::npos) << run_output;
  const double allowance = peak_allowance(run_output);
  const auto check = [&](const std::string& what, std::pair<double, double> d, double max_rms, double max_max) {
    const auto [max, rms] = d;
    std::printf("%s: hardware path vs in-process: max %.3f mm, rms %.3f mm\n", what.c_str(), max * 1e3, rms * 1e3);
    EXPECT_LT(rms, max_rms) << what;
    EXPECT_LT(max, max_max + allowance) << what;
  };
  check("x_r - x_ref (whole run)",
        difference(hw.column("t"), minus(hw.column("x_r"), hw.column("x_ref")), ref.column("t"),
                   minus(ref.column("x_r"), ref.column("x_ref"))),
        0.48e-3, 2e-3);
  for (const char* ch : {"x_r", "x_w", "x_b"}) {
    const bool body = std::string(ch) == "x_b";
    check(std::string(ch) + " (from the ramp's end)",
          difference(hw.column("t"), hw.column(ch), ref.column("t"), ref.column(ch), kRampEnd),
          body ? 1e-3 : 0.48e-3, body ? 4e-3 : 2e-3);
  }
}

}  // namespace

TEST_F(HardwareInTheLoop, StepTestOverModbusTcpMatchesTheInProcessSimulation) {
  const int port = start_rig_sim({});
  ASSERT_GT(port, 0);
  wait_until_rig_sim_settled();
  const auto run = run_command(kRigctl + " run " + write_config("modbus", port) + " --log " + path("hw.lcm") +
                               " --csv " + path("hw.csv"));
  ASSERT_EQ(run.exit_code, 0) << run.output << sim_->output();
  // The summary reports the loop's period keeping and the wire's latency.
  EXPECT_NE(run.output.find("wake-up latency: p50"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("I/O round trip: p50"), std::string::npos) << run.output;
  ASSERT_EQ(run_command(kRigctl + " run " + kConfig + " --fast --log " + path("ref.lcm") + " --csv " + path("ref.csv"))
                .exit_code,
            0);
  expect_matches_in_process_run(path("hw.csv"), path("ref.csv"), run.output);
}

TEST_F(HardwareInTheLoop, StepTestWithTheCanopenValveMatchesTheInProcessSimulation) {
  const int port = start_rig_sim({"--can-socket", path("valve.sock")});
  ASSERT_GT(port, 0);
  ASSERT_TRUE(sim_->wait_for("canopen valve on", 60.0)) << sim_->output();
  wait_until_rig_sim_settled();
  const auto run = run_command(kRigctl + " run " + write_config("modbus_canopen", port) + " --log " + path("hw.lcm") +
                               " --csv " + path("hw.csv"));
  ASSERT_EQ(run.exit_code, 0) << run.output << sim_->output();
  ASSERT_EQ(run_command(kRigctl + " run " + kConfig + " --fast --log " + path("ref.lcm") + " --csv " + path("ref.csv"))
                .exit_code,
            0);
  expect_matches_in_process_run(path("hw.csv"), path("ref.csv"), run.output);
  // The valve's own spool actual value comes back as an input.
  EXPECT_FALSE(read_run_file(path("hw.csv")).column("x_s").empty());
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
