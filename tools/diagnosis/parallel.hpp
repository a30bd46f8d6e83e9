// Independent work of the diagnosis spread over the machine's cores: the
// columns of a finite-difference Jacobian, the candidates of a screening
// round, the refits of the best few. Internal to the diagnosis.
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
// docs/diagnosis.md 4 is set for one).
constexpr std::size_t kDiagnosisWorkers = 2;

// Calls work(index, worker) once for every index in [0, count), on up to
// `workers` threads (worker 0 is the calling thread), each taking the next
// index when it is free: items of very different cost (a replay of one
// sub-model or of both) still keep both cores busy. The first exception
// thrown by any item is rethrown here once all workers have stopped.
template <class Work>
void parallel_for(std::size_t count, Work work, std::size_t workers = kDiagnosisWorkers) {
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
  workers = std::max<std::size_t>(1, std::min(workers, count));
  std::vector<std::thread> helpers;
  for (std::size_t k = 1; k < workers; ++k) helpers.emplace_back(run, k);
  run(0);
  for (auto& t : helpers) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace rigctl::diag
