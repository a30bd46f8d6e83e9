// `rigctl run`'s entry in the rig's run catalog (docs/rig-health.md 1): the
// run is entered before its loop starts (end reason running, with this
// process's id) and completed after it ends, so a run whose process dies
// (kill -9, power) is still in the catalog, and `rigctl catalog repair`
// completes it from its log. A catalog that cannot be written never stops a
// run: the failure is reported and the run goes on (the log is the record).
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <ostream>
#include <string>

#include "config/rig_config.hpp"
#include "tools/catalog/catalog.hpp"

namespace rigctl {

struct RunCatalogContext {
  std::string catalog_path;  // --catalog, else config.catalog.path; "" none
  std::string config_path;
  std::string case_name;
  bool excitation_override = false;  // identify/tune: the demand is theirs, not the config's profile
};

// The catalog's path for a run ("" when the run has none).
std::string run_catalog_path(const RigConfig& config, const std::string& option_path);

class RunCatalogEntry {
 public:
  // Opens the catalog and enters the run as running; on failure warns on
  // `out` and does nothing more.
  RunCatalogEntry(const RigConfig& config, const RunCatalogContext& context, const std::string& log_path,
                  int64_t start_utime, std::ostream& out);
  // Completes the entry from the closed log and the run's end.
  void finish(catalog::EndReason reason, const std::string& detail);
  bool active() const { return catalog_ != nullptr; }
  int64_t id() const { return id_; }

 private:
  std::unique_ptr<catalog::Catalog> catalog_;
  catalog::RunEntry entry_;
  int64_t id_ = 0;
  std::ostream& out_;
};

}  // namespace rigctl
