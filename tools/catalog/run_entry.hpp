// What the catalog knows of one run (docs/rig-health.md 1): who ran what,
// how it ended, where its log is and what its channels did.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "config/kind_names.hpp"

namespace rigctl::catalog {

enum class EndReason : uint8_t {
  kCompleted,    // the run's length reached (or the operator's stop), a controlled stop
  kFaulted,      // a trip ended it faulted
  kInterrupted,  // SIGINT/SIGTERM
  kKilled,       // the process died during the run (kill -9, power): entered by `catalog repair`
  kRunning,      // entered at the start, not finished yet (or killed and not repaired)
  kUnknown,      // a run file without its events (catalog add of a CSV)
};

constexpr std::string_view to_string(EndReason r) {
  switch (r) {
    case EndReason::kCompleted: return "completed";
    case EndReason::kFaulted: return "faulted";
    case EndReason::kInterrupted: return "interrupted";
    case EndReason::kKilled: return "killed";
    case EndReason::kRunning: return "running";
    case EndReason::kUnknown: return "unknown";
  }
  return "unknown";
}

// How the run came into the catalog.
enum class EnteredBy : uint8_t { kRun, kAdd, kRepair };

constexpr std::string_view to_string(EnteredBy e) {
  switch (e) {
    case EnteredBy::kRun: return "run";
    case EnteredBy::kAdd: return "add";
    case EnteredBy::kRepair: return "repair";
  }
  return "run";
}

// A channel's summary over the run's valid samples [SI].
struct ChannelStats {
  std::string channel;
  std::string unit;
  int64_t count = 0;
  double min = 0.0, max = 0.0, mean = 0.0, std = 0.0, rms = 0.0;
};

// The statistics a query can filter on; their column names in one place.
enum class Statistic : uint8_t { kMin, kMax, kMean, kStd, kRms };

constexpr std::string_view to_string(Statistic s) {
  switch (s) {
    case Statistic::kMin: return "min";
    case Statistic::kMax: return "max";
    case Statistic::kMean: return "mean";
    case Statistic::kStd: return "std";
    case Statistic::kRms: return "rms";
  }
  return "max";
}

struct RunEntry {
  int64_t id = 0;
  std::string rig_kind;   // quarter_car, pneumatic_rotary, half_car, ...
  std::string rig_name;   // this rig in the lab (catalog.rig_name; default the kind)
  std::string config_path, config_sha256;
  std::string revision;   // rigctl's git revision
  std::string start_utc;  // ISO 8601, e.g. 2026-11-27T21:02:03.250000Z
  double duration_s = 0.0;
  std::string profile;    // the demand: profile kind, case, csv file
  EndReason end_reason = EndReason::kUnknown;
  std::string end_detail;  // e.g. "sensor_stuck: x_r = 0.0348"
  int64_t trips = 0;
  int64_t samples = 0;
  std::string log_path;  // absolute
  int64_t log_bytes = 0;
  std::string log_sha256;
  EnteredBy entered_by = EnteredBy::kRun;
  int64_t pid = 0;        // the running process (end_reason running), for repair
  std::string host;
  std::vector<ChannelStats> channels;
};

}  // namespace rigctl::catalog

namespace rigctl {

template <>
struct KindNames<catalog::EndReason> {
  static constexpr std::string_view noun = "end reason";
  static constexpr std::array known{catalog::EndReason::kCompleted, catalog::EndReason::kFaulted,
                                    catalog::EndReason::kInterrupted, catalog::EndReason::kKilled,
                                    catalog::EndReason::kRunning, catalog::EndReason::kUnknown};
};

template <>
struct KindNames<catalog::EnteredBy> {
  static constexpr std::string_view noun = "entry kind";
  static constexpr std::array known{catalog::EnteredBy::kRun, catalog::EnteredBy::kAdd, catalog::EnteredBy::kRepair};
};

template <>
struct KindNames<catalog::Statistic> {
  static constexpr std::string_view noun = "statistic";
  static constexpr std::array known{catalog::Statistic::kMin, catalog::Statistic::kMax, catalog::Statistic::kMean,
                                    catalog::Statistic::kStd, catalog::Statistic::kRms};
};

}  // namespace rigctl
