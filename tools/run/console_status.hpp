// Once a second during a paced run, one line on the console with rig time,
// demand, feedback and command, so a person sees the rig run. Reads the
// publisher's newest record from its own thread; the loop is not involved.
#pragma once

#include <atomic>
#include <ostream>
#include <string>
#include <thread>

#include "rt/comms/telemetry_publisher.hpp"

namespace rigctl {

class ConsoleStatus {
 public:
  ConsoleStatus(const TelemetryPublisher& publisher, const TelemetryMeta& meta, int feedback_input,
                double duration_s, std::ostream& out);
  ~ConsoleStatus();
  ConsoleStatus(const ConsoleStatus&) = delete;
  ConsoleStatus& operator=(const ConsoleStatus&) = delete;

  // The line for one record (also used by tests).
  std::string line(const TelemetryRecord& r) const;

 private:
  void thread_main();

  const TelemetryPublisher& publisher_;
  const TelemetryMeta& meta_;
  int feedback_input_;
  double duration_s_;
  std::ostream& out_;
  std::atomic<bool> running_{true};
  std::thread thread_;
};

}  // namespace rigctl
