// A diagnosis as the run catalog keeps it (docs/rig-health.md 2): the
// calibrated baseline with standard deviations, the named causes with their
// sizes and gains, the fit percent per signal, linked to the run and the
// window of it that was diagnosed.
#pragma once

#include <string>

#include "tools/catalog/catalog.hpp"
#include "tools/diagnosis/engine.hpp"

namespace rigctl::diag {

struct DiagnosisWindow {
  int64_t run_id = 0;
  double start_s = 0.0, end_s = 0.0;  // rig time within the run
  double time_utc_s = 0.0;            // the window's start, seconds since the epoch
  std::string rig_name;
};

catalog::DiagnosisEntry catalog_record(const Diagnosis& d, const DiagnosisWindow& window);

// The run a run file or log belongs to in the catalog: found by its path, or
// entered now (as `catalog add` would). Returns the run.
catalog::RunEntry catalog_run_of(catalog::Catalog& c, const std::string& record_path, const std::string& rig_name);

}  // namespace rigctl::diag
