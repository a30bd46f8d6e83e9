// The Modbus DAQ client (ModbusDaq) against the simulated module
// (SimModbusDaq), both real libmodbus over TCP on 127.0.0.1 (a free port).
// No test asserts on this machine's timing:
// conditions are polled with deadlines, the times in the test configs are
// sized for a loaded machine, and "never blocks" is counted in context
// switches, not in microseconds.
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <new>
#include <cmath>
#include <functional>
#include <iostream>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "config/config_reader.hpp"
#include "config/modbus_reader.hpp"
#include "drivers/modbus/modbus_daq.hpp"
#include "drivers/modbus/modbus_link.hpp"
#include "drivers/sim/sim_modbus_daq.hpp"
#include "rt/histogram.hpp"
#include "wait_until.hpp"

using namespace rigctl;
using rigctl::test::wait_until;

// Counts this thread's heap allocations, to show the loop-side calls make none
// (the I/O and server threads allocate freely and are not counted).
namespace {
thread_local long t_allocations = 0;
}
[[gnu::noinline]] void* operator new(std::size_t n) {
  ++t_allocations;
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void* operator new[](std::size_t n) { return operator new(n); }
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

ModbusChannel channel(const std::string& name, int unit, RegisterType type, int address, DataFormat format,
                      WordOrder order, Calibration cal, double safe = 0.0) {
  ModbusChannel c;
  c.name = name;
  c.unit = "1";
  c.point = {unit, type, address, format, order};
  c.calibration = std::move(cal);
  c.safe = safe;
  return c;
}

TableCalibration table(std::vector<double> raw, std::vector<double> si) { return TableCalibration(raw, si); }

using enum DataFormat;
using enum WordOrder;
constexpr auto kIn = RegisterType::kInputRegister;
constexpr auto kHold = RegisterType::kHoldingRegister;

// Every data format and word order, both calibration kinds, an input kept in
// holding registers and a second unit (three read blocks).
ModbusDaqConfig rig_config() {
  ModbusDaqConfig c;
  c.connection.transport = ModbusTransport::kTcp;
  c.connection.host = "127.0.0.1";
  c.connection.port = 0;
  // Generous for a LAN: a server or client thread that a loaded 2-core
  // machine leaves waiting must not look like a timeout, nor a silent link
  // (no answer for a reconnect interval) like a dead one. The fault tests
  // make their timeouts happen (a silent server, late replies).
  c.connection.response_timeout_s = 0.2;
  c.connection.reconnect_interval_s = 1.0;
  c.poll_period_s = 0.0025;
  c.max_sample_age_s = 0.25;  // generous: "fresh" must not flicker under load
  c.max_gap = 4;
  c.inputs = {
      channel("a", 1, kIn, 0, kInt16, kHighFirst, LinearCalibration(1e-4, 0.01)),
      channel("b", 1, kIn, 1, kUint16, kHighFirstByteSwapped, table({0, 1000, 65535}, {0.0, 1.0e7, 2.5e7})),
      channel("c", 1, kIn, 2, kInt32, kLowFirst, LinearCalibration(1e-6, 0.0)),
      channel("d", 1, kIn, 4, kUint32, kLowFirstByteSwapped, LinearCalibration(0.5, -100.0)),
      channel("e", 1, kIn, 6, kFloat32, kHighFirst, table({-10, 0, 10}, {-2.0e4, 0.0, 1.0e4})),
      channel("f", 1, kIn, 8, kFloat32, kLowFirst, LinearCalibration(1.0, 0.0)),
      channel("g", 1, kIn, 10, kFloat32, kHighFirstByteSwapped, LinearCalibration(2.0, 1.0)),
      channel("h", 1, kHold, 20, kInt32, kHighFirst, LinearCalibration(1e-3, 0.0)),
      channel("i", 2, kIn, 0, kInt16, kHighFirst, LinearCalibration(1e-3, 0.0)),
  };
  c.outputs = {
      channel("u", 1, kHold, 0, kInt16, kHighFirst, LinearCalibration(3.0518e-5, 0.0), 0.0),
      channel("v", 1, kHold, 1, kFloat32, kLowFirst, table({0, 5, 10}, {0.0, 1.0e6, 3.0e6}), 2.0e5),
  };
  return c;
}

// Quantisation of each input above, in SI: half a count for integers.
const std::vector<double> kTolerance = {0.5e-4, 0.5e4, 0.5e-6, 0.25, 1e-3, 1e-6, 1e-6, 0.5e-3, 0.5e-3};
const std::vector<double> kValuesA = {-0.1, 5.0e6, -0.123456, 1.0e6, 5000.0, 0.37, -3.5, 12.345, -1.5};
const std::vector<double> kValuesB = {0.2, 1.2e7, 0.5, 3.0e4, -1.5e4, -42.0, 8.0, -7.5, 2.0};

// What the chain SI -> raw -> registers -> raw -> SI must give, through the codec.
double round_trip(const ModbusChannel& ch, double si) {
  uint16_t regs[2] = {0, 0};
  (void)encode_registers(ch.calibration.to_raw(si), ch.point.format, ch.point.order, regs);
  return ch.calibration.to_si(decode_registers(regs, ch.point.format, ch.point.order));
}

// A simulated module and a client connected to it.
class ModbusDaqTest : public ::testing::Test {
 protected:
  void SetUp() override {
    sim_ = std::make_unique<SimModbusDaq>(rig_config());
    sim_->start();
    sim_->set_inputs(kValuesA.data(), kValuesA.size());
  }
  void TearDown() override {
    if (daq_) daq_->stop();
    sim_->stop();
  }

  void start_client(ModbusDaqConfig c) {
    daq_ = std::make_unique<ModbusDaq>(std::move(c));
    daq_->start(10.0);
  }
  void start_client() { start_client(sim_->client_config()); }

  Sample read() {
    Sample s;
    daq_->read_inputs(s, 0, ModbusDaq::now_ns());
    return s;
  }
  bool all_fresh() { return read().status == 0; }
  bool all_stale() {
    const auto s = read();
    return s.status == (1u << daq_->input_count()) - 1;
  }
  bool shows(const std::vector<double>& values) {
    const Sample s = read();
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (((s.status >> i) & 1u) || std::abs(s.value[i] - values[i]) > kTolerance[i]) return false;
    }
    return true;
  }
  // Accumulates diagnostics() events (each call returns only the new ones).
  std::string events() {
    for (auto& e : daq_->diagnostics().events) events_ += e + "\n";
    return events_;
  }

  std::unique_ptr<SimModbusDaq> sim_;
  std::unique_ptr<ModbusDaq> daq_;
  std::string events_;
};

TEST_F(ModbusDaqTest, InputsArriveInSiThroughEveryFormatOrderAndCalibration) {
  start_client();
  const auto& inputs = rig_config().inputs;
  for (const auto* values : {&kValuesA, &kValuesB}) {
    sim_->set_inputs(values->data(), values->size());
    ASSERT_TRUE(wait_until([&] { return shows(*values); })) << "inputs never matched";
    const Sample s = read();
    for (std::size_t i = 0; i < inputs.size(); ++i) {
      SCOPED_TRACE(inputs[i].name);
      EXPECT_NEAR(s.value[i], (*values)[i], kTolerance[i]);
      EXPECT_NEAR(s.value[i], round_trip(inputs[i], (*values)[i]), 1e-9 * std::max(1.0, std::abs(s.value[i])));
    }
  }
  // Placed at an offset in the sample, other bits untouched.
  Sample s;
  s.status = 1u;
  daq_->read_inputs(s, 3, ModbusDaq::now_ns());
  EXPECT_EQ(s.status, 1u);
  EXPECT_NEAR(s.value[3], kValuesB[0], kTolerance[0]);
  EXPECT_NEAR(s.value[3 + 8], kValuesB[8], kTolerance[8]);
  // Out of the sample's range: nothing written.
  Sample untouched;
  EXPECT_EQ(daq_->read_inputs(untouched, kMaxInputs - 2, ModbusDaq::now_ns()), std::numeric_limits<int64_t>::max());
  EXPECT_EQ(untouched.value[kMaxInputs - 1], 0.0);

  const auto c = daq_->counters();
  EXPECT_TRUE(c.connected);
  EXPECT_GT(c.reads, 0);
  EXPECT_EQ(c.exceptions, 0);
}

TEST_F(ModbusDaqTest, OutputsWrittenByTheClientArriveDecodedOnTheServer) {
  start_client();
  double out[2] = {0, 0};
  // Before the loop posts anything, the safe values are written.
  ASSERT_TRUE(wait_until([&] {
    sim_->outputs(out);
    return out[0] == 0.0 && std::abs(out[1] - 2.0e5) < 1.0;
  }));
  const double command[2] = {0.25, 1.5e6};
  daq_->write_outputs(command, 2);
  ASSERT_TRUE(wait_until([&] {
    sim_->outputs(out);
    return std::abs(out[0] - 0.25) < 3.1e-5 && std::abs(out[1] - 1.5e6) < 1.0;
  })) << out[0] << " " << out[1];

  // A NaN is a fault: that output gets its safe value, the other keeps its command.
  const double bad[2] = {kNaN, 2.0e6};
  daq_->write_outputs(bad, 2);
  ASSERT_TRUE(wait_until([&] {
    sim_->outputs(out);
    return out[0] == 0.0 && std::abs(out[1] - 2.0e6) < 1.0;
  }));
  EXPECT_GE(daq_->counters().rejected_outputs, 1);
  EXPECT_NE(events().find("output u: 1 NaN commands replaced by the safe value"), std::string::npos) << events();

  // Beyond the int16 range: clamped and counted.
  const double big[2] = {5.0, 0.0};
  daq_->write_outputs(big, 2);
  ASSERT_TRUE(wait_until([&] {
    sim_->outputs(out);
    return std::abs(out[0] - 32767 * 3.0518e-5) < 1e-9;
  }));
  EXPECT_GT(daq_->counters().saturated_outputs, 0);

  // make_safe() posts the safe values; stop() writes them as its last act.
  daq_->make_safe();
  ASSERT_TRUE(wait_until([&] {
    sim_->outputs(out);
    return out[0] == 0.0 && std::abs(out[1] - 2.0e5) < 1.0;
  }));
  daq_->write_outputs(command, 2);
  ASSERT_TRUE(wait_until([&] {
    sim_->outputs(out);
    return std::abs(out[0] - 0.25) < 3.1e-5;
  }));
  // Nothing else writes after stop(); waited for, as the server applies the
  // write on its own thread.
  daq_->stop();
  EXPECT_TRUE(wait_until([&] {
    sim_->outputs(out);
    return out[0] == 0.0 && std::abs(out[1] - 2.0e5) < 1.0;
  })) << out[0] << " " << out[1];
}

TEST_F(ModbusDaqTest, LoopSideReadNeverBlocksWhileTheIoThreadWaitsForATimeout) {
  auto c = sim_->client_config();
  c.connection.response_timeout_s = 0.3;  // the I/O thread sits 300 ms in each request
  c.connection.reconnect_interval_s = 60.0;  // and never gives up on the connection here
  start_client(c);
  sim_->set_silent(true);
  ASSERT_TRUE(wait_until([&] { return sim_->requests() > 0 && daq_->counters().timeouts > 0; }));

  const int64_t timeouts_before = daq_->counters().timeouts;
  DurationHistogram calls(100, 100000);  // 0.1 us bins up to 10 ms
  Sample s;
  // A call that waited for the I/O thread (a lock it holds through its
  // 300 ms request) would sleep: a voluntary context switch of this thread.
  // Counted, not timed: a loaded machine preempts calls (involuntary
  // switches, any length), but cannot make one sleep.
  const auto voluntary_switches = [] {
    rusage u{};
    getrusage(RUSAGE_THREAD, &u);
    return u.ru_nvcsw;
  };
  const long switches_before = voluntary_switches();
  const int64_t end = ModbusDaq::now_ns() + 1'500'000'000;  // spans a whole timeout + drain of 600 ms
  while (ModbusDaq::now_ns() < end) {
    const int64_t t0 = ModbusDaq::now_ns();
    daq_->read_inputs(s, 0, t0);
    calls.record(ModbusDaq::now_ns() - t0);
  }
  const long switches = voluntary_switches() - switches_before;
  const auto summary = calls.summary();
  std::cout << "read_inputs during a timeout: " << summary.count << " calls, p50 " << summary.p50_ns << " ns, p99 "
            << summary.p99_ns << " ns, max " << summary.max_ns << " ns, " << switches << " voluntary context switches\n";
  // The I/O thread really was stuck in timeouts meanwhile.
  EXPECT_GT(daq_->counters().timeouts, timeouts_before);
  EXPECT_EQ(switches, 0) << "a loop-side read slept, waiting for something";
  // A waiting call would take up to 300 ms; preemption on a loaded machine
  // delays a few calls of the hundreds of thousands, not the 99th percentile.
  EXPECT_LT(summary.p99_ns, 500'000);
}

TEST_F(ModbusDaqTest, LoopSideCallsDoNotAllocate) {
  start_client();
  ASSERT_TRUE(wait_until([&] { return shows(kValuesA); }));
  Sample s;
  const double command[2] = {0.1, kNaN};
  const long before = t_allocations;
  for (int i = 0; i < 2000; ++i) {
    const int64_t now = ModbusDaq::now_ns();
    daq_->read_inputs(s, 0, now);
    daq_->write_outputs(command, 2);
    (void)daq_->output_age_ns(now);
    if (i % 100 == 0) daq_->make_safe();
    if (i == 1000) sim_->set_silent(true);  // and while requests time out
  }
  EXPECT_EQ(t_allocations - before, 0);
}

TEST_F(ModbusDaqTest, SilentServerMakesInputsStaleAndIsCountedAndLogged) {
  start_client();
  ASSERT_TRUE(wait_until([&] { return shows(kValuesA); }));
  const double max_age = sim_->client_config().max_sample_age_s;

  sim_->set_silent(true);
  ASSERT_TRUE(wait_until([&] { return all_stale(); }));
  // Stale as soon as older than max_sample_age: read_inputs judges the age
  // at the time it is given, so when that is is the caller's (no wall-clock
  // bound here). The last values are still there, flagged, and their age
  // is past the limit.
  Sample s = read();
  EXPECT_NEAR(s.value[0], kValuesA[0], kTolerance[0]);
  EXPECT_GT(daq_->read_inputs(s, 0, ModbusDaq::now_ns()), static_cast<int64_t>(max_age * 1e9));

  // The I/O thread's side: each request waits out its 200 ms timeout, so
  // the read's timeout may be logged after the inputs went stale; waited for.
  const std::string timeout_event =
      "modbus " + sim_->endpoint() + ": timeout (no reply within 200 ms) reading input registers 0-11 of unit 1";
  EXPECT_TRUE(wait_until([&] {
    const std::string log = events();
    return log.find(timeout_event) != std::string::npos && log.find("samples with stale inputs") != std::string::npos;
  })) << events();
  const auto c = daq_->counters();
  EXPECT_GT(c.timeouts, 0);
  EXPECT_GT(c.stale_samples, 0);

  sim_->set_silent(false);
  ASSERT_TRUE(wait_until([&] { return all_fresh(); }));
  EXPECT_TRUE(wait_until([&] { return events().find("works again") != std::string::npos; })) << events();
}

TEST_F(ModbusDaqTest, LateRepliesTimeOutAndDoNotPoisonLaterRequests) {
  auto c = sim_->client_config();
  c.connection.reconnect_interval_s = 60.0;  // keep this connection: a new one would hide a backlog
  start_client(c);
  ASSERT_TRUE(wait_until([&] { return shows(kValuesA); }));
  sim_->set_reply_delay(0.6);  // three response timeouts
  ASSERT_TRUE(wait_until([&] { return all_stale(); }));
  EXPECT_GT(daq_->counters().timeouts, 0);
  // Replies now arrive long after their request; once on time again, the
  // client must read current values, not a backlog of old replies.
  sim_->set_reply_delay(0.0);
  sim_->set_inputs(kValuesB.data(), kValuesB.size());
  ASSERT_TRUE(wait_until([&] { return shows(kValuesB); }));
  EXPECT_EQ(daq_->counters().connection_losses, 0);
}

TEST_F(ModbusDaqTest, OneLateReplyDoesNotLeaveTheConnectionOneReplyBehind) {
  // One reply later than the timeout is consumed by the next request (wrong
  // transaction id). If the client then only flushed at once, its own reply,
  // still on its way, would poison the request after, and so on forever.
  auto c = sim_->client_config();
  c.connection.reconnect_interval_s = 60.0;  // a reconnect would hide the desynchronisation
  start_client(c);
  // Every reply takes 2 ms (well inside the 200 ms timeout), like a busy
  // module's: a reply then always arrives after the client has handled a
  // mismatch, which is when a plain flush cannot catch it.
  sim_->set_reply_delay(0.002);
  ASSERT_TRUE(wait_until([&] { return shows(kValuesA); }));
  for (int episode = 0; episode < 3; ++episode) {
    const int64_t timeouts = daq_->counters().timeouts;
    sim_->set_reply_delay(0.3);  // 1.5 response timeouts, for the request being served now
    ASSERT_TRUE(wait_until([&] { return daq_->counters().timeouts > timeouts; }));
    sim_->set_reply_delay(0.002);
    const double* values = episode % 2 == 0 ? kValuesB.data() : kValuesA.data();
    sim_->set_inputs(values, kValuesA.size());
    ASSERT_TRUE(wait_until([&] { return shows(episode % 2 == 0 ? kValuesB : kValuesA); }))
        << "episode " << episode << ": " << daq_->counters().protocol_errors << " bad replies\n" << events();
    // And it stays in step: no further bad replies over the next 100 reads
    // (counted, not slept for: a slow machine just takes longer to do them).
    const int64_t bad = daq_->counters().protocol_errors;
    const int64_t reads = daq_->counters().reads;
    ASSERT_TRUE(wait_until([&] { return daq_->counters().reads >= reads + 100; }))
        << "episode " << episode << ": " << daq_->counters().protocol_errors - bad << " more bad replies";
    EXPECT_EQ(daq_->counters().protocol_errors, bad) << "episode " << episode;
  }
  EXPECT_EQ(daq_->counters().connection_losses, 0);
}

TEST_F(ModbusDaqTest, ExceptionResponsesAreCountedAndNameTheRegisters) {
  start_client();
  ASSERT_TRUE(wait_until([&] { return shows(kValuesA); }));
  sim_->add_exception({1, kIn, 5, 5, 0x02});  // touches the block of input registers 0-11 of unit 1
  ASSERT_TRUE(wait_until([&] { return daq_->counters().exceptions > 0; }));
  const std::string expected =
      "modbus " + sim_->endpoint() + ": exception 'Illegal data address' reading input registers 0-11 of unit 1";
  ASSERT_TRUE(wait_until([&] { return events().find(expected) != std::string::npos; })) << events();

  // Only that block's inputs go stale; the other blocks are still read.
  ASSERT_TRUE(wait_until([&] { return read().status == 0x7Fu; }));
  sim_->set_inputs(kValuesB.data(), kValuesB.size());
  ASSERT_TRUE(wait_until([&] {
    const Sample s = read();
    return std::abs(s.value[7] - kValuesB[7]) <= kTolerance[7] && std::abs(s.value[8] - kValuesB[8]) <= kTolerance[8];
  }));
  EXPECT_TRUE(daq_->counters().connected);  // an exception is an answer: the link is fine

  // Another code on the output write: the outputs stop being refreshed, and
  // their age says so.
  const int64_t max_age = static_cast<int64_t>(rig_config().max_sample_age_s * 1e9);
  EXPECT_LT(daq_->output_age_ns(ModbusDaq::now_ns()), max_age);
  sim_->add_exception({1, kHold, 0, 0, 0x04});
  ASSERT_TRUE(wait_until([&] {
    return events().find("exception '" + modbus_exception_text(4) +
                         "' writing holding registers 0-2 of unit 1") != std::string::npos;
  })) << events();
  ASSERT_TRUE(wait_until([&] { return daq_->output_age_ns(ModbusDaq::now_ns()) > max_age; }));

  sim_->clear_exceptions();
  ASSERT_TRUE(wait_until([&] { return shows(kValuesB); }));
  ASSERT_TRUE(wait_until([&] { return daq_->output_age_ns(ModbusDaq::now_ns()) < max_age; }));
}

TEST_F(ModbusDaqTest, DroppedConnectionReconnectsWithoutRestart) {
  start_client();
  ASSERT_TRUE(wait_until([&] { return shows(kValuesA); }));
  EXPECT_EQ(daq_->counters().reconnects, 0);

  sim_->drop_connections(0.6);  // and refuse new ones for a while
  ASSERT_TRUE(wait_until([&] { return daq_->counters().connection_losses > 0; }));
  // While disconnected the inputs age until stale.
  ASSERT_TRUE(wait_until([&] { return all_stale(); }));
  sim_->set_inputs(kValuesB.data(), kValuesB.size());
  // Fresh values again from a new connection, same ModbusDaq object.
  ASSERT_TRUE(wait_until([&] { return shows(kValuesB) && daq_->counters().connected; }));
  const auto c = daq_->counters();
  EXPECT_GE(c.reconnects, 1);
  EXPECT_GE(sim_->connections(), 2);
  const std::string log = events();
  EXPECT_NE(log.find("connection lost"), std::string::npos) << log;
  EXPECT_NE(log.find("reconnected"), std::string::npos) << log;
  // Outputs flow again too.
  const double command[2] = {-0.5, 1.0e6};
  daq_->write_outputs(command, 2);
  double out[2];
  ASSERT_TRUE(wait_until([&] {
    sim_->outputs(out);
    return std::abs(out[0] + 0.5) < 3.1e-5;
  }));
}

TEST_F(ModbusDaqTest, StuckAndOutOfRangeRegistersAreVisibleInSi) {
  start_client();
  ASSERT_TRUE(wait_until([&] { return shows(kValuesA); }));
  sim_->set_stuck(0, true);
  sim_->force_raw(8, 32767);  // the ADC rail of input i
  sim_->force_raw(5, kNaN);   // a float module reporting NaN for f
  sim_->set_inputs(kValuesB.data(), kValuesB.size());
  ASSERT_TRUE(wait_until([&] {
    const Sample s = read();
    return std::abs(s.value[1] - kValuesB[1]) <= kTolerance[1] && std::abs(s.value[8] - 32.767) < 1e-9;
  }));
  const Sample s = read();
  EXPECT_NEAR(s.value[0], kValuesA[0], kTolerance[0]);  // frozen, and it looks fresh: nothing on the wire says otherwise
  EXPECT_EQ(s.status & 1u, 0u);
  EXPECT_DOUBLE_EQ(s.value[8], 32.767);  // rail value in SI, for the limit check to judge
  EXPECT_EQ((s.status >> 8) & 1u, 0u);
  EXPECT_TRUE(std::isnan(s.value[5]));  // not a number: flagged invalid
  EXPECT_EQ((s.status >> 5) & 1u, 1u);

  sim_->clear_faults();
  sim_->set_inputs(kValuesB.data(), kValuesB.size());
  ASSERT_TRUE(wait_until([&] { return shows(kValuesB); }));
}

TEST_F(ModbusDaqTest, IoLatencyIsMeasured) {
  auto c = sim_->client_config();
  c.io_priority = 10;  // applied when permitted, else an event; either way the client runs
  start_client(c);
  ASSERT_TRUE(wait_until([&] { return daq_->io_latency().count >= 400; }));
  const auto l = daq_->io_latency();
  std::cout << "I/O cycle (3 reads + 1 write) on loopback: " << l.count << " cycles, p50 " << l.p50_ns / 1000.0
            << " us, p99 " << l.p99_ns / 1000.0 << " us, p99.9 " << l.p999_ns / 1000.0 << " us, max "
            << l.max_ns / 1000.0 << " us\n";
  EXPECT_GT(l.min_ns, 0);
  EXPECT_LE(l.p50_ns, l.p99_ns);
  EXPECT_LE(l.p99_ns, l.max_ns);
  const auto d = daq_->diagnostics();
  auto counter = [&](const std::string& name) {
    for (const auto& [n, v] : d.counters) {
      if (n == name) return v;
    }
    return int64_t{-1};
  };
  EXPECT_EQ(counter("modbus_connected"), 1);
  EXPECT_GE(counter("modbus_cycles"), 400);
  EXPECT_GE(counter("modbus_reads"), 3 * 400);
  EXPECT_EQ(counter("modbus_reconnects"), 0);
}

// Lock-step (`rigctl run --lock-step` against `rig-sim --lock-step`): after
// start()'s sample, each read_inputs() is one exchange, outputs first, so
// the far side's exchange k sees the command posted before read k and read
// k returns what exchange k put in the registers, whatever the clock does.
TEST(ModbusDaqLockStep, EachReadIsOneExchangeThatCarriesTheCommandBeforeIt) {
  SimModbusDaq sim(rig_config());
  std::vector<double> seen;  // the far side's u at each exchange (its server thread; read after stop)
  std::vector<double> values = kValuesA;
  int64_t exchanges = 0;
  sim.set_exchange_hook([&] {
    double out[2] = {0, 0};
    sim.outputs(out);
    seen.push_back(out[0]);
    values[0] = 1e-3 * static_cast<double>(exchanges++);  // input a: the exchange's number
    sim.set_inputs(values.data(), values.size());
  });
  sim.start();
  ModbusDaqConfig c = sim.client_config();
  c.lock_step = true;
  ModbusDaq daq(c);
  daq.start(10.0);
  constexpr int kReads = 50;
  for (int k = 0; k < kReads; ++k) {
    Sample s;
    daq.read_inputs(s, 0, ModbusDaq::now_ns());
    EXPECT_EQ(s.status, 0u) << "read " << k << ": every input from this read's exchange";
    EXPECT_NEAR(s.value[0], 1e-3 * k, 0.5e-4) << "read " << k << " is exchange " << k;
    const double u = 0.01 * (k + 1);
    daq.write_outputs(&u, 1);
  }
  daq.stop();  // its last act writes the safe values: a write, not an exchange
  sim.stop();
  ASSERT_EQ(seen.size(), static_cast<std::size_t>(kReads)) << "start()'s read and one per later read";
  EXPECT_EQ(seen[0], 0.0) << "start() wrote the safe value";
  for (std::size_t k = 1; k < seen.size(); ++k) {
    EXPECT_NEAR(seen[k], 0.01 * static_cast<double>(k), 3.1e-5) << "exchange " << k << " carries read " << k - 1 << "'s command";
  }
}

TEST(ModbusDaqStart, AgainstAClosedPortThrowsNamingHostAndPort) {
  // A port nobody listens on: bind one, note it, close it.
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  socklen_t len = sizeof addr;
  getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  close(fd);

  auto c = rig_config();
  c.connection.port = ntohs(addr.sin_port);
  ModbusDaq daq(c);
  try {
    daq.start(2.0);  // the I/O thread's first attempt fails at once; a loaded machine may start it late
    FAIL() << "start() succeeded against a closed port";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("127.0.0.1:" + std::to_string(c.connection.port)), std::string::npos) << what;
    EXPECT_NE(what.find("Connection refused"), std::string::npos) << what;
  }
  EXPECT_GT(daq.counters().connect_failures, 0);
  EXPECT_FALSE(daq.counters().connected);
}

TEST(ModbusDaqConfig, ConstructorRejectsBadConfigs) {
  auto c = rig_config();
  c.outputs[1].point.type = kIn;
  EXPECT_THROW(ModbusDaq{c}, std::invalid_argument);
  c = rig_config();
  c.outputs[1].point.address = 0;  // overlaps u
  EXPECT_THROW(ModbusDaq{c}, std::invalid_argument);
  c = rig_config();
  c.max_sample_age_s = c.poll_period_s / 2;
  EXPECT_THROW(ModbusDaq{c}, std::invalid_argument);
  c = rig_config();
  c.connection.transport = ModbusTransport::kRtu;  // no device
  EXPECT_THROW(ModbusDaq{c}, std::invalid_argument);
}

}  // namespace
