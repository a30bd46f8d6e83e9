// Process and thread set-up for real-time operation: lock memory, SCHED_FIFO,
// CPU affinity, and hold the CPU out of deep idle states. Each step that the
// system refuses (not root, no rtprio limit) becomes a warning: the loop then
// runs best effort rather than not at all.
#pragma once

#include <string>
#include <thread>
#include <vector>

namespace rigctl {

struct RealtimeConfig {
  bool enabled = true;
  int priority = 80;           // SCHED_FIFO priority 1..99
  bool lock_memory = true;     // mlockall(MCL_CURRENT | MCL_FUTURE)
  int cpu = -1;                // pin the loop thread to this CPU; -1 = no pinning
  bool hold_cpu_dma_latency = true;  // keep /dev/cpu_dma_latency at 0 while running
};

// Gives a running thread SCHED_FIFO at `priority` (an I/O thread just below
// the loop). Returns 0 or the error number; the caller reports a refusal and
// the thread runs best effort.
int set_fifo_priority(std::thread& thread, int priority);

// Gives the calling thread SCHED_FIFO at `priority` for a while (a start-up
// that must keep a deadline, e.g. a heartbeat a device watches), and its
// old policy back when destroyed. error() is 0 or the error number of a
// refusal (the thread then runs best effort); priority 0 changes nothing.
class ScopedFifoPriority {
 public:
  explicit ScopedFifoPriority(int priority);
  ~ScopedFifoPriority();
  ScopedFifoPriority(const ScopedFifoPriority&) = delete;
  ScopedFifoPriority& operator=(const ScopedFifoPriority&) = delete;
  int error() const { return error_; }

 private:
  bool changed_ = false;
  int error_ = 0;
  int old_policy_ = 0;
  int old_priority_ = 0;
};

// Holds what was acquired (the cpu_dma_latency file) until destroyed.
class RealtimeSession {
 public:
  // Applies the config to the calling thread (call it from the loop thread,
  // after other threads are started: they keep normal priority).
  explicit RealtimeSession(const RealtimeConfig& config);
  ~RealtimeSession();
  RealtimeSession(const RealtimeSession&) = delete;
  RealtimeSession& operator=(const RealtimeSession&) = delete;

  const std::vector<std::string>& warnings() const { return warnings_; }
  const std::vector<std::string>& applied() const { return applied_; }

 private:
  std::vector<std::string> warnings_;
  std::vector<std::string> applied_;
  int dma_latency_fd_ = -1;
};

}  // namespace rigctl
