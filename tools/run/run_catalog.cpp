#include "tools/run/run_catalog.hpp"

#include <unistd.h>

#include <filesystem>
#include <stdexcept>

#include "tools/catalog/run_summary.hpp"
#include "tools/common/revision.hpp"

namespace rigctl {

namespace {

std::string host_name() {
  char buf[256] = {};
  return gethostname(buf, sizeof buf - 1) == 0 ? buf : "";
}

// The demand as a person would name it: the profile's kind, its CSV, the case.
std::string profile_text(const RigConfig& config, const RunCatalogContext& c) {
  std::string text = c.excitation_override ? "excitation" : std::string(to_string(config.profile.type));
  if (!c.excitation_override && !config.profile.csv_file.empty())
    text += " " + std::filesystem::path(config.profile.csv_file).filename().string();
  if (!c.case_name.empty()) text += " (case " + c.case_name + ")";
  return text;
}

}  // namespace

std::string run_catalog_path(const RigConfig& config, const std::string& option_path) {
  if (!option_path.empty()) return option_path;
  return config.catalog ? config.catalog->path : "";
}

RunCatalogEntry::RunCatalogEntry(const RigConfig& config, const RunCatalogContext& context,
                                 const std::string& log_path, int64_t start_utime, std::ostream& out)
    : out_(out) {
  if (context.catalog_path.empty()) return;
  auto& e = entry_;
  e.rig_kind = std::string(to_string(config.rig));
  e.rig_name = config.catalog && !config.catalog->rig_name.empty() ? config.catalog->rig_name : e.rig_kind;
  e.config_path = context.config_path.empty() ? "" : std::filesystem::absolute(context.config_path).lexically_normal().string();
  try {
    if (!context.config_path.empty()) e.config_sha256 = catalog::file_sha256(context.config_path);
  } catch (const std::exception&) {
    // a config given as text (tests, make-run): no file to hash
  }
  e.revision = rigctl_revision();
  e.start_utc = catalog::utc_text(start_utime);
  e.profile = profile_text(config, context);
  e.log_path = std::filesystem::absolute(log_path).lexically_normal().string();
  e.entered_by = catalog::EnteredBy::kRun;
  e.pid = static_cast<int64_t>(getpid());
  e.host = host_name();
  try {
    catalog_ = std::make_unique<catalog::Catalog>(context.catalog_path);
    id_ = catalog_->begin_run(e);
  } catch (const std::exception& ex) {
    out_ << "  catalog: NOT ENTERED: " << ex.what() << "\n";
    catalog_.reset();
  }
}

void RunCatalogEntry::finish(catalog::EndReason reason, const std::string& detail) {
  if (!catalog_) return;
  catalog::RunEntry e = entry_;
  e.end_reason = reason;
  e.end_detail = detail;
  e.pid = 0;  // no longer running
  std::string note;
  try {
    catalog::RunEntry logged = catalog::summarise_record(entry_.log_path);
    e.duration_s = logged.duration_s;
    e.samples = logged.samples;
    e.trips = logged.trips;
    e.channels = std::move(logged.channels);
    e.log_bytes = logged.log_bytes;
    e.log_sha256 = logged.log_sha256;
  } catch (const std::exception& ex) {
    // A run stopped before its first sample reached the log: how it ended is
    // still known, its statistics are not.
    note = std::string("; no statistics: ") + ex.what();
  }
  try {
    catalog_->finish_run(id_, e);
    out_ << "  catalog: run " << id_ << " in " << catalog_->database().path() << " (" << to_string(reason) << ")" << note
         << "\n";
  } catch (const std::exception& ex) {
    out_ << "  catalog: run " << id_ << " NOT COMPLETED (catalog repair completes it from the log): " << ex.what() << "\n";
  }
}

}  // namespace rigctl
