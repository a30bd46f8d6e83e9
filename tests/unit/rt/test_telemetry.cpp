// TelemetryPublisher over memq://: what is pushed comes out on the bus with
// the same values, the log holds exactly the published bytes, drops are
// counted, and the log is flushed while running.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "rigctl/command_t.hpp"
#include "rigctl/controller_t.hpp"
#include "rigctl/sample_t.hpp"
#include "rigctl/state_t.hpp"
#include "rigctl/timing_t.hpp"
#include "rt/comms/telemetry_publisher.hpp"

namespace fs = std::filesystem;
using namespace rigctl;

namespace {

constexpr int64_t kStartUtime = 1'700'000'000'000'000;
constexpr int64_t kPeriodNs = 2'500'000;

TelemetryMeta make_meta() {
  TelemetryMeta m;
  m.rig = "quarter_car";
  m.layout.inputs = {{"x_r", "m"}, {"x_w", "m"}, {"x_b", "m"}, {"p1", "Pa"}, {"sim_x_b", "m"}};
  m.layout.outputs = {{"u", "1"}};
  m.setpoint_name = "x_ref";
  m.controller_name = "pi";
  m.term_names = {"p", "i"};
  m.start_utime = kStartUtime;
  return m;
}

// States and events of the 50-tick script used by the round-trip test.
RigState state_at(int64_t tick) {
  if (tick == 0) return RigState::kStarting;
  if (tick < 20) return RigState::kRunning;
  if (tick < 49) return RigState::kFaulted;
  return RigState::kStopped;
}

TelemetryRecord make_record(int64_t tick) {
  TelemetryRecord r;
  r.tick = tick;
  r.sample.t_ns = tick * kPeriodNs + 1234;  // not a multiple of 1 us on purpose
  r.sample.status = tick == 7 ? 0x4u : 0u;
  for (int i = 0; i < 5; ++i) r.sample.value[i] = 0.001 * tick + i + (i == 3 ? 2.0e5 : 0.0);
  r.command.value[0] = -0.5 + 0.01 * tick;
  r.controller.setpoint = 0.05 + 1e-4 * tick;
  r.controller.measurement = 0.04 + 1e-4 * tick;
  r.controller.error = r.controller.setpoint - r.controller.measurement;
  r.controller.term[0] = 1.5 * tick;
  r.controller.term[1] = -2.5 * tick;
  r.controller.output_unsaturated = 3.0 * tick;
  r.controller.output = 0.9;
  r.controller.saturated = tick % 2 == 1;
  r.controller.integrator_held = tick % 3 == 0;
  r.state = state_at(tick);
  if (tick == 0) r.event.code = EventCode::kRunStarted;
  if (tick == 10) r.event.code = EventCode::kProfileFinished;
  if (tick == 20) r.event = {EventCode::kLimitTripped, 0, 0.1712};
  if (tick == 40) {
    r.has_timing = true;
    r.timing.period_ns = kPeriodNs;
    r.timing.ticks = 41;
    r.timing.overruns = 2;
    r.timing.missed_ticks = 1;
    r.timing.wakeup_latency = {41, 1000, 90000, 23000.5, 21000, 80000, 90000};
    r.timing.compute = {41, 500, 9000, 1200.25, 1100, 8000, 9000};
  }
  return r;
}

int64_t utime_of(const TelemetryRecord& r) { return kStartUtime + r.sample.t_ns / 1000; }

struct Captured {
  std::string channel;
  std::vector<uint8_t> bytes;
};

// Subscriber on the publisher's own LCM instance (memq:// is in-process).
struct Collector {
  std::vector<Captured> all;  // every message in arrival order
  std::vector<sample_t> samples;
  std::vector<command_t> commands;
  std::vector<controller_t> controllers;
  std::vector<state_t> states;
  std::vector<timing_t> timings;

  void keep(const lcm::ReceiveBuffer* rb, const std::string& ch) {
    const auto* p = static_cast<const uint8_t*>(rb->data);
    all.push_back({ch, std::vector<uint8_t>(p, p + rb->data_size)});
  }
  void on_sample(const lcm::ReceiveBuffer* rb, const std::string& ch, const sample_t* m) { keep(rb, ch); samples.push_back(*m); }
  void on_command(const lcm::ReceiveBuffer* rb, const std::string& ch, const command_t* m) { keep(rb, ch); commands.push_back(*m); }
  void on_controller(const lcm::ReceiveBuffer* rb, const std::string& ch, const controller_t* m) { keep(rb, ch); controllers.push_back(*m); }
  void on_state(const lcm::ReceiveBuffer* rb, const std::string& ch, const state_t* m) { keep(rb, ch); states.push_back(*m); }
  void on_timing(const lcm::ReceiveBuffer* rb, const std::string& ch, const timing_t* m) { keep(rb, ch); timings.push_back(*m); }

  void subscribe(TelemetryPublisher& pub) {
    lcm::LCM& l = pub.lcm();
    const TelemetryChannels& c = pub.channels();
    l.subscribe(c.sample, &Collector::on_sample, this);
    l.subscribe(c.command, &Collector::on_command, this);
    l.subscribe(c.controller, &Collector::on_controller, this);
    l.subscribe(c.state, &Collector::on_state, this);
    l.subscribe(c.timing, &Collector::on_timing, this);
  }
};

struct LoggedEvent {
  int64_t timestamp;
  std::string channel;
  std::vector<uint8_t> bytes;
};

std::vector<LoggedEvent> read_log(const std::string& path) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error("cannot read " + path);
  std::vector<LoggedEvent> out;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    const auto* p = static_cast<const uint8_t*>(ev->data);
    out.push_back({ev->timestamp, ev->channel, std::vector<uint8_t>(p, p + ev->datalen)});
  }
  return out;
}

class TelemetryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("rigctl_test_telemetry_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(TelemetryTest, MemqRoundTripAndLogHoldsExactlyThePublishedBytes) {
  const std::string log_path = (dir_ / "sub" / "run.lcm").string();  // parent dirs get created
  TelemetryPublisher pub(make_meta(), "memq://", log_path);
  Collector col;
  col.subscribe(pub);
  pub.start();

  constexpr int kTicks = 50;
  std::vector<TelemetryRecord> pushed;
  for (int64_t k = 0; k < kTicks; ++k) {
    pushed.push_back(make_record(k));
    ASSERT_TRUE(pub.push(pushed.back()));
  }
  // 3 messages every tick, state on ticks 0 (first), 1 (change), 10 (event),
  // 20 (change + event), 49 (change); timing on tick 40.
  const std::vector<int64_t> state_ticks = {0, 1, 10, 20, 49};
  const std::size_t expected = 3 * kTicks + state_ticks.size() + 1;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (col.all.size() < expected && std::chrono::steady_clock::now() < deadline) pub.lcm().handleTimeout(100);
  pub.stop();
  while (pub.lcm().handleTimeout(50) > 0) {}  // anything extra would show as a count mismatch
  EXPECT_EQ(pub.published(), kTicks);
  EXPECT_EQ(pub.dropped(), 0);
  ASSERT_EQ(col.all.size(), expected);

  ASSERT_EQ(col.samples.size(), static_cast<std::size_t>(kTicks));
  ASSERT_EQ(col.commands.size(), static_cast<std::size_t>(kTicks));
  ASSERT_EQ(col.controllers.size(), static_cast<std::size_t>(kTicks));
  for (int k = 0; k < kTicks; ++k) {
    const TelemetryRecord& r = pushed[k];
    const sample_t& s = col.samples[k];
    EXPECT_EQ(s.tick, k);
    EXPECT_EQ(s.utime, utime_of(r));
    EXPECT_DOUBLE_EQ(s.t, r.sample.t_ns * 1e-9);
    EXPECT_EQ(s.rig, "quarter_car");
    EXPECT_EQ(s.status, static_cast<int32_t>(r.sample.status));
    ASSERT_EQ(s.num_channels, 5);
    EXPECT_EQ(s.names, (std::vector<std::string>{"x_r", "x_w", "x_b", "p1", "sim_x_b"}));
    EXPECT_EQ(s.units, (std::vector<std::string>{"m", "m", "m", "Pa", "m"}));
    for (int i = 0; i < 5; ++i) EXPECT_EQ(s.values[i], r.sample.value[i]) << "tick " << k << " channel " << i;

    const command_t& c = col.commands[k];
    EXPECT_EQ(c.tick, k);
    EXPECT_EQ(c.utime, utime_of(r));
    EXPECT_EQ(c.setpoint_name, "x_ref");
    EXPECT_EQ(c.setpoint, r.controller.setpoint);
    ASSERT_EQ(c.num_outputs, 1);
    EXPECT_EQ(c.names[0], "u");
    EXPECT_EQ(c.units[0], "1");
    EXPECT_EQ(c.values[0], r.command.value[0]);

    const controller_t& q = col.controllers[k];
    EXPECT_EQ(q.tick, k);
    EXPECT_EQ(q.controller, "pi");
    EXPECT_EQ(q.term_names, (std::vector<std::string>{"p", "i"}));
    ASSERT_EQ(q.terms.size(), 2u);
    EXPECT_EQ(q.terms[0], r.controller.term[0]);
    EXPECT_EQ(q.terms[1], r.controller.term[1]);
    EXPECT_EQ(q.setpoint, r.controller.setpoint);
    EXPECT_EQ(q.measurement, r.controller.measurement);
    EXPECT_EQ(q.error, r.controller.error);
    EXPECT_EQ(q.output_unsaturated, r.controller.output_unsaturated);
    EXPECT_EQ(q.output, r.controller.output);
    EXPECT_EQ(q.saturated, r.controller.saturated);
    EXPECT_EQ(q.integrator_held, r.controller.integrator_held);
  }

  ASSERT_EQ(col.states.size(), state_ticks.size());
  for (std::size_t i = 0; i < state_ticks.size(); ++i) {
    EXPECT_EQ(col.states[i].tick, state_ticks[i]);
    EXPECT_EQ(col.states[i].state, std::string(to_string(state_at(state_ticks[i]))));
  }
  EXPECT_EQ(col.states[0].event, "run_started");
  EXPECT_EQ(col.states[1].event, "");
  EXPECT_EQ(col.states[2].event, "profile_finished");
  EXPECT_EQ(col.states[2].state, "running");
  EXPECT_EQ(col.states[3].event, "limit_tripped");
  EXPECT_EQ(col.states[3].state, "faulted");
  const std::string& msg = col.states[3].message;
  EXPECT_NE(msg.find("x_r"), std::string::npos) << msg;
  EXPECT_NE(msg.find("0.1712 m"), std::string::npos) << msg;
  EXPECT_EQ(col.states[4].state, "stopped");

  ASSERT_EQ(col.timings.size(), 1u);
  const timing_t& tm = col.timings[0];
  const TimingSummary& ts = pushed[40].timing;
  EXPECT_EQ(tm.tick, 40);
  EXPECT_EQ(tm.utime, utime_of(pushed[40]));
  EXPECT_EQ(tm.period_ns, ts.period_ns);
  EXPECT_EQ(tm.overrun_policy, "skip");
  EXPECT_EQ(tm.ticks, ts.ticks);
  EXPECT_EQ(tm.overruns, ts.overruns);
  EXPECT_EQ(tm.missed_ticks, ts.missed_ticks);
  EXPECT_EQ(tm.dropped_records, 0);
  EXPECT_EQ(tm.latency_count, ts.wakeup_latency.count);
  EXPECT_EQ(tm.latency_max_ns, ts.wakeup_latency.max_ns);
  EXPECT_EQ(tm.latency_mean_ns, ts.wakeup_latency.mean_ns);
  EXPECT_EQ(tm.latency_p999_ns, ts.wakeup_latency.p999_ns);
  EXPECT_EQ(tm.compute_min_ns, ts.compute.min_ns);
  EXPECT_EQ(tm.compute_mean_ns, ts.compute.mean_ns);
  EXPECT_EQ(tm.compute_p99_ns, ts.compute.p99_ns);

  // The log: the same messages, same order, same bytes, timestamp = utime.
  const std::vector<LoggedEvent> logged = read_log(log_path);
  ASSERT_EQ(logged.size(), col.all.size());
  int sample_index = 0;
  for (std::size_t i = 0; i < logged.size(); ++i) {
    EXPECT_EQ(logged[i].channel, col.all[i].channel) << "event " << i;
    EXPECT_EQ(logged[i].bytes, col.all[i].bytes) << "event " << i << " on " << logged[i].channel;
    if (logged[i].channel == pub.channels().sample) {
      EXPECT_EQ(logged[i].timestamp, utime_of(pushed[sample_index++]));
    }
  }
  EXPECT_EQ(sample_index, kTicks);
}

TEST_F(TelemetryTest, FullQueueCountsDropsAndNeverBlocks) {
  const std::string log_path = (dir_ / "drops.lcm").string();
  TelemetryPublisher pub(make_meta(), "memq://", log_path, 4);  // thread not started
  int accepted = 0;
  for (int64_t k = 0; k < 10; ++k) accepted += pub.push(make_record(k)) ? 1 : 0;
  EXPECT_EQ(accepted, 4);
  EXPECT_EQ(pub.dropped(), 6);
  pub.stop();  // drains what was queued
  EXPECT_EQ(pub.published(), 4);
  std::vector<int64_t> ticks;
  for (const LoggedEvent& ev : read_log(log_path)) {
    if (ev.channel != pub.channels().sample) continue;
    sample_t s;
    ASSERT_GE(s.decode(ev.bytes.data(), 0, static_cast<int>(ev.bytes.size())), 0);
    ticks.push_back(s.tick);
  }
  EXPECT_EQ(ticks, (std::vector<int64_t>{0, 1, 2, 3}));
}

TEST_F(TelemetryTest, LogIsFlushedWhileRunning) {
  const std::string log_path = (dir_ / "flush.lcm").string();
  TelemetryPublisher pub(make_meta(), "memq://", log_path);
  pub.start();
  ASSERT_TRUE(pub.push(make_record(0)));  // a few hundred bytes: stays in stdio's buffer unless flushed
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);  // reached only on failure: the flush comes every 250 ms
  std::uintmax_t size = 0;
  while (size == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    size = fs::file_size(log_path);
  }
  EXPECT_GT(size, 0u) << "log not flushed within 3 s while the publisher runs";
  pub.stop();
}

TEST_F(TelemetryTest, BadUrlLogPathOrLayoutThrows) {
  try {
    TelemetryPublisher pub(make_meta(), "nosuchprovider://x", "");
    FAIL() << "no exception for a bad URL";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("nosuchprovider://x"), std::string::npos) << e.what();
  }
  EXPECT_THROW(TelemetryPublisher(make_meta(), "", ""), std::runtime_error);

  TelemetryMeta too_wide = make_meta();
  too_wide.layout.inputs.resize(kMaxInputs + 1, {"extra", "m"});
  EXPECT_THROW(TelemetryPublisher(too_wide, "memq://", ""), std::runtime_error);

  fs::create_directories(dir_);
  std::ofstream(dir_ / "plainfile") << "x";
  const std::string bad_log = (dir_ / "plainfile" / "run.lcm").string();  // parent is a file
  try {
    TelemetryPublisher pub(make_meta(), "memq://", bad_log);
    FAIL() << "no exception for an unwritable log path";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(bad_log), std::string::npos) << e.what();
  }
}

}  // namespace
