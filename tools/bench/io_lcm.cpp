// LCM udpm: TelemetryPublisher's throughput and the loss a subscriber sees
// at 400 Hz and 10 kHz, inside a network namespace made for the bench and
// deleted after it (never multicast on the host's interfaces).
#include <fcntl.h>
#include <sched.h>
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <set>
#include <thread>

#include <lcm/lcm-cpp.hpp>

#include "plant/quarter_car/quarter_car_plant.hpp"
#include "rigctl/sample_t.hpp"
#include "rt/comms/telemetry_publisher.hpp"
#include "tools/bench/io_support.hpp"

namespace rigctl::bench::io {

namespace {

using Clock = std::chrono::steady_clock;

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

}  // namespace

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

}  // namespace rigctl::bench::io
