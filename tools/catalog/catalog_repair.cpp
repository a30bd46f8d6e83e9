// `rigctl catalog repair`: no run is lost to a killed process.
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <set>

#include "tools/catalog/catalog_command.hpp"
#include "tools/catalog/run_summary.hpp"

namespace rigctl {

namespace {

namespace fs = std::filesystem;
using catalog::EndReason;
using catalog::RunEntry;

std::string this_host() {
  char buf[256] = {};
  return gethostname(buf, sizeof buf - 1) == 0 ? buf : "";
}

// A process of this host that still exists (EPERM: exists, another user's).
bool still_running(const RunEntry& r) {
  if (r.pid <= 0 || r.host != this_host()) return false;
  return ::kill(static_cast<pid_t>(r.pid), 0) == 0 || errno == EPERM;
}

// An unfinished entry completed from what its log holds.
void complete_from_log(catalog::Catalog& c, const RunEntry& r, const std::string& prefix, std::ostream& out) {
  RunEntry e = r;
  e.pid = 0;
  e.entered_by = catalog::EnteredBy::kRepair;
  std::error_code ec;
  if (!fs::exists(r.log_path, ec)) {
    e.end_reason = EndReason::kKilled;
    e.end_detail = "the process died and its log is missing";
  } else {
    const RunEntry logged = catalog::summarise_record(r.log_path, prefix);
    e.duration_s = logged.duration_s;
    e.samples = logged.samples;
    e.trips = logged.trips;
    e.channels = logged.channels;
    e.log_bytes = logged.log_bytes;
    e.log_sha256 = logged.log_sha256;
    e.end_reason = logged.end_reason;
    e.end_detail = logged.end_reason == EndReason::kKilled ? "the process died during the run (no closing record)"
                                                           : logged.end_detail;
  }
  c.complete_run(r.id, e);
  out << "repair: run " << r.id << " completed from " << r.log_path << " (" << to_string(e.end_reason) << ", "
      << e.duration_s << " s)\n";
}

}  // namespace

std::vector<int64_t> repair_catalog(catalog::Catalog& c, const std::string& log_dir, const std::string& rig_name,
                                    const std::string& prefix, std::ostream& out) {
  std::vector<int64_t> touched;
  catalog::RunFilter running;
  running.end_reason = EndReason::kRunning;
  for (const auto& r : c.runs(running)) {
    if (still_running(r)) {
      out << "repair: run " << r.id << " is still running (process " << r.pid << "), left as it is\n";
      continue;
    }
    complete_from_log(c, r, prefix, out);
    touched.push_back(r.id);
  }
  if (log_dir.empty()) return touched;
  std::vector<fs::path> logs;
  for (const auto& f : fs::directory_iterator(log_dir))
    if (f.is_regular_file() && f.path().extension() == ".lcm") logs.push_back(f.path());
  std::sort(logs.begin(), logs.end());  // the default names sort by start time
  for (const auto& p : logs) {
    const std::string path = fs::absolute(p).lexically_normal().string();
    if (c.run_by_log(path)) continue;
    try {
      RunEntry e = catalog::summarise_record(path, prefix);
      e.rig_name = rig_name.empty() ? e.rig_kind : rig_name;
      e.entered_by = catalog::EnteredBy::kRepair;
      if (e.end_reason == EndReason::kKilled) e.end_detail = "the process died during the run (no closing record)";
      const int64_t id = c.add_run(e);
      touched.push_back(id);
      out << "repair: " << path << " entered as run " << id << " (" << to_string(e.end_reason) << ", " << e.duration_s
          << " s)\n";
    } catch (const std::exception& ex) {
      out << "repair: " << path << " not entered: " << ex.what() << "\n";
    }
  }
  return touched;
}

}  // namespace rigctl
