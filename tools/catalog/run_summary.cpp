#include "tools/catalog/run_summary.hpp"

#include <openssl/evp.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include <lcm/lcm-cpp.hpp>

#include "rigctl/command_t.hpp"
#include "rigctl/sample_t.hpp"
#include "rigctl/state_t.hpp"
#include "rt/telemetry_record.hpp"
#include "tools/catalog/channel_summary.hpp"

namespace rigctl::catalog {

namespace fs = std::filesystem;

namespace {

// Per column, in first-seen order.
class Columns {
 public:
  ChannelSummary& at(const std::string& name, const std::string& unit) {
    auto it = index_.find(name);
    if (it == index_.end()) {
      it = index_.emplace(name, order_.size()).first;
      order_.push_back({name, unit, {}});
    }
    return order_[it->second].summary;
  }
  std::vector<ChannelStats> stats() const {
    std::vector<ChannelStats> out;
    for (const auto& c : order_) out.push_back(c.summary.stats(c.name, c.unit));
    return out;
  }

 private:
  struct Column {
    std::string name, unit;
    ChannelSummary summary;
  };
  std::map<std::string, std::size_t> index_;
  std::vector<Column> order_;
};

// The end of a log's run from its state messages.
struct EndSeen {
  std::string state;       // the last state message's (stopped, faulted, running, ...)
  std::string event;       // ... and its event and message
  std::string message;
};

EndReason end_reason_of(const EndSeen& e) {
  if (e.state == to_string(RigState::kFaulted)) return EndReason::kFaulted;
  if (e.state != to_string(RigState::kStopped)) return EndReason::kKilled;  // no closing record: the process died
  return e.event == to_string(EventCode::kStopRequested) ? EndReason::kInterrupted : EndReason::kCompleted;
}

std::string hex(const unsigned char* p, unsigned n) {
  static constexpr char kDigits[] = "0123456789abcdef";
  std::string out;
  for (unsigned i = 0; i < n; ++i) {
    out += kDigits[p[i] >> 4];
    out += kDigits[p[i] & 15];
  }
  return out;
}

std::vector<std::string> split_csv(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) out.push_back(cell);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

std::string trim(std::string s) {
  const auto a = s.find_first_not_of(" \t\r");
  const auto b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? "" : s.substr(a, b - a + 1);
}

}  // namespace

bool is_trip_event(const std::string& code) {
  // The detectors' and the driver's codes (rt/telemetry_record.hpp): each
  // stops, holds or faults the rig, or says it would have.
  static constexpr std::array kTrips{EventCode::kLimitTripped, EventCode::kInputInvalid, EventCode::kDriverReadFailed,
                                     EventCode::kRateLimit,    EventCode::kTrackingError, EventCode::kValveSaturated,
                                     EventCode::kSampleStale,  EventCode::kOverruns,      EventCode::kOpenCircuit,
                                     EventCode::kSensorStuck,  EventCode::kStopTimeout};
  for (const EventCode c : kTrips)
    if (to_string(c) == code) return true;
  return false;
}

bool is_lcm_log(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  unsigned char sync[4] = {};
  f.read(reinterpret_cast<char*>(sync), 4);
  // LCM's event sync word 0xEDA1DA01, big-endian.
  return f.gcount() == 4 && sync[0] == 0xED && sync[1] == 0xA1 && sync[2] == 0xDA && sync[3] == 0x01;
}

RunEntry summarise_lcm_log(const std::string& path, const std::string& prefix) {
  lcm::LogFile log(path, "r");
  if (!log.good()) throw std::runtime_error("catalog: '" + path + "': cannot open as LCM log: " + std::strerror(errno));
  RunEntry r;
  Columns columns;
  EndSeen end;
  std::set<std::string> trips_seen;
  int64_t first_utime = -1;
  double first_t = 0.0, last_t = 0.0;
  const std::string sample_ch = prefix + "SAMPLE", command_ch = prefix + "COMMAND", state_ch = prefix + "STATE";
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel == sample_ch) {
      rigctl::sample_t s;
      if (s.decode(ev->data, 0, ev->datalen) < 0) continue;
      if (first_utime < 0) {
        first_utime = s.utime;
        first_t = s.t;
        r.rig_kind = s.rig;
      }
      last_t = s.t;
      ++r.samples;
      for (std::size_t i = 0; i < s.values.size() && i < s.names.size(); ++i) {
        // A channel the driver flagged invalid is no value of the channel.
        if (i < 32 && (s.status >> i) & 1) continue;
        columns.at(s.names[i], i < s.units.size() ? s.units[i] : "").add(s.values[i]);
      }
    } else if (ev->channel == command_ch) {
      rigctl::command_t c;
      if (c.decode(ev->data, 0, ev->datalen) < 0) continue;
      columns.at(c.setpoint_name, "").add(c.setpoint);
      for (std::size_t i = 0; i < c.values.size() && i < c.names.size(); ++i)
        columns.at(c.names[i], i < c.units.size() ? c.units[i] : "").add(c.values[i]);
    } else if (ev->channel == state_ch) {
      rigctl::state_t st;
      if (st.decode(ev->data, 0, ev->datalen) < 0) continue;
      // The last state message of a run that ended is its closing record,
      // whose event is why it ended ("" for a completed run).
      end.state = st.state;
      end.event = st.event;
      end.message = st.message;
      // The closing record repeats the trip that ended the run (same event,
      // same message): each trip is counted once.
      if (is_trip_event(st.event) && trips_seen.insert(st.event + "\n" + st.message).second) ++r.trips;
    }
  }
  if (first_utime < 0) throw std::runtime_error("catalog: '" + path + "': no sample messages on channel " + sample_ch);
  r.start_utc = utc_text(first_utime - static_cast<int64_t>(first_t * 1e6));
  r.duration_s = last_t;
  r.end_reason = end_reason_of(end);
  r.end_detail = end.event.empty() ? "" : end.event + (end.message.empty() ? "" : ": " + end.message);
  r.channels = columns.stats();
  return r;
}

RunEntry summarise_run_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("catalog: '" + path + "': cannot open: " + std::strerror(errno));
  RunEntry r;
  r.end_reason = EndReason::kUnknown;
  std::string line;
  std::vector<std::string> header;
  std::size_t line_no = 0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.rfind('#', 0) == 0) {
      const auto colon = line.find(':');
      if (colon == std::string::npos) continue;
      const std::string key = trim(line.substr(1, colon - 1)), value = trim(line.substr(colon + 1));
      if (key == "rig") r.rig_kind = value;
      if (key == "start_utc") r.start_utc = value;
      continue;
    }
    header = split_csv(line);
    break;
  }
  if (header.empty() || trim(header[0]) != "t") {
    throw std::runtime_error("catalog: '" + path + "' line " + std::to_string(line_no) + ": expected the header row starting with t");
  }
  std::vector<ChannelSummary> sums(header.size());
  double first_t = 0.0, last_t = 0.0;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    const auto cells = split_csv(line);
    for (std::size_t i = 0; i < cells.size() && i < header.size(); ++i) {
      char* end = nullptr;
      const double v = std::strtod(cells[i].c_str(), &end);
      if (end == cells[i].c_str()) continue;  // an empty or text cell: no value (the diagnosis reader names it)
      if (i == 0) {
        if (r.samples == 0) first_t = v;
        last_t = v;
      } else {
        sums[i].add(v);
      }
    }
    ++r.samples;
  }
  if (r.samples == 0) throw std::runtime_error("catalog: '" + path + "': no data rows");
  r.duration_s = last_t - first_t;
  for (std::size_t i = 1; i < header.size(); ++i) r.channels.push_back(sums[i].stats(trim(header[i]), ""));
  if (r.start_utc.empty()) {
    const auto mtime = fs::last_write_time(path);
    const auto sys = std::chrono::file_clock::to_sys(mtime);
    const auto us = std::chrono::duration_cast<std::chrono::microseconds>(sys.time_since_epoch()).count();
    r.start_utc = utc_text(us - static_cast<int64_t>(r.duration_s * 1e6));
  }
  return r;
}

RunEntry summarise_record(const std::string& path, const std::string& prefix) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw std::runtime_error("catalog: '" + path + "' is not a file");
  RunEntry r = is_lcm_log(path) ? summarise_lcm_log(path, prefix) : summarise_run_file(path);
  r.log_path = fs::absolute(path).lexically_normal().string();
  r.log_bytes = static_cast<int64_t>(fs::file_size(path));
  r.log_sha256 = file_sha256(path);
  return r;
}

std::string file_sha256(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("catalog: '" + path + "': cannot read: " + std::strerror(errno));
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> ctx(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  if (!ctx || EVP_DigestInit_ex(ctx.get(), EVP_sha256(), nullptr) != 1) throw std::runtime_error("catalog: SHA-256 unavailable");
  std::array<char, 1 << 16> buf{};  // 64 KiB reads: a few hundred MB/s, the disk's pace
  while (in) {
    in.read(buf.data(), buf.size());
    if (in.gcount() > 0) EVP_DigestUpdate(ctx.get(), buf.data(), static_cast<std::size_t>(in.gcount()));
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned n = 0;
  EVP_DigestFinal_ex(ctx.get(), digest, &n);
  return hex(digest, n);
}

std::string utc_text(int64_t utime_us) {
  const std::time_t secs = static_cast<std::time_t>(utime_us / 1'000'000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char buf[64];
  const std::size_t n = std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%S", &tm);
  std::snprintf(buf + n, sizeof buf - n, ".%06lldZ", static_cast<long long>(utime_us % 1'000'000));
  return buf;
}

double utc_seconds(const std::string& text) {
  std::tm tm{};
  int year = 0, month = 0, day = 0, hour = 0, minute = 0;
  double second = 0.0;
  const int n = std::sscanf(text.c_str(), "%d-%d-%dT%d:%d:%lf", &year, &month, &day, &hour, &minute, &second);
  if (n != 3 && n != 6) throw std::invalid_argument("'" + text + "' is not an ISO 8601 UTC time (2026-11-27T21:02:03Z)");
  tm.tm_year = year - 1900;
  tm.tm_mon = month - 1;
  tm.tm_mday = day;
  tm.tm_hour = hour;
  tm.tm_min = minute;
  return static_cast<double>(timegm(&tm)) + second;
}

}  // namespace rigctl::catalog
