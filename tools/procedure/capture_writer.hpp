// A test procedure's data capture (docs/procedures.md, "Capture"), written
// on the telemetry publisher's thread from the messages the tick already
// hands over (the SAMPLE of every tick, PROCEDURE at every cycle end, STATE
// with every trip): the tick does nothing for it, so it never allocates,
// locks or waits for it. Into FOLDER (default <log>.capture/):
//   peaks.csv            every test cycle: step, cycle numbers, each chosen
//                        channel's peak and valley over the cycle
//   cycle-S-N.csv        full-rate samples (every input) of cycle N of step S,
//                        N = 1, 2, 5, 10, 20, 50, ... (log-spaced)
//   trip-TICK-EVENT.csv  full-rate samples from pre_trigger before the trip's
//                        tick to post_trigger after it
// Each file is whole when the run ends (or when its cycle or window ends);
// a killed run leaves the files cut at the kill.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "rt/comms/telemetry_publisher.hpp"
#include "rt/comms/telemetry_tap.hpp"
#include "rt/procedure/procedure_spec.hpp"
#include "rt/sample.hpp"

namespace rigctl {

// Whether cycle n (1-based) of a step is one of the log-spaced 1, 2, 5, 10, 20, 50, ...
bool log_spaced_cycle(int64_t n);

class CaptureWriter final : public TelemetryTap {
 public:
  // Creates `folder`; throws std::runtime_error naming it when it cannot.
  CaptureWriter(const std::string& folder, const CaptureSpec& spec, const ChannelLayout& layout,
                const std::vector<std::string>& step_names, double period_s, const std::string& channel_prefix);
  ~CaptureWriter() override;
  CaptureWriter(const CaptureWriter&) = delete;
  CaptureWriter& operator=(const CaptureWriter&) = delete;

  void on_message(const std::string& channel, int64_t utime, const uint8_t* data, std::size_t size) noexcept override;
  // Closes every open file (after the publisher has stopped).
  void finish() noexcept;

  const std::string& folder() const { return folder_; }
  int64_t cycles_written() const { return cycles_written_; }
  int64_t histories_written() const { return histories_written_; }
  int64_t trips_written() const { return trips_written_; }

 private:
  struct Row {
    int64_t tick = 0;
    double t = 0.0;
    std::vector<double> values;
  };
  struct Window {  // a trip's file until its post-trigger ends
    std::FILE* file = nullptr;
    int64_t last_tick = 0;
  };

  void on_sample(const uint8_t* data, std::size_t size);
  void on_procedure(const uint8_t* data, std::size_t size);
  void on_state(const uint8_t* data, std::size_t size);
  std::FILE* open_csv(const std::string& name);
  void write_row(std::FILE* f, const Row& r);
  void close(std::FILE*& f);

  std::string folder_;
  CaptureSpec spec_;
  ChannelLayout layout_;
  std::vector<std::string> step_names_;
  std::string sample_channel_, procedure_channel_, state_channel_;
  int64_t pre_ticks_ = 0, post_ticks_ = 0;
  std::string header_;  // "t,tick,<inputs>"
  // The last pre_ticks_ samples (a ring), and the present one.
  std::vector<Row> ring_;
  std::size_t ring_next_ = 0, ring_size_ = 0;
  Row row_;
  // The present cycle: its extremes, its step and whether it is a test cycle.
  std::vector<double> peak_, valley_;
  bool cycle_seen_ = false;
  bool have_status_ = false;
  int32_t step_ = 0;
  int64_t step_cycles_ = 0, total_cycles_ = 0, row_index_ = 0, pass_ = 0;
  std::string phase_;
  std::FILE* peaks_ = nullptr;
  std::FILE* history_ = nullptr;
  std::vector<Window> windows_;
  int64_t cycles_written_ = 0, histories_written_ = 0, trips_written_ = 0;
  bool failed_ = false;  // a file could not be written: said once, capture goes on without it
};

}  // namespace rigctl
