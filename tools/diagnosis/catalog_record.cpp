#include "tools/diagnosis/catalog_record.hpp"

#include <filesystem>
#include <fstream>

#include "tools/catalog/run_summary.hpp"
#include "tools/common/revision.hpp"

namespace rigctl::diag {

namespace {

// The parameters a window could not determine: why it is not trended for them.
std::string undetermined(const Diagnosis& d) {
  std::string out;
  for (const auto& c : d.calibration)
    if (!c.determined) out += (out.empty() ? "" : ", ") + c.name;
  return out;
}

}  // namespace

catalog::DiagnosisEntry catalog_record(const Diagnosis& d, const DiagnosisWindow& w) {
  catalog::DiagnosisEntry e;
  e.run_id = w.run_id;
  e.window_start_s = w.start_s;
  e.window_end_s = w.end_s;
  e.time_utc_s = w.time_utc_s;
  e.rig_name = w.rig_name;
  e.cause = d.cause;
  e.unexplained = d.unexplained;
  e.excitation = undetermined(d);
  e.revision = rigctl_revision();
  e.elapsed_s = d.elapsed_s;
  for (const auto& c : d.calibration) {
    catalog::ParameterRecord p{"baseline", c.name, c.unit, c.nominal, std::nullopt, std::nullopt,
                               c.tolerance, c.determined, c.stands_for};
    if (c.determined) {
      p.value = c.value;
      p.sigma = c.sigma;
    }
    e.parameters.push_back(p);
  }
  for (const auto& cause : d.causes) {
    e.causes.push_back({cause.cause, cause.signal, cause.confidence, cause.gain_percent_points,
                        cause.baseline_fit_percent, cause.extended_fit_percent});
    for (const auto& p : cause.parameters) {
      catalog::ParameterRecord r{cause.cause, p.name, p.unit, std::nullopt, std::nullopt, std::nullopt,
                                 std::nullopt, p.determined, ""};
      if (p.determined) {
        r.value = p.value;
        r.sigma = p.sigma;
      }
      e.parameters.push_back(r);
    }
  }
  for (const auto& [signal, fit] : d.baseline_fit_percent) {
    catalog::FitRecord f{signal, fit, std::nullopt};
    if (const auto it = d.extended_fit_percent.find(signal); it != d.extended_fit_percent.end()) f.extended_fit_percent = it->second;
    e.fits.push_back(f);
  }
  return e;
}

namespace {

// The LCM log a run file was converted from (`# source: rigctl log2csv NAME`).
std::string source_log_name(const std::string& csv) {
  std::ifstream in(csv);
  const std::string key = "# source: rigctl log2csv ";
  for (std::string line; std::getline(in, line) && !line.empty() && line[0] == '#';)
    if (line.rfind(key, 0) == 0) return line.substr(key.size());
  return "";
}

}  // namespace

catalog::RunEntry catalog_run_of(catalog::Catalog& c, const std::string& record_path, const std::string& rig_name) {
  const std::string path = std::filesystem::absolute(record_path).lexically_normal().string();
  if (auto r = c.run_by_log(path)) return *r;
  // A run file of a logged run (`rigctl run --csv`, log2csv) belongs to the log's run.
  if (const std::string log = source_log_name(path); !log.empty())
    if (auto r = c.run_by_log_name(log)) return *r;
  catalog::RunEntry e = catalog::summarise_record(path);
  e.rig_name = rig_name.empty() ? e.rig_kind : rig_name;
  e.entered_by = catalog::EnteredBy::kAdd;
  e.id = c.add_run(e);
  return e;
}

}  // namespace rigctl::diag
