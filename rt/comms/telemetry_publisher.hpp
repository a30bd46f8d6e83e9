// The non-real-time side of telemetry: a thread that drains the loop's
// lock-free queue, encodes LCM messages, publishes them on the configured LCM
// URL and writes the same events into an LCM log file (lcm-logger format).
#pragma once

#include <atomic>
#include <functional>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "rt/driver.hpp"
#include "rt/bounded_handoff.hpp"
#include "rt/queue_full_policy.hpp"
#include "rt/sample.hpp"
#include "rt/telemetry_record.hpp"
#include "rt/comms/telemetry_sink.hpp"
#include "rt/comms/telemetry_tap.hpp"

namespace lcm {
class LCM;
class LogFile;
}  // namespace lcm

namespace rigctl {

// Fixed facts about a run that every message needs; set once before start().
struct TelemetryMeta {
  std::string rig;                 // "quarter_car"
  ChannelLayout layout;            // names/units of sample inputs and command outputs
  std::string setpoint_name;       // "x_ref"; with several control channels the first's, "x_ref_1"
  // The demands of the control channels after the first ("x_ref_2", ...):
  // published on <prefix>CHANNELS (lcmtypes/rigctl_channels_t.lcm); empty
  // for a one-channel rig, which publishes no such message.
  std::vector<std::string> more_setpoint_names;
  std::string controller_name;     // "pi"
  std::vector<std::string> term_names;  // controller terms, e.g. {"p", "i"}
  std::string channel_prefix = "RIGCTL_";
  std::string overrun_policy = "skip";
  // A full queue: kDrop for paced runs, kWait (backpressure) in simulated
  // time (rt/queue_full_policy.hpp). Published in every timing message.
  QueueFullPolicy queue_policy = QueueFullPolicy::kDrop;
  int64_t period_ns = 2'500'000;
  // Wall-clock time of tick 0 [us since the epoch]. Message utime and log
  // event timestamps are start_utime + rig time, so a --fast run and a paced
  // run of the same config give the same log apart from this offset, and
  // lcm-logplayer replays either at the rig's real speed.
  int64_t start_utime = 0;
  // A test procedure's steps (their names and kinds, by index) and its
  // programmed test cycles: RIGCTL_PROCEDURE names the present step.
  std::vector<std::string> procedure_step_names, procedure_step_kinds;
  int64_t procedure_cycles = 0;
};

// LCM channel names, given the prefix.
struct TelemetryChannels {
  std::string sample, command, controller, timing, state, driver, procedure, channels;
  explicit TelemetryChannels(const std::string& prefix)
      : sample(prefix + "SAMPLE"), command(prefix + "COMMAND"), controller(prefix + "CONTROLLER"),
        timing(prefix + "TIMING"), state(prefix + "STATE"), driver(prefix + "DRIVER"), procedure(prefix + "PROCEDURE"),
        channels(prefix + "CHANNELS") {}
};

class TelemetryPublisher final : public TelemetrySink {
 public:
  // lcm_url: e.g. "memq://" or "udpm://239.255.76.67:7667?ttl=0". log_path:
  // LCM log file to write ("" = no log). Throws std::runtime_error naming the
  // URL or path when either cannot be opened.
  TelemetryPublisher(TelemetryMeta meta, const std::string& lcm_url, const std::string& log_path,
                     std::size_t queue_capacity = 8192);
  ~TelemetryPublisher();
  TelemetryPublisher(const TelemetryPublisher&) = delete;
  TelemetryPublisher& operator=(const TelemetryPublisher&) = delete;

  // Loop side. kDrop: never blocks, returns false and counts a drop when
  // full. kWait: waits for the publisher thread to make room.
  bool push(const TelemetryRecord& record) noexcept override;

  // Polled about once a second (and at stop) for the driver's counters and
  // events, published on channels().driver and logged. Set before start().
  void set_diagnostics_source(std::function<DriverDiagnostics()> source, std::string driver_name);

  // A consumer of every message besides the bus and the log (the Foxglove
  // server, a benchmark's clock); called on the publisher thread, in the
  // order added. Add before start().
  void add_tap(TelemetryTap* tap) { taps_.push_back(tap); }

  // From any non-real-time thread (the event log's writer): an event to
  // publish on the STATE channel (and log), e.g. a failing event log.
  void report_event(const std::string& event, const std::string& message);
  int64_t log_failures() const { return log_failures_.load(); }

  void start();  // starts the publisher thread
  void stop();   // drains the queue, flushes and closes the log, joins the thread

  int64_t published() const { return published_.load(); }
  int64_t dropped() const { return queue_.dropped(); }
  int64_t queue_waits() const { return queue_.waits(); }  // kWait: pushes that found the queue full
  QueueFullPolicy queue_policy() const { return queue_.policy(); }
  const TelemetryChannels& channels() const { return channels_; }
  // The LCM instance, so in-process subscribers (memq://) can share it.
  lcm::LCM& lcm();
  // The newest record published, for a console status line. Shared with the
  // publisher thread under a mutex; the real-time loop never touches it.
  std::optional<TelemetryRecord> latest() const;

 private:
  void thread_main();
  void publish_record(const TelemetryRecord& record);
  void publish_procedure(const TelemetryRecord& record, int64_t utime, double t);
  void publish_more_channels(const TelemetryRecord& record, int64_t utime, double t);
  void publish_driver_status();
  void publish_reports();
  void publish_state_event(const std::string& event, const std::string& message, bool to_log);
  void flush_log();
  void note_log_result(int err);

  TelemetryMeta meta_;
  TelemetryChannels channels_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<lcm::LogFile> log_;
  BoundedHandoff<TelemetryRecord> queue_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<int64_t> published_{0};
  mutable std::mutex latest_mutex_;
  std::optional<TelemetryRecord> latest_;
  std::function<DriverDiagnostics()> diagnostics_;
  std::string driver_name_;
  std::vector<TelemetryTap*> taps_;
  int64_t last_t_ns_ = 0;  // rig time of the newest record, for driver status time stamps
  RigState last_state_ = RigState::kStarting;
  SafetyState last_safety_state_ = SafetyState::kFaulted;
  std::atomic<int64_t> log_failures_{0};
  std::mutex reports_mutex_;
  std::vector<std::pair<std::string, std::string>> reports_;
  bool first_record_ = true;
  ProcedureStatus last_procedure_{};  // the procedure state last published
  bool stopped_ = false;
};

}  // namespace rigctl
