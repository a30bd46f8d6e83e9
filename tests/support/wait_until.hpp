// Waiting for an event in a test: poll a condition until it holds. The
// timeout is a deadline for something that never happens, reached only when
// the test fails, so it is generous (a loaded machine may take seconds for
// what an idle one does in milliseconds); a test never sleeps a fixed time
// and then asserts.
#pragma once

#include <chrono>
#include <functional>
#include <thread>

namespace rigctl::test {

inline bool wait_until(const std::function<bool()>& done, double timeout_s = 30.0) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return done();
}

}  // namespace rigctl::test
