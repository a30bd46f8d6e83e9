// LCM log -> run-file CSV (docs/run-files.md). Two passes over the
// log: the first finds the layout and the sample rate (the metadata lines come
// before the data), the second joins SAMPLE and COMMAND by tick and writes
// rows, holding only a short window of ticks in memory. A rig with several
// control channels also logs CHANNELS (the demands after the first): its
// setpoints follow the first one's column (x_ref_1, x_ref_2, ..., u_1, u_2, ...).
#include "tools/runfile/log2csv.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <limits>
#include <map>
#include <stdexcept>
#include <unistd.h>
#include <utility>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "rigctl/channels_t.hpp"
#include "rigctl/command_t.hpp"
#include "rigctl/sample_t.hpp"
#include "rigctl/timing_t.hpp"
#include "rt/comms/telemetry_columns.hpp"
#include "tools/runfile/lcm_log.hpp"

namespace rigctl {

namespace {

namespace fs = std::filesystem;

// Messages of one tick may arrive a little out of order from lcm-logger on a
// busy bus; a tick is final once the log has moved this many ticks past it.
constexpr int64_t kJoinWindowTicks = 256;

[[noreturn]] void fail(const std::string& path, const std::string& reason) {
  throw std::runtime_error("log2csv: '" + path + "': " + reason);
}

template <typename Msg>
bool decode(const lcm::LogEvent& ev, Msg& msg) {
  return msg.decode(ev.data, 0, ev.datalen) >= 0;
}

// Calls f(event) for every event of the log.
template <typename F>
void for_each_event(const std::string& path, F&& f) {
  lcm::LogFile log(path, "r");
  if (!log.good()) fail(path, std::string("cannot open as LCM log: ") + std::strerror(errno));
  while (const lcm::LogEvent* ev = log.readNextEvent()) f(*ev);
}

struct Layout {
  std::string rig;
  std::vector<std::string> inputs;
  std::vector<bool> keep_input;  // written to the file (simulator truth channels may be left out)
  std::vector<std::string> outputs;
  std::vector<std::string> more_setpoints;  // the CHANNELS message's, empty for a one-channel rig
  // The file's columns after t, as every telemetry writer names them.
  std::vector<TelemetryColumn> command_columns, input_columns;
  long sample_rate_hz = 0;  // 0 = unknown (fewer than two samples)
  // From the newest timing message: what a full telemetry queue did and how
  // many records it dropped, so a run file says whether it is complete.
  std::string queue_policy;  // "" = no timing message in the log
  int64_t dropped_records = 0;
};

long median_rate(std::vector<std::pair<int64_t, double>> tick_t) {
  std::sort(tick_t.begin(), tick_t.end());
  std::vector<double> spacing;
  for (std::size_t i = 1; i < tick_t.size(); ++i) {
    const int64_t dtick = tick_t[i].first - tick_t[i - 1].first;
    const double dt = tick_t[i].second - tick_t[i - 1].second;
    if (dtick > 0 && dt > 0) spacing.push_back(dt / static_cast<double>(dtick));
  }
  if (spacing.empty()) return 0;
  auto mid = spacing.begin() + static_cast<std::ptrdiff_t>(spacing.size() / 2);
  std::nth_element(spacing.begin(), mid, spacing.end());
  return std::lround(1.0 / *mid);
}

Layout scan(const std::string& path, const std::string& sample_ch, const std::string& command_ch,
            const std::string& timing_ch, const std::string& channels_ch) {
  Layout layout;
  bool have_sample = false;
  bool have_command = false;
  bool have_channels = false;
  std::vector<std::pair<int64_t, double>> tick_t;
  for_each_event(path, [&](const lcm::LogEvent& ev) {
    if (ev.channel == sample_ch) {
      rigctl::sample_t s;
      if (!decode(ev, s)) return;
      if (!have_sample) {
        layout.rig = s.rig;
        layout.inputs = s.names;
        layout.input_columns = sample_columns(s);
        have_sample = true;
      }
      tick_t.emplace_back(s.tick, s.t);
    } else if (ev.channel == command_ch && !have_command) {
      rigctl::command_t c;
      if (!decode(ev, c)) return;
      layout.command_columns = command_columns(c);
      layout.outputs = c.names;
      have_command = true;
    } else if (ev.channel == channels_ch && !have_channels) {
      rigctl::channels_t m;
      if (!decode(ev, m)) return;
      layout.more_setpoints = m.setpoint_names;
      have_channels = true;
    } else if (ev.channel == timing_ch) {
      rigctl::timing_t m;
      if (!decode(ev, m)) return;
      layout.queue_policy = m.queue_policy;
      layout.dropped_records = m.dropped_records;
    }
  });
  if (!have_sample) fail(path, "no sample messages on channel " + sample_ch);
  if (!have_command) fail(path, "no command messages on channel " + command_ch);
  layout.sample_rate_hz = median_rate(std::move(tick_t));
  // The demands of the channels after the first, after the first's column.
  std::vector<TelemetryColumn> more;
  for (const auto& name : layout.more_setpoints) more.push_back({name, ""});
  layout.command_columns.insert(layout.command_columns.begin() + 1, more.begin(), more.end());
  return layout;
}

struct Pending {
  bool has_sample = false;
  bool has_command = false;
  bool has_channels = false;
  double t = 0.0;
  int32_t status = 0;
  std::vector<std::string> in_names, out_names;
  std::vector<double> in, out;
  double setpoint = 0.0;
  std::vector<std::string> more_setpoint_names;
  std::vector<double> more_setpoints;
};

// Writes the rows in tick order; drops what the run-file contract forbids.
class RowWriter {
 public:
  RowWriter(std::FILE* f, const Layout& layout) : f_(f), layout_(layout) {}

  void write(const Pending& p, Log2CsvResult& result) {
    const bool channels_ok = layout_.more_setpoints.empty() ||
                             (p.has_channels && p.more_setpoint_names == layout_.more_setpoints);
    if (!p.has_sample || !p.has_command || !channels_ok || p.in_names != layout_.inputs ||
        p.out_names != layout_.outputs) {
      ++result.skipped;
      return;
    }
    // An invalid input (flagged by the driver) or a NaN must not become a
    // number in the file: the diagnosis would take it at face value.
    bool finite = std::isfinite(p.t) && std::isfinite(p.setpoint) && p.status == 0;
    for (double v : p.in) finite = finite && std::isfinite(v);
    for (double v : p.more_setpoints) finite = finite && std::isfinite(v);
    for (double v : p.out) finite = finite && std::isfinite(v);
    // Compare t as printed, so the file's t column strictly increases.
    char t_text[40];
    std::snprintf(t_text, sizeof t_text, "%.12g", p.t);
    const double t_printed = std::strtod(t_text, nullptr);
    if (!finite || (have_last_t_ && t_printed <= last_t_)) {
      ++result.skipped;
      return;
    }
    have_last_t_ = true;
    last_t_ = t_printed;
    std::fputs(t_text, f_);
    put(p.setpoint);
    for (double v : p.more_setpoints) put(v);
    for (double v : p.out) put(v);
    for (std::size_t i = 0; i < p.in.size(); ++i)
      if (layout_.keep_input[i]) put(p.in[i]);
    std::fputc('\n', f_);
    ++result.rows;
  }

 private:
  // 9 significant digits; "+ 0.0" turns -0 into 0 so the file never shows "-0".
  void put(double v) { std::fprintf(f_, ",%.9g", v + 0.0); }

  std::FILE* f_;
  const Layout& layout_;
  bool have_last_t_ = false;
  double last_t_ = 0.0;
};

void write_head(std::FILE* f, const Layout& layout, const std::string& log_path) {
  std::fprintf(f, "# rig: %s\n", layout.rig.c_str());
  if (layout.sample_rate_hz > 0) std::fprintf(f, "# sample_rate_hz: %ld\n", layout.sample_rate_hz);
  std::fprintf(f, "# source: rigctl log2csv %s\n", fs::path(log_path).filename().c_str());
  if (!layout.queue_policy.empty()) {
    std::fprintf(f, "# telemetry_queue_policy: %s\n", layout.queue_policy.c_str());
    std::fprintf(f, "# dropped_records: %lld\n", static_cast<long long>(layout.dropped_records));
  }
  std::fputs(kTimeColumn, f);
  for (const auto& c : layout.command_columns) std::fprintf(f, ",%s", c.name.c_str());
  for (std::size_t i = 0; i < layout.input_columns.size(); ++i)
    if (layout.keep_input[i]) std::fprintf(f, ",%s", layout.input_columns[i].name.c_str());
  std::fputc('\n', f);
}

void join_and_write(const std::string& path, const std::string& sample_ch, const std::string& command_ch,
                    const std::string& channels_ch, RowWriter& writer, Log2CsvResult& result) {
  std::map<int64_t, Pending> pending;
  int64_t max_tick = std::numeric_limits<int64_t>::min();
  int64_t last_written = std::numeric_limits<int64_t>::min();
  auto slot = [&](int64_t tick) -> Pending* {
    if (tick <= last_written) return nullptr;  // late duplicate of a finished tick
    max_tick = std::max(max_tick, tick);
    return &pending[tick];
  };
  for_each_event(path, [&](const lcm::LogEvent& ev) {
    if (ev.channel == sample_ch) {
      rigctl::sample_t s;
      if (!decode(ev, s)) return;
      Pending* p = slot(s.tick);
      if (p == nullptr) return;
      p->has_sample = true;
      p->t = s.t;
      p->status = s.status;
      p->in_names = std::move(s.names);
      p->in = std::move(s.values);
    } else if (ev.channel == command_ch) {
      rigctl::command_t c;
      if (!decode(ev, c)) return;
      Pending* p = slot(c.tick);
      if (p == nullptr) return;
      p->has_command = true;
      p->setpoint = c.setpoint;
      p->out_names = std::move(c.names);
      p->out = std::move(c.values);
    } else if (ev.channel == channels_ch) {
      rigctl::channels_t m;
      if (!decode(ev, m)) return;
      Pending* p = slot(m.tick);
      if (p == nullptr) return;
      p->has_channels = true;
      p->more_setpoint_names = std::move(m.setpoint_names);
      p->more_setpoints = std::move(m.setpoints);
    } else {
      return;
    }
    while (!pending.empty() && pending.begin()->first + kJoinWindowTicks <= max_tick) {
      writer.write(pending.begin()->second, result);
      last_written = pending.begin()->first;
      pending.erase(pending.begin());
    }
  });
  for (const auto& [tick, p] : pending) writer.write(p, result);
}

// Removes the temp file unless the conversion got as far as the rename.
struct TempFile {
  std::string path;
  std::FILE* f = nullptr;
  bool committed = false;
  ~TempFile() {
    if (f != nullptr) std::fclose(f);
    if (!committed) std::remove(path.c_str());
  }
};

}  // namespace

Log2CsvResult log_to_csv(const std::string& lcm_log_path, const std::string& csv_path,
                         const std::string& channel_prefix, bool simulator_truth) {
  const std::string sample_ch = channel_prefix + "SAMPLE";
  const std::string command_ch = channel_prefix + "COMMAND";
  check_is_lcm_log(lcm_log_path, "log2csv");
  const std::string channels_ch = channel_prefix + "CHANNELS";
  Layout layout = scan(lcm_log_path, sample_ch, command_ch, channel_prefix + "TIMING", channels_ch);
  for (const auto& name : layout.inputs) layout.keep_input.push_back(simulator_truth || name.rfind("sim_", 0) != 0);

  TempFile tmp;
  tmp.path = csv_path + ".tmp." + std::to_string(::getpid());
  tmp.f = std::fopen(tmp.path.c_str(), "w");
  if (tmp.f == nullptr) fail(csv_path, std::string("cannot create: ") + std::strerror(errno));

  Log2CsvResult result;
  result.rig = layout.rig;
  result.dropped_records = layout.dropped_records;
  write_head(tmp.f, layout, lcm_log_path);
  RowWriter writer(tmp.f, layout);
  join_and_write(lcm_log_path, sample_ch, command_ch, channels_ch, writer, result);

  const bool write_error = std::ferror(tmp.f) != 0;
  const bool close_error = std::fclose(tmp.f) != 0;
  tmp.f = nullptr;
  if (write_error || close_error) fail(csv_path, "write failed (disk full?)");
  std::error_code ec;
  fs::rename(tmp.path, csv_path, ec);
  if (ec) fail(csv_path, "cannot rename the temp file into place: " + ec.message());
  tmp.committed = true;
  return result;
}

}  // namespace rigctl
