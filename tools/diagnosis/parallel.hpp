// Independent work of the diagnosis spread over the machine's cores: the
// columns of a finite-difference Jacobian, the candidates of a screening
// round, the refits of the best few. Internal to the diagnosis.
//
// One diagnosis owns one ThreadBudget of `--threads` threads (the calling
// thread included). The loops nest (a screening round's candidates each fit
// with a Jacobian whose columns are parallel too); a loop borrows only the
// threads the budget has spare, so nested loops never run more threads than
// the budget: inside an outer loop that holds every thread, an inner one runs
// on its caller's thread; once the outer loop's helpers run out of items and
// hand their threads back, the inner loops started after that use them (the
// third refit of a round gets both cores for its last Jacobians).
#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <vector>

namespace rigctl::diag {

// The rig is diagnosed on a 2-core PC (the speed target of
// docs/diagnosis.md 4 is set for one): the default of --threads.
constexpr std::size_t kDefaultDiagnosisThreads = 2;

class ThreadBudget {
 public:
  explicit ThreadBudget(std::size_t threads = kDefaultDiagnosisThreads)
      : threads_(std::max<std::size_t>(1, threads)), spare_(threads_ - 1) {}
  ThreadBudget(const ThreadBudget&) = delete;
  ThreadBudget& operator=(const ThreadBudget&) = delete;

  std::size_t threads() const { return threads_; }
  // Up to `want` spare threads, taken from the budget (possibly none).
  std::size_t take(std::size_t want) {
    std::size_t have = spare_.load();
    for (;;) {
      const std::size_t n = std::min(want, have);
      if (n == 0) return 0;
      if (spare_.compare_exchange_weak(have, have - n)) return n;
    }
  }
  void give_back(std::size_t n) { spare_ += n; }

 private:
  std::size_t threads_;
  std::atomic<std::size_t> spare_;
};

// Calls work(index, worker) once for every index in [0, count), on the
// calling thread (worker 0) and on as many threads as the budget has spare
// (workers 1..), each taking the next index when it is free: items of very
// different cost (a replay of one sub-model or of both) still keep the cores
// busy. worker < budget.threads(). A helper hands its thread back to the
// budget as soon as no item is left for it. The first exception thrown by any
// item is rethrown here once all workers have stopped.
template <class Work>
void parallel_for(ThreadBudget& budget, std::size_t count, Work work) {
  std::atomic<std::size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto run = [&](std::size_t worker) {
    for (std::size_t i = next++; i < count; i = next++) {
      try {
        work(i, worker);
      } catch (...) {
        std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
        next = count;  // the others stop after their current item
      }
    }
  };
  const std::size_t helpers_wanted = count > 1 ? std::min(count - 1, budget.threads() - 1) : 0;
  const std::size_t taken = budget.take(helpers_wanted);
  std::vector<std::thread> helpers;
  // A worker's number is its slot among this loop's threads: buffers indexed
  // by it belong to this loop (the caller allocates them per call).
  for (std::size_t k = 1; k <= taken; ++k)
    helpers.emplace_back([&, k] {
      run(k);
      budget.give_back(1);
    });
  run(0);
  for (auto& t : helpers) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace rigctl::diag
