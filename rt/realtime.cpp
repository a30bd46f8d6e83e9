#include "rt/realtime.hpp"

#include <fcntl.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>

namespace rigctl {

namespace {
std::string error_text(int err) { return std::string(std::strerror(err)); }

// Touch a stack region now so that page faults do not happen on the first
// deep call inside the loop (the pages stay resident under mlockall).
void prefault_stack() {
  constexpr std::size_t kBytes = 256 * 1024;
  volatile unsigned char buffer[kBytes];
  for (std::size_t i = 0; i < kBytes; i += 4096) buffer[i] = static_cast<unsigned char>(i);
  (void)buffer[0];
}
}  // namespace

int set_fifo_priority(std::thread& thread, int priority) {
  sched_param param{};
  param.sched_priority = priority;
  return pthread_setschedparam(thread.native_handle(), SCHED_FIFO, &param);
}

ScopedFifoPriority::ScopedFifoPriority(int priority) {
  if (priority <= 0) return;
  sched_param old{};
  error_ = pthread_getschedparam(pthread_self(), &old_policy_, &old);
  if (error_ != 0) return;
  old_priority_ = old.sched_priority;
  sched_param param{};
  param.sched_priority = priority;
  error_ = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  changed_ = error_ == 0;
}

ScopedFifoPriority::~ScopedFifoPriority() {
  if (!changed_) return;
  sched_param old{};
  old.sched_priority = old_priority_;
  pthread_setschedparam(pthread_self(), old_policy_, &old);
}

RealtimeSession::RealtimeSession(const RealtimeConfig& config) {
  if (!config.enabled) {
    warnings_.push_back("real-time set-up disabled in config: running best effort");
    return;
  }
  if (config.lock_memory) {
    if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
      applied_.push_back("memory locked (mlockall)");
      prefault_stack();
    } else {
      warnings_.push_back("mlockall failed (" + error_text(errno) +
                          "): page faults may delay ticks; run as root or raise the memlock limit");
    }
  }
  if (config.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(config.cpu, &set);
    const int rc = pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
    if (rc == 0) {
      applied_.push_back("loop pinned to CPU " + std::to_string(config.cpu));
    } else {
      warnings_.push_back("cannot pin the loop to CPU " + std::to_string(config.cpu) + " (" + error_text(rc) + ")");
    }
  }
  sched_param param{};
  param.sched_priority = config.priority;
  const int rc = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  if (rc == 0) {
    applied_.push_back("SCHED_FIFO priority " + std::to_string(config.priority));
  } else {
    warnings_.push_back("SCHED_FIFO priority " + std::to_string(config.priority) + " refused (" + error_text(rc) +
                        "): the loop runs at normal priority and will see more jitter; run as root or set rtprio");
  }
  if (config.hold_cpu_dma_latency) {
    dma_latency_fd_ = open("/dev/cpu_dma_latency", O_WRONLY | O_CLOEXEC);
    const int32_t zero = 0;
    if (dma_latency_fd_ >= 0 && write(dma_latency_fd_, &zero, sizeof(zero)) == sizeof(zero)) {
      applied_.push_back("cpu_dma_latency held at 0 us");
    } else {
      warnings_.push_back("cannot hold /dev/cpu_dma_latency at 0 (" + error_text(errno) +
                          "): deep CPU idle states may add wake-up latency");
      if (dma_latency_fd_ >= 0) close(dma_latency_fd_);
      dma_latency_fd_ = -1;
    }
  }
}

RealtimeSession::~RealtimeSession() {
  if (dma_latency_fd_ >= 0) close(dma_latency_fd_);
}

}  // namespace rigctl
