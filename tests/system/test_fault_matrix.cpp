// The fault-injection matrix of issue 7 (SAFETY.md "Fault injection"): every
// fault on the quarter car's 50 mm step test (config/quarter_car.yaml), read
// back from the run's LCM log, CSV and event log:
//  * detected within a stated number of periods of the injection (rig time),
//  * the configured action taken (interlock: faulted on the trip tick;
//    stop: stopping, then disarmed),
//  * the valve at its safe command (0) within a stated number of periods,
//  * the event in the event log with its reason naming the channel,
//  * no gap in the telemetry ticks before the fault.
// In-process faults (the simulated driver) run --fast: rig time is ticks,
// whatever the machine does. The wire's faults run paced against `rigctl
// rig-sim` as tests/system/test_hardware_in_the_loop.cpp does, and their time to a
// safe valve is measured on the far side, on rig-sim's simulated clock (it
// prints where the final stretch of null valve commands began).
// Each test prints a MATRIX line with what it measured.
#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "background_process.hpp"
#include "process.hpp"
#include "read_file.hpp"
#include "rigctl/driver_status_t.hpp"
#include "rigctl/sample_t.hpp"
#include "wire_config.hpp"

using rigctl::test::BackgroundProcess;
using rigctl::test::run_command;
namespace fs = std::filesystem;

namespace {

const std::string kRigctl = RIGCTL_BINARY;
const std::string kConfig = std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml";
constexpr double kPeriod = 0.0025;
// Every in-process fault starts with the +50 mm step at 5 s: the demand then
// moves fastest (0.2 m/s), the worst case for a controlled stop.
constexpr double kFaultAt = 5.0;

using rigctl::test::read_file;

struct EventLine {
  double t = 0.0;
  std::string state, code, channel, message;
};

std::vector<EventLine> read_events(const std::string& path) {
  std::vector<EventLine> out;
  std::ifstream in(path);
  const std::regex re(R"( t=([0-9.]+) tick=\S+ state=(\S+) code=(\S+)(?: channel=(\S+))?.* message="(.*)\"$)");
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (line.empty() || line[0] == '#' || !std::regex_search(line, m, re)) continue;
    out.push_back({std::stod(m[1].str()), m[2].str(), m[3].str(), m[4].str(), m[5].str()});
  }
  return out;
}

std::string describe(const std::vector<EventLine>& events) {
  std::string s;
  for (const auto& e : events) s += "  t=" + std::to_string(e.t) + " " + e.state + " " + e.code + " " + e.message + "\n";
  return s;
}

// What the LCM log holds: the loop's sample ticks and times, and the
// simulated driver's reports (fault injections, when the valve went safe).
struct LogContents {
  std::vector<int64_t> ticks;
  std::vector<double> times;
  std::vector<double> first_values;  // input 0 (x_r) of each sample
  std::vector<std::string> driver_events;
  int64_t valve_safe_since_ns = -2;  // -2: not reported
};

LogContents read_log(const std::string& path) {
  LogContents c;
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel == "RIGCTL_SAMPLE") {
      rigctl::sample_t s;
      if (s.decode(e->data, 0, e->datalen) < 0) continue;
      c.ticks.push_back(s.tick);
      c.times.push_back(s.t);
      c.first_values.push_back(s.num_channels > 0 ? s.values[0] : 0.0);
    } else if (e->channel == "RIGCTL_DRIVER") {
      rigctl::driver_status_t d;
      if (d.decode(e->data, 0, e->datalen) < 0) continue;
      for (const auto& ev : d.events) c.driver_events.push_back(ev);
      for (int i = 0; i < d.num_counters; ++i) {
        if (d.counter_names[i] == "sim_valve_safe_since_ns") c.valve_safe_since_ns = d.counters[i];
      }
    }
  }
  return c;
}

// Ticks 0, 1, 2, ... with no record missing up to the last one before t_fault.
void expect_no_gap_before(const LogContents& log, double t_fault, bool rig_time_is_ticks) {
  ASSERT_FALSE(log.ticks.empty());
  int64_t before = 0;
  for (std::size_t i = 0; i < log.ticks.size() && log.times[i] < t_fault - 1e-9; ++i) {
    ASSERT_EQ(log.ticks[i], static_cast<int64_t>(i)) << "telemetry tick missing before the fault, at t = " << log.times[i];
    // --fast: rig time is tick x period, so no period was skipped either.
    if (rig_time_is_ticks) {
      ASSERT_NEAR(log.times[i], static_cast<double>(i) * kPeriod, 1e-9);
    }
    ++before;
  }
  // In rig time the fault is t_fault/period ticks in; at least that many
  // were logged (paced: overruns may skip periods, never records).
  if (rig_time_is_ticks) {
    EXPECT_EQ(before, std::llround(t_fault / kPeriod));
  } else {
    EXPECT_GT(before, 0);
  }
}

class FaultMatrix : public ::testing::Test {
 public:
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("rigctl_faults_" + std::to_string(::getpid()) + "_" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

// ---------------------------------------------------------------------------
// In the simulated driver, --fast.

struct InProcessCase {
  std::string fault;    // --fault
  std::string code;     // the detector's event code
  std::string channel;  // the channel its message names ("" for overruns)
  std::string action;   // configured action of the detector
  int max_detect_periods;
  int max_safe_periods;
};

void run_in_process(const FaultMatrix& fx, const InProcessCase& c) {
  const std::string log = fx.path("f.lcm"), csv = fx.path("f.csv");
  // 7 s: two seconds past the fault; a fault left undetected ends at the
  // profile's controlled stop with exit 0, and the test says so.
  const auto run = run_command(kRigctl + " run " + kConfig + " --fast --duration 7 --fault " + c.fault + " --log " +
                               log + " --csv " + csv);
  ASSERT_EQ(run.exit_code, 3) << c.fault << " not detected:\n" << run.output;
  const LogContents contents = read_log(log);
  const auto events = read_events(log + ".events");

  // The driver reports when it injected the fault, in rig time.
  double t_fault = -1.0;
  for (const auto& e : contents.driver_events) {
    std::smatch m;
    if (std::regex_search(e, m, std::regex("fault " + std::regex_replace(c.fault, std::regex(R"([.^$|()\[\]{}*+?\\])"), R"(\$&)") +
                                           " injected at t = ([0-9.]+) s"))) {
      t_fault = std::stod(m[1].str());
    }
  }
  ASSERT_GE(t_fault, 0.0) << "no injection report in the log";
  EXPECT_NEAR(t_fault, kFaultAt, 1e-9);

  // Detection: the configured detector's event, its reason naming the channel.
  const std::string suffix = "(action " + c.action + ")";
  const auto trip = std::find_if(events.begin(), events.end(), [&](const EventLine& e) {
    return e.code == c.code && (c.channel.empty() || e.channel == c.channel) &&
           e.message.find(suffix) != std::string::npos;
  });
  ASSERT_NE(trip, events.end()) << c.fault << ": no " << c.code << " event " << suffix << "\n" << describe(events);
  if (!c.channel.empty()) {
    EXPECT_EQ(trip->message.rfind(c.channel + " ", 0), 0u) << trip->message;
  }
  const long detect = std::lround((trip->t - t_fault) / kPeriod);
  EXPECT_GE(detect, 0);
  EXPECT_LE(detect, c.max_detect_periods) << c.fault;

  // The action, on the trip's tick.
  const auto after = [&](const std::string& text) {
    return std::find_if(events.begin(), events.end(), [&](const EventLine& e) {
      return e.code == "state_changed" && e.t >= trip->t - 1e-9 && e.message == text;
    });
  };
  double t_disarmed = trip->t;
  if (c.action == "interlock") {
    const auto f = after("running -> faulted");
    ASSERT_NE(f, events.end()) << describe(events);
    EXPECT_DOUBLE_EQ(f->t, trip->t) << "an interlock faults the rig on the tick it trips";
  } else {
    ASSERT_EQ(c.action, "stop");
    const auto s = after("running -> stopping");
    ASSERT_NE(s, events.end()) << describe(events);
    EXPECT_DOUBLE_EQ(s->t, trip->t);
    const auto d = after("stopping -> hydraulics_high");
    ASSERT_NE(d, events.end()) << "the controlled stop did not settle\n" << describe(events);
    t_disarmed = d->t;
  }

  // The valve: at the safe command since (the driver's own record), and
  // never before the rig decided so.
  ASSERT_GE(contents.valve_safe_since_ns, 0) << "the simulated valve was still driven at the end";
  const double t_safe = static_cast<double>(contents.valve_safe_since_ns) * 1e-9;
  EXPECT_NEAR(t_safe, t_disarmed, 1e-9) << "the valve went safe on the tick the rig left the driven states";
  const long safe = std::lround((t_safe - t_fault) / kPeriod);
  EXPECT_LE(safe, c.max_safe_periods) << c.fault;

  expect_no_gap_before(contents, t_fault, true);
  // The run file (tools/log2csv) holds the same: one row per period up to the fault.
  std::ifstream in(csv);
  int64_t rows_before = 0;
  bool header = true;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    if (std::stod(line.substr(0, line.find(','))) < t_fault - 1e-9) ++rows_before;
  }
  EXPECT_EQ(rows_before, std::llround(t_fault / kPeriod));
  std::printf("MATRIX %s: %s %s, detected after %ld periods (%.1f ms), valve safe after %ld periods (%.1f ms)\n",
              c.fault.c_str(), c.code.c_str(), c.action.c_str(), detect, detect * kPeriod * 1e3, safe,
              safe * kPeriod * 1e3);
}

}  // namespace

// Bounds: measured value (SAFETY.md) plus a margin in periods, so a change of
// the loop or the detectors that slows the reaction fails here.
TEST_F(FaultMatrix, SensorStuckIsInterlockedOnceTheValveIsDrivenHard) {
  // x_r frozen as the +50 mm step begins: the loop opens the valve, the
  // reading does not move, 100 ticks at |u| >= 0.5 trip x_r_stuck.
  run_in_process(*this, {"stuck@5:x_r", "sensor_stuck", "x_r", "interlock", 130, 130});
}

TEST_F(FaultMatrix, OpenCircuitAtTheRailIsInterlockedOnTheSameTick) {
  run_in_process(*this, {"rail@5:x_r", "open_circuit", "x_r", "interlock", 0, 0});
}

TEST_F(FaultMatrix, NoiseBurstIsInterlockedAsAJumpNoRodCanMake) {
  run_in_process(*this, {"noise@5:x_r:0.005:0.5", "rate_limit", "x_r", "interlock", 8, 8});
}

TEST_F(FaultMatrix, NotANumberIsInterlockedOnTheSameTick) {
  run_in_process(*this, {"nan@5:x_r", "input_invalid", "x_r", "interlock", 0, 0});
}

TEST_F(FaultMatrix, StepOffsetIsInterlockedAsAJump) {
  run_in_process(*this, {"offset@5:x_r:0.01", "rate_limit", "x_r", "interlock", 0, 0});
}

TEST_F(FaultMatrix, OverrunBurstStopsTheRigUnderControl) {
  // 25 reads each stalling 2 periods (virtual time with --fast: the loop's
  // clock moves on by the stall, the plant with it, under the held command).
  run_in_process(*this, {"overrun@5:25", "overruns", "", "stop", 80, 250});
}

TEST_F(FaultMatrix, SupplyPressureLossIsInterlocked) {
  run_in_process(*this, {"supply@5:0", "limit_tripped", "p2", "interlock", 20, 20});
}

TEST_F(FaultMatrix, BurstPipeOnTheCapSideIsInterlocked) {
  run_in_process(*this, {"burst@5:p1", "limit_tripped", "p1", "interlock", 10, 10});
}

// ---------------------------------------------------------------------------
// On the wire: rig-sim's faults through the Modbus DAQ and CANopen valve
// drivers, paced, with the test config of tests/support/wire_config.hpp: start-up
// times in seconds (a loaded machine only starts the run later), and 10 ms
// replies and 100 ms (40 periods) of sample age while running.
//
// Why the period bounds below hold on a loaded machine: from the fault to
// the null valve everything runs in SCHED_FIFO threads (rig-sim's plant and
// valve node, the loop, the drivers' I/O threads), which a CPU hog at
// normal priority cannot delay, and the time is read on rig-sim's clock.
// Where SCHED_FIFO is refused (no CAP_SYS_NICE) that no longer holds: the
// test then checks everything but the bounds and says so by skipping.

namespace {

class WireFaultMatrix : public FaultMatrix {
 protected:
  std::string write_config(const std::string& driver, int port, double heartbeat_timeout_s) {
    const std::string file = path(driver + ".yaml");
    std::ofstream(file) << rigctl::test::wire_config(driver, port, path("valve.sock"), heartbeat_timeout_s);
    return file;
  }

  // rig-sim with the fault, then `rigctl run` against it; checks the matrix's
  // points and prints the MATRIX line. heartbeat_timeout_s: the valve's, in
  // the run's config.
  void run_on_wire(const std::string& driver, const std::string& fault, int max_detect_periods, int max_safe_periods,
                   double heartbeat_timeout_s = rigctl::test::kWireMaxAge) {
    std::vector<std::string> argv{kRigctl, "rig-sim", write_config("sim", 1502, heartbeat_timeout_s),
                                  "--modbus", "127.0.0.1:0", "--fault", fault};
    if (driver == "modbus_canopen") argv.insert(argv.end(), {"--can-socket", path("valve.sock")});
    BackgroundProcess sim(argv, path("rig-sim.out"));
    ASSERT_TRUE(sim.wait_for("modbus listening on", 60.0)) << sim.output();
    if (driver == "modbus_canopen") {
      ASSERT_TRUE(sim.wait_for("canopen valve on", 60.0)) << sim.output();
    }
    std::smatch m;
    const std::string started = sim.output();
    ASSERT_TRUE(std::regex_search(started, m, std::regex(R"(modbus listening on 127\.0\.0\.1:(\d+))"))) << started;
    const std::string log = path("f.lcm");
    const auto run = run_command(kRigctl + " run " + write_config(driver, std::stoi(m[1].str()), heartbeat_timeout_s) +
                                 " --duration 10 --log " + log);
    EXPECT_EQ(run.exit_code, 3) << fault << ":\n" << run.output << sim.output();
    sim.stop();  // prints where the final stretch of null valve commands began
    const std::string out = sim.output();

    // rig-sim's own clock: when it injected the fault, when the valve it
    // drives went to null for good.
    ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(rig-sim: t = ([0-9.]+) s: fault )"))) << out;
    const double t_fault = std::stod(m[1].str());
    ASSERT_TRUE(std::regex_search(out, m, std::regex(R"(rig-sim: valve u = 0 since t = ([0-9.e+-]+) s)"))) << out;
    const double t_null = std::stod(m[1].str());
    // Not before the fault: the loop drove the valve until then.
    EXPECT_GE(t_null, t_fault) << out;
    const long safe = std::lround((t_null - t_fault) / kPeriod);

    // The event log: an input invalid (or the read failing) with its reason
    // naming the channel, and the rig faulted on that tick.
    const auto events = read_events(log + ".events");
    const auto trip = std::find_if(events.begin(), events.end(), [](const EventLine& e) {
      return e.code == "input_invalid" || e.code == "driver_read_failed" || e.code == "sample_stale";
    });
    ASSERT_NE(trip, events.end()) << describe(events);
    if (trip->code == "input_invalid") {
      EXPECT_FALSE(trip->channel.empty());
      EXPECT_EQ(trip->message.rfind(trip->channel + " invalid", 0), 0u) << trip->message;
    }
    if (trip->code == "driver_read_failed") {
      // No usable sample at all: the loop ends on that tick and makes the
      // driver safe on its way out; the failure is the run's last event.
      EXPECT_EQ(trip - events.begin(), static_cast<long>(events.size()) - 1) << describe(events);
    } else {
      const auto faulted = std::find_if(events.begin(), events.end(), [&](const EventLine& e) {
        return e.code == "state_changed" && e.message == "running -> faulted";
      });
      ASSERT_NE(faulted, events.end()) << describe(events);
      EXPECT_DOUBLE_EQ(faulted->t, trip->t);
    }

    // Every loop tick logged up to the fault (overruns of this busy VM may
    // skip periods, never records).
    const LogContents contents = read_log(log);
    expect_no_gap_before(contents, trip->t, false);
    // Detection in the controller's own clock. A silent or absent DAQ shows
    // in the log as the last fresh sample repeated (x_r's noise changes a live
    // reading every tick): the fault began at the first repeat. (The two
    // processes' clocks cannot be lined up closer than the ~20 ms a driver
    // takes to start.) The valve's faults leave the DAQ's samples fresh; the
    // valve's null at the rig, which follows the loop's reaction, bounds them.
    long detect = safe;
    if (driver == "modbus") {
      std::size_t first_stale = contents.first_values.size() - 1;
      while (first_stale > 0 && contents.first_values[first_stale - 1] == contents.first_values.back()) --first_stale;
      ASSERT_GT(first_stale, 0u);
      detect = std::lround((trip->t - contents.times[first_stale]) / kPeriod);
      EXPECT_GE(detect, 0);
    }
    std::printf("MATRIX %s (%s): %s \"%s\" after %s%ld periods (%.1f ms), valve null at the rig after %ld periods (%.1f ms)\n",
                fault.c_str(), driver.c_str(), trip->code.c_str(), trip->message.c_str(),
                driver == "modbus" ? "" : "<= ", detect, detect * kPeriod * 1e3, safe, safe * kPeriod * 1e3);

    // The bounds, where the chain from fault to null ran at SCHED_FIFO.
    for (const std::string& side : {run.output, out}) {
      if (std::regex_search(side, std::regex("SCHED_FIFO priority [0-9]+ refused"))) {
        GTEST_SKIP() << "SCHED_FIFO refused, so a loaded machine can delay the fault's handling: "
                        "everything but the period bounds was checked\n" << side;
      }
    }
    EXPECT_LE(detect, max_detect_periods) << fault;
    EXPECT_LE(safe, max_safe_periods) << fault << "\n" << out;
  }
};

}  // namespace

// Bounds: the detection time the driver's configuration sets (sample age,
// heartbeat timeout) plus 24 periods (60 ms) for this VM's stalls of the
// SCHED_FIFO threads (see above).
TEST_F(WireFaultMatrix, DaqTimeoutIsStaleDataAndNullsTheValve) {
  run_on_wire("modbus", "silence@3", 40 + 8, 40 + 24);
}

TEST_F(WireFaultMatrix, DaqDisconnectIsStaleDataAndNullsTheValve) {
  run_on_wire("modbus", "drop@3", 40 + 8, 40 + 24);
}

TEST_F(WireFaultMatrix, CanHeartbeatLossNullsTheValve) {
  // The shipped heartbeat timeout, 50 ms (20 periods): what is measured here.
  run_on_wire("modbus_canopen", "heartbeat@3:2", 20 + 24, 20 + 24, 0.05);
}

TEST_F(WireFaultMatrix, EmcyNullsTheValve) {
  run_on_wire("modbus_canopen", "emcy@3:0x5000:1", 24, 24);
}

TEST_F(WireFaultMatrix, ValveLeavingDeviceModeActiveNullsTheValve) {
  // HOLD for 0.5 s: the valve goes to its hold setpoint (null) itself; the
  // loop faults and makes it safe, so it finds null when it comes back.
  run_on_wire("modbus_canopen", "hold@3:0.5", 24, 24);
}
