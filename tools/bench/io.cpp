// I/O section, each path against the bare client a user would compare with:
//  * Modbus TCP on loopback: one I/O cycle of the rig's DAQ driver (read
//    every input, write the output, as planned from config/quarter_car.yaml)
//    against a bare libmodbus client doing the same requests at the same
//    period and priority, both against the simulated DAQ (SimModbusDaq).
//  * CAN: a frame's round trip over the seqpacket transport (CanTransport
//    both ends, an echo thread) against bare send/poll/recv on a socketpair.
//  * LCM udpm: TelemetryPublisher's throughput and the loss a subscriber
//    sees at 400 Hz and 10 kHz, inside a network namespace made for the
//    bench and deleted after it (never multicast on the host's interfaces).
#include <fcntl.h>
#include <modbus/modbus.h>
#include <poll.h>
#include <pthread.h>
#include <sched.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <optional>
#include <set>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "drivers/canopen/can_transport.hpp"
#include "drivers/modbus/modbus_daq.hpp"
#include "drivers/modbus/modbus_link.hpp"
#include "drivers/modbus/modbus_write_plan.hpp"
#include "drivers/sim/sim_modbus_daq.hpp"
#include "plant/quarter_car/quarter_car_plant.hpp"
#include "rigctl/sample_t.hpp"
#include "rt/histogram.hpp"
#include "rt/comms/telemetry_publisher.hpp"
#include "tools/bench/sections.hpp"

namespace rigctl::bench {

namespace {

using Clock = std::chrono::steady_clock;

int64_t mono_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

void sleep_until_ns(int64_t t) {
  const timespec ts{static_cast<time_t>(t / 1'000'000'000), static_cast<long>(t % 1'000'000'000)};
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

std::string set_fifo(int priority) {
  if (priority <= 0) return "normal scheduling";
  sched_param p{};
  p.sched_priority = priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p);
  return rc == 0 ? "SCHED_FIFO " + std::to_string(priority) : "best effort (SCHED_FIFO refused: " + std::string(std::strerror(rc)) + ")";
}

Json comparison_row(const DistributionSummary& ours, const DistributionSummary& bare) {
  Json r = Json::object();
  r["p50"] = ratio(static_cast<double>(ours.p50_ns), static_cast<double>(bare.p50_ns));
  r["p99"] = ratio(static_cast<double>(ours.p99_ns), static_cast<double>(bare.p99_ns));
  r["p999"] = ratio(static_cast<double>(ours.p999_ns), static_cast<double>(bare.p999_ns));
  r["max"] = ratio(static_cast<double>(ours.max_ns), static_cast<double>(bare.max_ns));
  return r;
}

std::vector<std::string> cells(const std::string& a, const std::string& b, const DistributionSummary& d) {
  return {a, b, fmt("%.1f", d.p50_ns / 1e3), fmt("%.1f", d.p99_ns / 1e3), fmt("%.1f", d.p999_ns / 1e3),
          fmt("%.1f", d.max_ns / 1e3), std::to_string(d.count)};
}

// ---------------------------------------------------------------------------
// Modbus

// Where the threads run: a loopback round trip is two thread wake-ups, and
// on this kind of VM a wake-up on the other CPU costs tens of microseconds,
// so unpinned runs mix two distributions at random. Each comparison is made
// with both ends on one CPU and with them on different CPUs.
struct Placement {
  std::string name;
  int server_cpu;
  int client_cpu;
};

std::vector<Placement> placements() {
  std::vector<Placement> p = {{"same_cpu", 0, 0}};
  if (sysconf(_SC_NPROCESSORS_ONLN) > 1) p.push_back({"cross_cpu", 1, 0});
  return p;
}

struct ModbusPair {
  Json json;
  DistributionSummary driver, bare;
};

ModbusPair modbus_pair(Context& ctx, const ModbusDaqConfig& server_config, const Placement& where, double seconds) {
  ModbusPair out;
  Json& j = out.json;
  j = Json::object();
  j["server_cpu"] = where.server_cpu;
  j["client_cpu"] = where.client_cpu;
  SimModbusDaq server(server_config);
  {
    PinnedScope pin(where.server_cpu);
    server.start();
  }
  const ModbusDaqConfig client = server.client_config();
  std::vector<double> inputs(client.inputs.size(), 0.0);
  for (std::size_t i = 0; i < inputs.size(); ++i) inputs[i] = 0.001 * static_cast<double>(i + 1);
  server.set_inputs(inputs.data(), inputs.size());
  const int64_t period_ns = std::llround(client.poll_period_s * 1e9);
  const int64_t cycles = std::llround(seconds / client.poll_period_s);

  // The driver: its I/O thread's own cycle times (ModbusDaq::io_latency).
  {
    ModbusDaq daq(client);
    {
      PinnedScope pin(where.client_cpu);  // the I/O thread starts here and keeps the pin
      daq.start(2.0);
    }
    const int64_t start = mono_ns();
    for (int64_t k = 1; k <= cycles && !ctx.stop.load(); ++k) {
      const double u = 0.1 * std::sin(static_cast<double>(k) * 0.01);
      daq.write_outputs(&u, 1);  // what the loop does each tick
      sleep_until_ns(start + k * period_ns);
    }
    out.driver = daq.io_latency();
    const ModbusDaqCounters c = daq.counters();
    daq.stop();
    Json d = Json::object();
    d["what"] = "ModbusDaq I/O thread, one cycle = every planned read + the output write";
    d["scheduling"] = client.io_priority > 0 ? "SCHED_FIFO " + std::to_string(client.io_priority) + " requested" : "normal";
    d["cycle_time"] = latency_json(out.driver);
    d["timeouts"] = c.timeouts;
    d["protocol_errors"] = c.protocol_errors;
    d["cycle_overruns"] = c.cycle_overruns;
    j["driver"] = d;
  }

  // A bare libmodbus client, same requests, period and priority.
  {
    std::vector<ModbusPoint> in_points, out_points;
    for (const auto& ch : client.inputs) in_points.push_back(ch.point);
    for (const auto& ch : client.outputs) out_points.push_back(ch.point);
    const ReadPlan reads = plan_reads(in_points, {client.max_gap, kMaxReadRegisters});
    const WritePlan writes = plan_writes(out_points);
    Json b = Json::object();
    std::string error;
    int64_t failures = 0;
    std::optional<PinnedScope> pin;
    pin.emplace(where.client_cpu);
    std::thread t([&] {
      b["scheduling"] = set_fifo(client.io_priority);
      modbus_t* mb = modbus_new_tcp_pi(client.connection.host.c_str(), std::to_string(client.connection.port).c_str());
      if (mb == nullptr) {
        error = "modbus_new_tcp_pi failed";
        return;
      }
      const auto timeout_us = static_cast<uint32_t>(std::llround(client.connection.response_timeout_s * 1e6));
      modbus_set_response_timeout(mb, timeout_us / 1000000u, timeout_us % 1000000u);
      if (modbus_connect(mb) != 0) {
        error = std::string("connect: ") + modbus_strerror(errno);
        modbus_free(mb);
        return;
      }
      DurationHistogram hist(1000, 20000);
      std::vector<uint16_t> buffer(kMaxReadRegisters);
      uint16_t out_regs[kMaxWriteRegisters] = {};
      int64_t next = mono_ns();
      for (int64_t k = 0; k < cycles && !ctx.stop.load(); ++k) {
        const int64_t t0 = mono_ns();
        bool ok = true;
        for (const auto& blk : reads.blocks) {
          modbus_set_slave(mb, blk.unit_id);
          const int rc = blk.type == RegisterType::kInputRegister
                             ? modbus_read_input_registers(mb, blk.address, blk.count, buffer.data())
                             : modbus_read_registers(mb, blk.address, blk.count, buffer.data());
          ok = ok && rc == blk.count;
        }
        out_regs[0] = static_cast<uint16_t>(k);
        for (const auto& blk : writes.blocks) {
          modbus_set_slave(mb, blk.unit_id);
          const int rc = blk.count == 1 ? modbus_write_register(mb, blk.address, out_regs[0])
                                        : modbus_write_registers(mb, blk.address, blk.count, out_regs);
          ok = ok && rc == (blk.count == 1 ? 1 : blk.count);
        }
        if (ok) {
          hist.record(mono_ns() - t0);
        } else {
          // The driver's recovery (ModbusLink::drain): a late reply must not
          // be taken for the next request's, or the client stays one reply
          // behind for good. Wait out one response timeout, then flush.
          ++failures;
          sleep_until_ns(mono_ns() + static_cast<int64_t>(timeout_us) * 1000);
          modbus_flush(mb);
        }
        next += period_ns;
        sleep_until_ns(next);
      }
      modbus_close(mb);
      modbus_free(mb);
      out.bare = hist.summary();
    });
    pin.reset();
    t.join();
    if (!error.empty()) {
      b["status"] = "error";
      b["error"] = error;
    }
    b["what"] = "bare libmodbus client loop (modbus_read_input_registers + modbus_write_register), same plan";
    b["cycle_time"] = latency_json(out.bare);
    b["failed_cycles"] = failures;
    j["bare_libmodbus"] = b;
  }
  server.stop();
  j["ratio_driver_over_bare"] = comparison_row(out.driver, out.bare);
  return out;
}

void ratio_row(Table& table, const Json& r) {
  table.row({"", "ratio", fmt("%.2f", r.find("p50")->number()), fmt("%.2f", r.find("p99")->number()),
             fmt("%.2f", r.find("p999")->number()), fmt("%.2f", r.find("max")->number()), ""});
}

Json modbus_bench(Context& ctx, Table& table) {
  const RigConfig config = load_rig_config(ctx.quarter_car_config);
  if (!config.modbus) return skipped(ctx.quarter_car_config + " has no modbus: section");
  ModbusDaqConfig server_config = *config.modbus;
  server_config.connection.transport = ModbusTransport::kTcp;
  server_config.connection.host = "127.0.0.1";
  server_config.connection.port = 0;
  const double seconds = ctx.pick(5.0, 0.5);

  Json j = Json::object();
  std::vector<ModbusPoint> in_points, out_points;
  for (const auto& ch : server_config.inputs) in_points.push_back(ch.point);
  for (const auto& ch : server_config.outputs) out_points.push_back(ch.point);
  const ReadPlan reads = plan_reads(in_points, {server_config.max_gap, kMaxReadRegisters});
  const WritePlan writes = plan_writes(out_points);
  std::string requests;
  for (const auto& b : reads.blocks) requests += (requests.empty() ? "" : ", ") + describe_request(false, b.type, b.unit_id, b.address, b.count);
  for (const auto& b : writes.blocks) requests += ", " + describe_request(true, RegisterType::kHoldingRegister, b.unit_id, b.address, b.count);
  j["server"] = "SimModbusDaq on 127.0.0.1 (normal priority)";
  j["cycle"] = requests;
  j["period_us"] = static_cast<int64_t>(std::llround(server_config.poll_period_s * 1e6));
  j["response_timeout_ms"] = server_config.connection.response_timeout_s * 1e3;
  j["seconds_each"] = seconds;
  for (const auto& where : placements()) {
    if (ctx.stop.load()) break;
    ModbusPair pair = modbus_pair(ctx, server_config, where, seconds);
    table.row(cells("Modbus TCP cycle, " + where.name, "rigctl driver", pair.driver));
    table.row(cells("", "bare libmodbus", pair.bare));
    ratio_row(table, pair.json["ratio_driver_over_bare"]);
    j[where.name] = pair.json;
  }
  j["status"] = "ok";
  return j;
}

// ---------------------------------------------------------------------------
// CAN over seqpacket

DistributionSummary can_round_trips(Context& ctx, bool through_transport, int64_t frames, int64_t period_ns,
                                    int64_t& lost, const Placement& where) {
  DurationHistogram hist(1000, 20000);
  lost = 0;
  std::optional<PinnedScope> pin;
  pin.emplace(where.server_cpu);  // the echo thread starts here
  if (through_transport) {
    auto ends = socketpair_seqpacket();
    CanTransport& a = ends.first;
    CanTransport& b = ends.second;
    std::thread echo([&b] {
      canopen::CanFrame f;
      for (;;) {
        const auto rx = b.receive(f, 200);
        if (rx == CanTransport::Rx::kFrame) {
          b.send(f);
        } else if (rx != CanTransport::Rx::kTimeout) {
          return;
        }
      }
    });
    pin.emplace(where.client_cpu);  // and the sender runs here
    int64_t next = mono_ns();
    for (int64_t k = 0; k < frames && !ctx.stop.load(); ++k) {
      canopen::CanFrame f = canopen::make_frame(0x201, {0x0f, 0x00, static_cast<uint8_t>(k), static_cast<uint8_t>(k >> 8)});
      canopen::CanFrame g;
      const int64_t t0 = mono_ns();
      a.send(f);
      if (a.receive(g, 100) == CanTransport::Rx::kFrame && g.data[2] == f.data[2]) {
        hist.record(mono_ns() - t0);
      } else {
        ++lost;
      }
      next += period_ns;
      sleep_until_ns(next);
    }
    a.shutdown();
    echo.join();
  } else {
    int sv[2];
    if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, sv) != 0) {
      throw std::runtime_error(std::string("socketpair: ") + std::strerror(errno));
    }
    std::thread echo([fd = sv[1]] {
      canopen::CanFrame f;
      pollfd p{fd, POLLIN, 0};
      for (;;) {
        p.revents = 0;
        const int rc = ::poll(&p, 1, 200);
        if (rc < 0 && errno == EINTR) continue;
        if (rc == 0) continue;
        if (rc < 0 || (p.revents & (POLLHUP | POLLERR)) != 0) return;
        const ssize_t n = ::recv(fd, &f, sizeof f, 0);
        if (n <= 0) return;
        ::send(fd, &f, sizeof f, MSG_DONTWAIT | MSG_NOSIGNAL);
      }
    });
    pin.emplace(where.client_cpu);
    int64_t next = mono_ns();
    pollfd p{sv[0], POLLIN, 0};
    for (int64_t k = 0; k < frames && !ctx.stop.load(); ++k) {
      canopen::CanFrame f = canopen::make_frame(0x201, {0x0f, 0x00, static_cast<uint8_t>(k), static_cast<uint8_t>(k >> 8)});
      canopen::CanFrame g;
      const int64_t t0 = mono_ns();
      ::send(sv[0], &f, sizeof f, MSG_DONTWAIT | MSG_NOSIGNAL);
      p.revents = 0;
      if (::poll(&p, 1, 100) == 1 && ::recv(sv[0], &g, sizeof g, 0) == static_cast<ssize_t>(sizeof g) &&
          g.data[2] == f.data[2]) {
        hist.record(mono_ns() - t0);
      } else {
        ++lost;
      }
      next += period_ns;
      sleep_until_ns(next);
    }
    ::shutdown(sv[0], SHUT_RDWR);
    echo.join();
    ::close(sv[0]);
    ::close(sv[1]);
  }
  return hist.summary();
}

Json can_bench(Context& ctx, Table& table) {
  const int64_t frames = ctx.pick<int64_t>(2000, 200);
  const int64_t period_ns = 2'500'000;
  Json j = Json::object();
  j["what"] = "16-byte struct can_frame sent, echoed by a second thread, received; one frame per 2.5 ms; normal priority";
  j["frames_each"] = frames;
  for (const auto& where : placements()) {
    if (ctx.stop.load()) break;
    int64_t lost_t = 0, lost_b = 0;
    const DistributionSummary t = can_round_trips(ctx, true, frames, period_ns, lost_t, where);
    const DistributionSummary b = can_round_trips(ctx, false, frames, period_ns, lost_b, where);
    Json p = Json::object();
    p["echo_cpu"] = where.server_cpu;
    p["sender_cpu"] = where.client_cpu;
    Json tj = Json::object();
    tj["round_trip"] = latency_json(t);
    tj["lost"] = lost_t;
    p["can_transport"] = tj;
    Json bj = Json::object();
    bj["round_trip"] = latency_json(b);
    bj["lost"] = lost_b;
    p["bare_socketpair"] = bj;
    p["ratio_transport_over_bare"] = comparison_row(t, b);
    table.row(cells("CAN frame round trip, " + where.name, "CanTransport (seqpacket)", t));
    table.row(cells("", "bare socketpair", b));
    ratio_row(table, p["ratio_transport_over_bare"]);
    j[where.name] = p;
  }
  j["status"] = "ok";
  return j;
}

// ---------------------------------------------------------------------------
// LCM udpm in a network namespace

constexpr const char* kUdpmUrl = "udpm://239.255.76.67:7667?ttl=0";

class Namespace {
 public:
  Namespace() {
    name_ = "rigctl-bench-" + std::to_string(::getpid());
    const std::vector<std::vector<std::string>> steps = {
        {"ip", "netns", "add", name_},
        {"ip", "netns", "exec", name_, "ip", "link", "set", "lo", "up"},
        {"ip", "netns", "exec", name_, "ip", "link", "set", "lo", "multicast", "on"},
        {"ip", "netns", "exec", name_, "ip", "route", "add", "224.0.0.0/4", "dev", "lo"},
    };
    for (const auto& step : steps) {
      const ChildResult r = run_child(step, "", 10.0, never_);
      if (step[2] == "add" && r.exit_code == 0) created_ = true;
      if (r.exit_code != 0) {
        std::string text;
        for (const auto& s : step) text += (text.empty() ? "" : " ") + s;
        error_ = "cannot set up a network namespace: '" + text + "' failed" + (r.error.empty() ? "" : " (" + r.error + ")");
        return;
      }
    }
  }
  ~Namespace() {
    if (created_) run_child({"ip", "netns", "del", name_}, "", 10.0, never_);
  }
  const std::string& error() const { return error_; }
  const std::string& name() const { return name_; }

  // Moves the calling thread into the namespace and checks it is there.
  std::string join() const {
    const std::string file = "/var/run/netns/" + name_;
    const int fd = ::open(file.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return "open " + file + ": " + std::strerror(errno);
    const int rc = ::setns(fd, CLONE_NEWNET);
    ::close(fd);
    if (rc != 0) return std::string("setns: ") + std::strerror(errno);
    struct stat want{}, have{};
    if (::stat(file.c_str(), &want) != 0 || ::stat("/proc/thread-self/ns/net", &have) != 0 || want.st_ino != have.st_ino) {
      return "thread is not in network namespace " + name_ + ": refusing to use multicast";
    }
    return "";
  }

 private:
  std::string name_;
  std::string error_;
  bool created_ = false;
  const std::atomic<bool> never_{false};
};

class SampleCounter {
 public:
  void handle(const lcm::ReceiveBuffer* rbuf, const std::string&) {
    rigctl::sample_t s;
    if (s.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) >= 0) ticks.insert(s.tick);
    bytes += rbuf->data_size;
  }
  void probe(const lcm::ReceiveBuffer*, const std::string&) { probed = true; }
  std::set<int64_t> ticks;
  std::atomic<bool> probed{false};
  uint64_t bytes = 0;
};

struct LcmScenario {
  std::string name;
  double rate_hz;  // 0: as fast as the publisher drains its queue
  int64_t records;
  int queue_capacity;  // subscriber's; 0 = LCM's default
};

TelemetryMeta bench_meta() {
  TelemetryMeta m;
  m.rig = "quarter_car";
  QuarterCarPlant plant(QuarterCarParams{});
  m.layout.inputs = plant.signals();
  m.layout.outputs = plant.commands();
  m.setpoint_name = "x_ref";
  m.controller_name = "pi";
  m.term_names = {"p", "i"};
  m.start_utime = 1'700'000'000'000'000;
  return m;
}

// In the namespace thread.
Json lcm_scenario(Context& ctx, const LcmScenario& sc) {
  Json j = Json::object();
  j["rate_hz"] = sc.rate_hz > 0 ? Json(sc.rate_hz) : Json("unpaced");
  j["records"] = sc.records;
  j["subscriber_queue_capacity"] = sc.queue_capacity > 0 ? Json(sc.queue_capacity) : Json("LCM default");
  const TelemetryMeta meta = bench_meta();
  const TelemetryChannels channels(meta.channel_prefix);

  lcm::LCM sub(kUdpmUrl);
  if (!sub.good()) throw std::runtime_error(std::string("LCM subscriber on ") + kUdpmUrl + " failed");
  SampleCounter counter;
  lcm::Subscription* s = sub.subscribe(channels.sample, &SampleCounter::handle, &counter);
  if (sc.queue_capacity > 0) s->setQueueCapacity(sc.queue_capacity);
  sub.subscribe("RIGCTL_BENCH_PROBE", &SampleCounter::probe, &counter);
  std::atomic<bool> done{false};
  std::thread rx([&] {
    while (!done.load()) sub.handleTimeout(20);
  });

  const auto queue = static_cast<std::size_t>(std::max<int64_t>(8192, sc.rate_hz > 0 ? static_cast<int64_t>(sc.rate_hz) : 8192));
  TelemetryPublisher pub(meta, kUdpmUrl, "", queue);
  const uint8_t probe = 1;
  const auto ready_deadline = Clock::now() + std::chrono::seconds(5);
  while (!counter.probed.load()) {
    if (Clock::now() > ready_deadline) {
      done = true;
      rx.join();
      throw std::runtime_error("LCM subscriber received nothing within 5 s inside the namespace");
    }
    pub.lcm().publish("RIGCTL_BENCH_PROBE", &probe, 1);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }

  TelemetryRecord r;
  r.state = RigState::kRunning;
  pub.start();
  const int64_t period_ns = sc.rate_hz > 0 ? std::llround(1e9 / sc.rate_hz) : 0;
  const int64_t start = mono_ns();
  int64_t full = 0;
  for (int64_t k = 0; k < sc.records && !ctx.stop.load(); ++k) {
    r.tick = k;
    r.sample.t_ns = k * 2'500'000;
    for (std::size_t i = 0; i < meta.layout.inputs.size(); ++i) r.sample.value[i] = 1e-3 * static_cast<double>(k + i);
    r.command.value[0] = 0.01 * static_cast<double>(k % 100);
    while (!pub.push(r)) {  // the queue is full: wait for the publisher (unpaced runs)
      ++full;
      std::this_thread::sleep_for(std::chrono::microseconds(100));
    }
    if (period_ns > 0) sleep_until_ns(start + (k + 1) * period_ns);
  }
  const int64_t pushed_ns = mono_ns() - start;
  while (pub.published() < sc.records && mono_ns() - start < pushed_ns + 10'000'000'000) {
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  const int64_t published_ns = mono_ns() - start;
  const int64_t published = pub.published();
  pub.stop();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // stragglers
  done = true;
  rx.join();

  const auto received = static_cast<int64_t>(counter.ticks.size());
  j["pushed_rate_hz"] = ratio(static_cast<double>(sc.records), pushed_ns * 1e-9);
  j["published"] = published;
  j["publish_throughput_records_per_s"] = ratio(static_cast<double>(published), published_ns * 1e-9);
  j["lcm_messages_per_record"] = 3;  // sample, command, controller
  j["sample_message_bytes"] = counter.ticks.empty() ? Json() : Json(static_cast<double>(counter.bytes) / static_cast<double>(received));
  j["received"] = received;
  j["lost"] = published - received;
  j["loss_fraction"] = ratio(static_cast<double>(published - received), static_cast<double>(published));
  j["producer_waits_on_full_queue"] = full;
  j["status"] = "ok";
  return j;
}

Json lcm_bench(Context& ctx, Table& lcm_table) {
  if (::geteuid() != 0) return skipped("needs root to create a network namespace (udpm is never used on the host's interfaces)");
  if (!on_path("ip")) return skipped("no 'ip' program (iproute2)");
  Namespace ns;
  if (!ns.error().empty()) return skipped(ns.error());
  Json j = Json::object();
  j["url"] = kUdpmUrl;
  j["namespace"] = ns.name() + " (created for the bench, deleted after it)";
  j["what"] = "TelemetryPublisher (its own thread) publishing each record as sample, command and controller messages; an in-process subscriber on its own LCM instance counts distinct sample ticks";
  const std::vector<LcmScenario> scenarios = {
      {"400Hz", 400.0, ctx.pick<int64_t>(4000, 200), 0},
      {"10kHz", 10000.0, ctx.pick<int64_t>(100000, 2000), 0},
      {"10kHz_queue10000", 10000.0, ctx.pick<int64_t>(100000, 2000), 10000},
      {"unpaced_queue10000", 0.0, ctx.pick<int64_t>(100000, 5000), 10000},
  };
  Json runs = Json::object();
  std::string error;
  std::thread t([&] {
    error = ns.join();
    if (!error.empty()) return;
    for (const auto& sc : scenarios) {
      if (ctx.stop.load()) break;
      try {
        runs[sc.name] = lcm_scenario(ctx, sc);
      } catch (const std::exception& e) {
        Json e_json = Json::object();
        e_json["status"] = "error";
        e_json["error"] = std::string(e.what());
        runs[sc.name] = e_json;
      }
    }
  });
  t.join();
  if (!error.empty()) return skipped(error);
  for (const auto& sc : scenarios) {
    const Json* r = runs.find(sc.name);
    if (r == nullptr) continue;
    if (r->find("status")->string() != "ok") {
      lcm_table.row({sc.name, "error: " + r->find("error")->string()});
      continue;
    }
    lcm_table.row({sc.name, sc.queue_capacity > 0 ? std::to_string(sc.queue_capacity) : "default",
                   std::to_string(sc.records), fmt("%.0f", r->find("pushed_rate_hz")->number()),
                   fmt("%.0f", r->find("publish_throughput_records_per_s")->number()),
                   fmt("%.0f", r->find("lost")->number()), fmt("%.2e", r->find("loss_fraction")->number())});
  }
  j["runs"] = runs;
  j["status"] = "ok";
  return j;
}

}  // namespace

Section io_section() {
  return {"io", "io: Modbus TCP and CAN round trips against bare clients, LCM udpm throughput and loss", [](Context& ctx) {
            Json j = Json::object();
            // As during a run (rt/realtime.cpp): no deep idle states, whose
            // exit latency would dominate every wake-up measured here.
            const DmaLatencyHold dma;
            j["cpu_dma_latency"] = dma.held() ? "held at 0 us" : "not held: " + dma.reason();
            ctx.out << "  cpu_dma_latency " << (dma.held() ? "held at 0 us" : "not held (" + dma.reason() + ")") << "\n";
            Table table({"path", "client", "p50 us", "p99 us", "p99.9 us", "max us", "count"});
            auto guarded = [&](const char* name, auto&& fn) {
              try {
                j[name] = fn();
              } catch (const std::exception& e) {
                Json err = Json::object();
                err["status"] = "error";
                err["error"] = std::string(e.what());
                j[name] = err;
                ctx.out << "  " << name << ": error: " << e.what() << "\n";
              }
              const Json* st = j[name].find("status");
              if (st != nullptr && st->string() == "skipped") {
                ctx.out << "  " << name << ": skipped: " << j[name].find("reason")->string() << "\n";
              }
            };
            guarded("modbus_tcp", [&] { return modbus_bench(ctx, table); });
            guarded("can_seqpacket", [&] { return can_bench(ctx, table); });
            ctx.out << table.text();
            Table lcm_table({"lcm udpm", "sub queue", "records", "pushed/s", "published/s", "lost", "loss"});
            guarded("lcm_udpm", [&] { return lcm_bench(ctx, lcm_table); });
            ctx.out << lcm_table.text();
            return j;
          }};
}

}  // namespace rigctl::bench
