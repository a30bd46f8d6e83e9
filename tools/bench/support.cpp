#include "tools/bench/support.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <signal.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/utsname.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

extern char** environ;

namespace rigctl::bench {

namespace fs = std::filesystem;

Json latency_json(const DistributionSummary& d) {
  Json j = Json::object();
  j["count"] = d.count;
  j["min_us"] = d.min_ns / 1e3;
  j["mean_us"] = d.mean_ns / 1e3;
  j["p50_us"] = d.p50_ns / 1e3;
  j["p99_us"] = d.p99_ns / 1e3;
  j["p999_us"] = d.p999_ns / 1e3;
  j["max_us"] = d.max_ns / 1e3;
  return j;
}

namespace {
std::string us_text(int64_t ns) {
  char buf[32];
  if (ns >= 1'000'000) {
    std::snprintf(buf, sizeof buf, "%.2f ms", ns / 1e6);
  } else {
    std::snprintf(buf, sizeof buf, "%.1f us", ns / 1e3);
  }
  return buf;
}
}  // namespace

std::string latency_text(const DistributionSummary& d) {
  return "p50 " + us_text(d.p50_ns) + ", p99 " + us_text(d.p99_ns) + ", p99.9 " + us_text(d.p999_ns) + ", max " +
         us_text(d.max_ns) + " (" + std::to_string(d.count) + ")";
}

double ratio(double a, double b) { return b != 0.0 ? a / b : std::numeric_limits<double>::quiet_NaN(); }

DistributionSummary summary_from_us_histogram(const std::vector<int64_t>& counts, int64_t overflows, int64_t min_us,
                                              int64_t max_us, double mean_us) {
  DistributionSummary s;
  int64_t total = overflows;
  for (const int64_t c : counts) total += c;
  s.count = total;
  if (total == 0) return s;
  s.min_ns = min_us * 1000;
  s.max_ns = max_us * 1000;
  s.mean_ns = mean_us * 1000.0;
  auto percentile = [&](double p) -> int64_t {
    const auto rank = std::max<int64_t>(1, static_cast<int64_t>(std::ceil(p * static_cast<double>(total))));
    int64_t seen = 0;
    for (std::size_t i = 0; i < counts.size(); ++i) {
      seen += counts[i];
      if (seen >= rank) return std::clamp<int64_t>(static_cast<int64_t>(i + 1) * 1000, s.min_ns, s.max_ns);
    }
    return s.max_ns;
  };
  s.p50_ns = percentile(0.50);
  s.p99_ns = percentile(0.99);
  s.p999_ns = percentile(0.999);
  return s;
}

// ---------------------------------------------------------------------------

CpuLoad::CpuLoad(int threads, double max_seconds) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(max_seconds);
  for (int i = 0; i < threads; ++i) {
    threads_.emplace_back([this, deadline] {
      constexpr std::size_t kWords = (8u << 20) / sizeof(uint64_t);
      std::vector<uint64_t> buffer(kWords, 1);
      uint64_t x = 88172645463325252ull;
      while (!stop_.load(std::memory_order_relaxed) && std::chrono::steady_clock::now() < deadline) {
        // One pass: a cache line at a time, with some arithmetic per line.
        for (std::size_t w = 0; w < kWords; w += 8) {
          x ^= x << 13;
          x ^= x >> 7;
          x ^= x << 17;
          buffer[w] += x;
        }
      }
      volatile uint64_t sink = buffer[x % kWords];
      (void)sink;
    });
  }
}

CpuLoad::~CpuLoad() { stop(); }

void CpuLoad::stop() {
  stop_ = true;
  for (auto& t : threads_) {
    if (t.joinable()) t.join();
  }
  threads_.clear();
}

// ---------------------------------------------------------------------------

ChildResult run_child(const std::vector<std::string>& argv, const std::string& output_path, double timeout_s,
                      const std::atomic<bool>& stop) {
  ChildResult r;
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  const std::string out = output_path.empty() ? "/dev/null" : output_path;
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  // The child starts with default signal handling and scheduling, whatever
  // the calling thread has.
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  sigset_t none, defaults;
  sigemptyset(&none);
  sigemptyset(&defaults);
  for (const int s : {SIGINT, SIGTERM, SIGPIPE, SIGHUP}) sigaddset(&defaults, s);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setsigdefault(&attr, &defaults);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETSIGDEF);

  const auto start = std::chrono::steady_clock::now();
  pid_t pid = -1;
  const int rc = posix_spawnp(&pid, args[0], &actions, &attr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  if (rc != 0) {
    r.error = std::string("cannot start ") + argv[0] + ": " + std::strerror(rc);
    return r;
  }
  r.started = true;

  int status = 0;
  rusage usage{};
  bool interrupted = false;
  auto interrupted_at = start;
  for (;;) {
    const pid_t done = wait4(pid, &status, WNOHANG, &usage);
    if (done == pid) break;
    if (done < 0 && errno != EINTR) {
      r.error = std::string("wait4: ") + std::strerror(errno);
      return r;
    }
    const auto now = std::chrono::steady_clock::now();
    const double elapsed = std::chrono::duration<double>(now - start).count();
    if (!interrupted && (elapsed > timeout_s || stop.load())) {
      ::kill(pid, SIGINT);
      interrupted = true;
      interrupted_at = now;
      r.timed_out = true;
    } else if (interrupted && now - interrupted_at > std::chrono::seconds(2)) {
      ::kill(pid, SIGKILL);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.user_s = static_cast<double>(usage.ru_utime.tv_sec) + usage.ru_utime.tv_usec * 1e-6;
  r.system_s = static_cast<double>(usage.ru_stime.tv_sec) + usage.ru_stime.tv_usec * 1e-6;
  r.peak_rss_kb = usage.ru_maxrss;
  if (WIFEXITED(status)) r.exit_code = WEXITSTATUS(status);
  if (WIFSIGNALED(status)) r.signal = WTERMSIG(status);
  return r;
}

bool on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path != nullptr ? path : "/usr/bin:/bin");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (!dir.empty() && ::access((dir + "/" + program).c_str(), X_OK) == 0) return true;
  }
  return false;
}

namespace {

std::string first_line_value(const std::string& file, const std::string& key) {
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind(key, 0) != 0) continue;
    auto pos = line.find_first_of(":=", key.size());
    if (pos == std::string::npos) continue;
    std::string v = line.substr(pos + 1);
    v.erase(0, v.find_first_not_of(" \t\""));
    while (!v.empty() && (v.back() == '"' || v.back() == ' ')) v.pop_back();
    return v;
  }
  return "";
}

}  // namespace

double load_average_1min() {
  std::ifstream in("/proc/loadavg");
  double v = std::numeric_limits<double>::quiet_NaN();
  in >> v;
  return v;
}

Json machine_json() {
  Json m = Json::object();
  m["nproc"] = static_cast<int64_t>(sysconf(_SC_NPROCESSORS_ONLN));
  m["cpu_model"] = first_line_value("/proc/cpuinfo", "model name");
  utsname u{};
  if (uname(&u) == 0) {
    m["kernel"] = std::string(u.release);
    m["kernel_version"] = std::string(u.version);
    m["preempt_rt"] = std::string(u.version).find("PREEMPT_RT") != std::string::npos;
    m["arch"] = std::string(u.machine);
  }
  m["os"] = first_line_value("/etc/os-release", "PRETTY_NAME");
  const std::string mem = first_line_value("/proc/meminfo", "MemTotal");
  m["memory_total_kb"] = mem.empty() ? Json() : Json(static_cast<int64_t>(std::atoll(mem.c_str())));
  m["load_average_1min_at_start"] = load_average_1min();
  return m;
}

std::string realtime_refusal(int priority) {
  std::string reason;
  std::thread probe([&] {
    sched_param param{};
    param.sched_priority = priority;
    const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
    if (rc != 0) reason = "SCHED_FIFO priority " + std::to_string(priority) + " refused: " + std::strerror(rc);
  });
  probe.join();
  return reason;
}

PinnedScope::PinnedScope(int cpu) {
  if (pthread_getaffinity_np(pthread_self(), sizeof saved_, &saved_) != 0) return;
  cpu_set_t one;
  CPU_ZERO(&one);
  CPU_SET(cpu, &one);
  pinned_ = pthread_setaffinity_np(pthread_self(), sizeof one, &one) == 0;
}

PinnedScope::~PinnedScope() {
  if (pinned_) pthread_setaffinity_np(pthread_self(), sizeof saved_, &saved_);
}

DmaLatencyHold::DmaLatencyHold() {
  fd_ = ::open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
  const int32_t zero = 0;
  if (fd_ < 0 || ::write(fd_, &zero, sizeof zero) != sizeof zero) {
    reason_ = std::string("/dev/cpu_dma_latency: ") + std::strerror(errno);
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
}

DmaLatencyHold::~DmaLatencyHold() {
  if (fd_ >= 0) ::close(fd_);
}

CpuTimes read_cpu_times() {
  std::ifstream in("/proc/stat");
  std::string cpu;
  in >> cpu;
  CpuTimes t;
  if (cpu != "cpu") return t;
  // user nice system idle iowait irq softirq steal (guest times are inside user)
  for (int i = 0; i < 8; ++i) {
    uint64_t v = 0;
    if (!(in >> v)) break;
    t.total += v;
    if (i == 7) t.steal = v;
  }
  return t;
}

double steal_fraction(const CpuTimes& before, const CpuTimes& after) {
  if (after.total <= before.total) return std::numeric_limits<double>::quiet_NaN();
  return static_cast<double>(after.steal - before.steal) / static_cast<double>(after.total - before.total);
}

std::string Table::text(const std::string& indent) const {
  std::vector<std::size_t> width;
  for (const auto& r : rows_) {
    if (width.size() < r.size()) width.resize(r.size(), 0);
    for (std::size_t i = 0; i < r.size(); ++i) width[i] = std::max(width[i], r[i].size());
  }
  std::string out;
  for (const auto& r : rows_) {
    out += indent;
    for (std::size_t i = 0; i < r.size(); ++i) {
      const std::string pad(width[i] - r[i].size(), ' ');
      out += i == 0 ? r[i] + pad : "  " + pad + r[i];
    }
    out += "\n";
  }
  return out;
}

std::string fmt(const char* format, double value) {
  if (!std::isfinite(value)) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, format, value);
  return buf;
}

ScratchDir::ScratchDir(const std::string& tag) {
  for (int i = 0;; ++i) {
    fs::path p = fs::temp_directory_path() / ("rigctl-bench-" + tag + "-" + std::to_string(::getpid()) + "-" + std::to_string(i));
    std::error_code ec;
    if (fs::create_directory(p, ec)) {
      path_ = p.string();
      return;
    }
    if (i > 100) throw std::runtime_error("cannot make a scratch directory under " + fs::temp_directory_path().string());
  }
}

ScratchDir::~ScratchDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

}  // namespace rigctl::bench
