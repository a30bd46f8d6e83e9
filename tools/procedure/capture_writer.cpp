#include "tools/procedure/capture_writer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <stdexcept>
#include <string_view>

#include <spdlog/spdlog.h>

#include "rigctl/procedure_t.hpp"
#include "rigctl/sample_t.hpp"
#include "rigctl/state_t.hpp"

namespace rigctl {

namespace {

// The events a detector or the procedure raises when a limit is crossed, an
// input fails or the specimen changed (rt/telemetry_record.hpp): a capture
// window each.
constexpr std::array<std::string_view, 12> kTripEvents = {
    "limit_tripped", "input_invalid",  "rate_limit",   "tracking_error",     "valve_saturated",    "sample_stale",
    "open_circuit",  "sensor_stuck",   "overruns",     "stop_timeout",       "peak_valley_change", "compensation_limit"};

bool is_trip(const std::string& event) {
  return std::find(kTripEvents.begin(), kTripEvents.end(), event) != kTripEvents.end();
}

bool cyclic_kind(const std::string& kind) { return kind == "sine" || kind == "blocks" || kind == "drive"; }

}  // namespace

bool log_spaced_cycle(int64_t n) {
  if (n < 1) return false;
  while (n % 10 == 0) n /= 10;
  return n == 1 || n == 2 || n == 5;
}

CaptureWriter::CaptureWriter(const std::string& folder, const CaptureSpec& spec, const ChannelLayout& layout,
                             const std::vector<std::string>& step_names, double period_s,
                             const std::string& channel_prefix)
    : folder_(folder), spec_(spec), layout_(layout), step_names_(step_names),
      sample_channel_(channel_prefix + "SAMPLE"), procedure_channel_(channel_prefix + "PROCEDURE"),
      state_channel_(channel_prefix + "STATE") {
  std::error_code ec;
  std::filesystem::create_directories(folder_, ec);
  if (ec) throw std::runtime_error("capture: cannot create the folder '" + folder_ + "': " + ec.message());
  pre_ticks_ = std::llround(spec.pre_trigger_s / period_s);
  post_ticks_ = std::llround(spec.post_trigger_s / period_s);
  ring_.resize(static_cast<std::size_t>(pre_ticks_ + 1));  // the trigger's own tick as well
  for (auto& r : ring_) r.values.resize(layout.inputs.size());
  header_ = "t,tick";
  for (const auto& in : layout.inputs) header_ += "," + in.name;
  header_ += "\n";
  peak_.assign(spec.channels.size(), 0.0);
  valley_.assign(spec.channels.size(), 0.0);
  if (!spec.channels.empty()) {
    peaks_ = open_csv("peaks.csv");
    if (peaks_ != nullptr) {
      std::string h = "step,step_name,cycle,step_cycle,row,pass";
      for (int c : spec.channels) {
        const std::string& name = layout.inputs[static_cast<std::size_t>(c)].name;
        h += "," + name + "_peak," + name + "_valley";
      }
      std::fprintf(peaks_, "%s\n", h.c_str());
    }
  }
}

CaptureWriter::~CaptureWriter() { finish(); }

void CaptureWriter::finish() noexcept {
  close(peaks_);
  close(history_);
  for (auto& w : windows_) close(w.file);
  windows_.clear();
}

std::FILE* CaptureWriter::open_csv(const std::string& name) {
  const std::string path = (std::filesystem::path(folder_) / name).string();
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr && !failed_) {
    failed_ = true;
    spdlog::error("capture: cannot write '{}': the capture goes on without it", path);
  }
  return f;
}

void CaptureWriter::close(std::FILE*& f) {
  if (f == nullptr) return;
  if (std::fclose(f) != 0 && !failed_) {
    failed_ = true;
    spdlog::error("capture: a file in '{}' was not written whole (disk full?)", folder_);
  }
  f = nullptr;
}

void CaptureWriter::write_row(std::FILE* f, const Row& r) {
  std::fprintf(f, "%.9g,%lld", r.t, static_cast<long long>(r.tick));
  for (double v : r.values) std::fprintf(f, ",%.9g", v + 0.0);
  std::fputc('\n', f);
}

void CaptureWriter::on_message(const std::string& channel, int64_t, const uint8_t* data, std::size_t size) noexcept {
  try {
    if (channel == sample_channel_) {
      on_sample(data, size);
    } else if (channel == procedure_channel_) {
      on_procedure(data, size);
    } else if (channel == state_channel_) {
      on_state(data, size);
    }
  } catch (const std::exception& e) {
    if (!failed_) spdlog::error("capture: {}", e.what());
    failed_ = true;
  }
}

void CaptureWriter::on_sample(const uint8_t* data, std::size_t size) {
  rigctl::sample_t s;
  if (s.decode(data, 0, static_cast<int>(size)) < 0) return;
  Row& r = ring_[ring_next_];
  r.tick = s.tick;
  r.t = s.t;
  for (std::size_t i = 0; i < r.values.size(); ++i) r.values[i] = i < s.values.size() ? s.values[i] : NAN;
  ring_next_ = (ring_next_ + 1) % ring_.size();
  ring_size_ = std::min(ring_size_ + 1, ring_.size());
  if (have_status_ && phase_ == "run") {
    for (std::size_t k = 0; k < spec_.channels.size(); ++k) {
      const double v = r.values[static_cast<std::size_t>(spec_.channels[k])];
      peak_[k] = cycle_seen_ ? std::max(peak_[k], v) : v;
      valley_[k] = cycle_seen_ ? std::min(valley_[k], v) : v;
    }
    cycle_seen_ = true;
  }
  if (history_ != nullptr) write_row(history_, r);
  for (auto it = windows_.begin(); it != windows_.end();) {
    write_row(it->file, r);
    if (r.tick >= it->last_tick) {
      close(it->file);
      it = windows_.erase(it);
    } else {
      ++it;
    }
  }
}

void CaptureWriter::on_procedure(const uint8_t* data, std::size_t size) {
  rigctl::procedure_t p;
  if (p.decode(data, 0, static_cast<int>(size)) < 0) return;
  bool boundary = !have_status_ || p.step != step_ || p.phase != phase_;
  if (have_status_ && p.total_cycles > total_cycles_) {
    // A test cycle ended on this tick: its peaks and valleys.
    boundary = true;
    const int64_t step_cycle = p.step == step_ ? p.step_cycles : step_cycles_ + 1;
    if (peaks_ != nullptr && cycle_seen_) {
      const auto step = static_cast<std::size_t>(step_);
      std::fprintf(peaks_, "%d,\"%s\",%lld,%lld,%lld,%lld", step_, step < step_names_.size() ? step_names_[step].c_str() : "",
                   static_cast<long long>(p.total_cycles), static_cast<long long>(step_cycle),
                   static_cast<long long>(row_index_), static_cast<long long>(pass_));
      for (std::size_t k = 0; k < peak_.size(); ++k) std::fprintf(peaks_, ",%.9g,%.9g", peak_[k] + 0.0, valley_[k] + 0.0);
      std::fputc('\n', peaks_);
      ++cycles_written_;
    }
  }
  if (boundary) {
    cycle_seen_ = false;
    close(history_);
  }
  have_status_ = true;
  step_ = p.step;
  step_cycles_ = p.step_cycles;
  total_cycles_ = p.total_cycles;
  row_index_ = p.row;
  pass_ = p.pass;
  phase_ = p.phase;
  // The next cycle of the step, if it is one of the log-spaced ones.
  if (boundary && spec_.log_spaced_histories && p.phase == "run" && cyclic_kind(p.step_kind) &&
      log_spaced_cycle(p.step_cycles + 1)) {
    history_ = open_csv("cycle-" + std::to_string(p.step) + "-" + std::to_string(p.step_cycles + 1) + ".csv");
    if (history_ != nullptr) {
      std::fputs(header_.c_str(), history_);
      ++histories_written_;
    }
  }
}

void CaptureWriter::on_state(const uint8_t* data, std::size_t size) {
  rigctl::state_t st;
  if (st.decode(data, 0, static_cast<int>(size)) < 0 || !is_trip(st.event)) return;
  Window w;
  w.file = open_csv("trip-" + std::to_string(st.tick) + "-" + st.event + ".csv");
  if (w.file == nullptr) return;
  ++trips_written_;
  std::fputs(header_.c_str(), w.file);
  // The ring, oldest first: up to pre_trigger before the trip's tick, and that tick.
  for (std::size_t i = 0; i < ring_size_; ++i) {
    const Row& r = ring_[(ring_next_ + ring_.size() - ring_size_ + i) % ring_.size()];
    if (r.tick <= st.tick) write_row(w.file, r);
  }
  w.last_tick = st.tick + post_ticks_;
  if (post_ticks_ == 0) {
    close(w.file);
    return;
  }
  windows_.push_back(w);
}

}  // namespace rigctl
