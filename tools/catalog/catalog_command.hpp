// `rigctl catalog add|list|show|query|repair` (docs/rig-health.md 1).
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "tools/catalog/catalog.hpp"

namespace rigctl {

struct CatalogCommandOptions {
  std::string catalog_path;  // --catalog
  std::string config_path;   // --config: its catalog.path and rig_name when --catalog is not given
  std::string rig_name;      // add/repair: the rig's name (default the config's, else the record's rig kind)
  std::string channel_prefix = "RIGCTL_";
  std::vector<std::string> records;  // add: RUN.lcm or RUN.csv files
  std::string log_dir;               // repair: where the logs are
  int64_t run_id = 0;                // show
  // list/query filters, as typed: parsed by run_catalog_command (errors name them)
  std::string rig, since, until, end_reason;
  std::vector<std::string> where;
};

enum class CatalogAction { kAdd, kList, kShow, kQuery, kRepair };

// Returns the exit code: 0 done, 2 bad input (unknown run, bad filter), 1 other failures.
int run_catalog_command(CatalogAction action, const CatalogCommandOptions& options, std::ostream& out, std::ostream& err);

// The killed and unentered runs of a log folder, entered (`catalog repair`):
// every entry still marked running whose process is gone is completed from
// its log; every *.lcm log of `log_dir` not in the catalog is entered. Returns
// the ids touched; writes one line per run on `out`.
std::vector<int64_t> repair_catalog(catalog::Catalog& catalog, const std::string& log_dir, const std::string& rig_name,
                                    const std::string& channel_prefix, std::ostream& out);

}  // namespace rigctl
