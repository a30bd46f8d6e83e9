#include "tools/run/console_status.hpp"

#include <chrono>
#include <cstdio>

namespace rigctl {

ConsoleStatus::ConsoleStatus(const TelemetryPublisher& publisher, const TelemetryMeta& meta, int feedback_input,
                             double duration_s, std::ostream& out)
    : publisher_(publisher), meta_(meta), feedback_input_(feedback_input), duration_s_(duration_s), out_(out),
      thread_([this] { thread_main(); }) {}

ConsoleStatus::~ConsoleStatus() {
  running_.store(false);
  thread_.join();
}

std::string ConsoleStatus::line(const TelemetryRecord& r) const {
  const auto& in = meta_.layout.inputs[static_cast<std::size_t>(feedback_input_)];
  char buf[256];
  std::snprintf(buf, sizeof buf, "  t %6.1f/%.1f s | %-15s | %s %9.5f %s | %s %9.5f %s | error %9.5f | %s %+.4f",
                static_cast<double>(r.sample.t_ns) * 1e-9, duration_s_, std::string(to_string(r.safety_state)).c_str(),
                meta_.setpoint_name.c_str(),
                r.controller.setpoint, in.unit.c_str(), in.name.c_str(), r.controller.measurement, in.unit.c_str(),
                r.controller.error, meta_.layout.outputs.empty() ? "out" : meta_.layout.outputs[0].name.c_str(),
                r.controller.output);
  return buf;
}

void ConsoleStatus::thread_main() {
  using namespace std::chrono_literals;
  auto next = std::chrono::steady_clock::now() + 1s;
  while (running_.load()) {
    std::this_thread::sleep_for(50ms);
    if (std::chrono::steady_clock::now() < next) continue;
    next += 1s;
    if (const auto r = publisher_.latest()) {
      out_ << line(*r) << "\n";
      out_.flush();
    }
  }
}

}  // namespace rigctl
