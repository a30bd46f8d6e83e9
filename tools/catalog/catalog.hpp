// The run catalog of one rig PC (docs/rig-health.md): a SQLite file with
// every run, its channel statistics, the diagnoses of its windows and the
// health alarms. Opening it creates the file on first use and migrates an
// older schema (tools/catalog/schema.hpp). Every entry is one transaction:
// a process killed mid-entry leaves the file as it was before it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tools/catalog/health_entry.hpp"
#include "tools/catalog/run_entry.hpp"
#include "tools/catalog/sqlite_db.hpp"

namespace rigctl::catalog {

// A condition on a channel's statistic, e.g. x_r max > 0.05.
struct ChannelCondition {
  std::string channel;
  Statistic statistic = Statistic::kMax;
  enum class Op : uint8_t { kLess, kGreater } op = Op::kGreater;
  double value = 0.0;
};
// "x_r.max>0.05", "p1.mean<8e6"; throws CatalogError naming the text.
ChannelCondition parse_channel_condition(const std::string& text);

struct RunFilter {
  std::string rig;    // rig name or kind; "" any
  std::string since;  // start_utc >= this (ISO date or time prefix, e.g. 2026-11-01); "" any
  std::string until;  // start_utc < this
  std::optional<EndReason> end_reason;
  std::vector<ChannelCondition> channels;
};

class Catalog {
 public:
  explicit Catalog(const std::string& path);

  // `rigctl run` at its start: the run as known then, end reason running,
  // with this process's id; finish_run completes it at the end.
  int64_t begin_run(const RunEntry& run);
  void finish_run(int64_t id, const RunEntry& run);
  // A whole run at once (catalog add, repair). Throws CatalogError when its
  // log is already entered, naming the run.
  int64_t add_run(const RunEntry& run);
  // Replaces an unfinished entry's fields (repair of a killed run).
  void complete_run(int64_t id, const RunEntry& run) { finish_run(id, run); }

  std::optional<RunEntry> run(int64_t id);
  std::optional<RunEntry> run_by_log(const std::string& log_path);
  // The one run whose log has this file name (in any folder); none when no
  // run or several have it.
  std::optional<RunEntry> run_by_log_name(const std::string& file_name);
  std::vector<RunEntry> runs(const RunFilter& filter);  // without channel statistics, oldest first

  // Diagnoses, trends and alarms (tools/catalog/health_entry.hpp).
  int64_t add_diagnosis(const DiagnosisEntry& d);
  std::vector<DiagnosisEntry> diagnoses(int64_t run_id);
  // Every diagnosis of the rig, oldest first, each with its parameters.
  std::vector<DiagnosisEntry> rig_diagnoses(const std::string& rig_name);
  // Returns false when the same alarm (rig, parameter, since, direction) is there already.
  bool add_alarm(const AlarmEntry& a);
  std::vector<AlarmEntry> alarms(const std::string& rig_name);

  Database& database() { return db_; }

 private:
  void write_channels(int64_t id, const std::vector<ChannelStats>& channels);
  std::vector<ChannelStats> read_channels(int64_t id);
  Database db_;
};

}  // namespace rigctl::catalog
