// Pieces `rigctl bench` sections share: latency summaries in microseconds,
// a bounded CPU load, child processes with their run time and peak memory,
// facts about the machine, and a scratch directory.
#pragma once

#include <sched.h>

#include <atomic>
#include <cstdint>
#include <string>
#include <thread>
#include <vector>

#include "rt/timing_summary.hpp"
#include "tools/bench/json.hpp"

namespace rigctl::bench {

// count, min/mean/p50/p99/p99.9/max in microseconds.
Json latency_json(const DistributionSummary& d);
// "p50 12.0 us, p99 40.0 us, p99.9 80.0 us, max 1.2 ms" style, for the console.
std::string latency_text(const DistributionSummary& d);
// a / b, or NaN (null in JSON) when b is 0.
double ratio(double a, double b);

// Percentiles of a histogram in 1 us bins (bin i holds [i, i+1) us, as
// cyclictest's -h writes it), with values beyond the last bin given as
// `overflows` at `max_us`. Same convention as rt/histogram.hpp: a percentile
// is the upper edge of its bin, clamped to [min, max].
DistributionSummary summary_from_us_histogram(const std::vector<int64_t>& counts, int64_t overflows, int64_t min_us,
                                              int64_t max_us, double mean_us);

// Busy threads (one per CPU by default) that stream through a private 8 MB
// buffer each: CPU time and cache pressure, at normal priority. They stop
// on stop(), on destruction, or after max_seconds, whichever comes first.
class CpuLoad {
 public:
  CpuLoad(int threads, double max_seconds);
  ~CpuLoad();
  CpuLoad(const CpuLoad&) = delete;
  CpuLoad& operator=(const CpuLoad&) = delete;
  void stop();
  int threads() const { return static_cast<int>(threads_.size()); }

 private:
  std::atomic<bool> stop_{false};
  std::vector<std::thread> threads_;
};

struct ChildResult {
  bool started = false;
  int exit_code = -1;     // -1: killed by a signal or not started
  int signal = 0;         // the signal that ended it, 0 if none
  bool timed_out = false; // we stopped it (time limit or stop flag)
  double wall_s = 0.0;
  double user_s = 0.0, system_s = 0.0;
  int64_t peak_rss_kb = 0;  // ru_maxrss of the child
  std::string error;        // why it could not be started
};

// Runs argv (PATH lookup) with stdout and stderr into output_path ("" for
// /dev/null) and waits for it; after timeout_s, or when `stop` becomes true,
// sends it SIGINT, then SIGKILL 2 s later. Only this child is signalled.
ChildResult run_child(const std::vector<std::string>& argv, const std::string& output_path, double timeout_s,
                      const std::atomic<bool>& stop);

bool on_path(const std::string& program);

// nproc, CPU model, kernel, OS, memory, load average, whether the kernel is PREEMPT_RT.
Json machine_json();
// Load average over the last minute (/proc/loadavg), or NaN.
double load_average_1min();

// "" when the calling process may give a thread SCHED_FIFO at `priority`
// (checked on a short-lived thread), else the reason.
std::string realtime_refusal(int priority);

// Pins the calling thread to one CPU until destroyed (then restores its
// mask). Threads started meanwhile inherit the pin: that is how the I/O
// benchmarks place a server and a client on the same or on different CPUs.
class PinnedScope {
 public:
  explicit PinnedScope(int cpu);
  ~PinnedScope();
  PinnedScope(const PinnedScope&) = delete;
  PinnedScope& operator=(const PinnedScope&) = delete;
  bool pinned() const { return pinned_; }

 private:
  bool pinned_ = false;
  cpu_set_t saved_{};
};

// Holds /dev/cpu_dma_latency at 0 (no deep CPU idle states) until destroyed,
// as the loop's real-time set-up does while it runs.
class DmaLatencyHold {
 public:
  DmaLatencyHold();
  ~DmaLatencyHold();
  DmaLatencyHold(const DmaLatencyHold&) = delete;
  DmaLatencyHold& operator=(const DmaLatencyHold&) = delete;
  bool held() const { return fd_ >= 0; }
  const std::string& reason() const { return reason_; }

 private:
  int fd_ = -1;
  std::string reason_;
};

// Cumulative CPU time of the whole machine (/proc/stat), for the share the
// hypervisor took away (steal) while something ran.
struct CpuTimes {
  uint64_t total = 0, steal = 0;
};
CpuTimes read_cpu_times();
// steal / total between two readings, or NaN.
double steal_fraction(const CpuTimes& before, const CpuTimes& after);

// A console table: columns padded to their widest cell, first column left
// aligned, the others right aligned.
class Table {
 public:
  explicit Table(std::vector<std::string> header) { rows_.push_back(std::move(header)); }
  void row(std::vector<std::string> cells) { rows_.push_back(std::move(cells)); }
  std::string text(const std::string& indent = "  ") const;

 private:
  std::vector<std::vector<std::string>> rows_;
};

// printf-style number formatting for tables ("-" for NaN).
std::string fmt(const char* format, double value);

// A fresh directory under the system temp dir, removed with its contents.
class ScratchDir {
 public:
  explicit ScratchDir(const std::string& tag);
  ~ScratchDir();
  ScratchDir(const ScratchDir&) = delete;
  ScratchDir& operator=(const ScratchDir&) = delete;
  const std::string& path() const { return path_; }
  std::string file(const std::string& name) const { return path_ + "/" + name; }

 private:
  std::string path_;
};

}  // namespace rigctl::bench
