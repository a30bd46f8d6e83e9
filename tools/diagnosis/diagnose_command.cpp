#include "tools/diagnosis/diagnose_command.hpp"

#include <fstream>
#include <iomanip>
#include <sstream>

#include "config/config_reader.hpp"
#include "tools/catalog/run_summary.hpp"
#include "tools/diagnosis/catalog_record.hpp"
#include "tools/diagnosis/engine.hpp"
#include "tools/diagnosis/model.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {

namespace {

std::string one_line(std::string s) {
  for (auto& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

}  // namespace

int run_diagnose(const DiagnoseCommandOptions& o, std::ostream& out, std::ostream& err) {
  diag::Diagnosis d;
  try {
    const RunFileRig rig = run_file_rig_from_string(o.rig);
    auto cols = run_file_columns(rig);
    cols.drop_bad_rows = o.drop_bad_rows;
    const RunFile run = read_run_file(o.data_path, cols);
    if (const auto r = run.meta("rig"); r && *r != to_string(rig))
      throw RunFileError(o.data_path + ": the run file says '# rig: " + *r + "' but --rig is " + o.rig);
    if (run.dropped_rows > 0) err << "diagnose: " << run.dropped_rows << " bad rows dropped\n";
    if (run.resampled) err << "diagnose: jittered time stamps resampled to the median step " << run.dt << " s\n";
    diag::RigModelOptions mo;
    mo.config_path = o.config_path;
    mo.decimate = o.decimate;
    const auto model = diag::make_rig_model(rig, run, mo);
    diag::DiagnoseOptions dopt;
    dopt.progress = o.quiet ? nullptr : &err;
    dopt.threads = o.threads;
    d = diag::diagnose(*model, dopt);
  } catch (const RunFileError& e) {
    err << "rigctl diagnose: " << one_line(e.what()) << "\n";
    return 2;
  } catch (const ConfigError& e) {
    err << "rigctl diagnose: config error: " << one_line(e.what()) << "\n";
    return 2;
  } catch (const std::exception& e) {
    err << "rigctl diagnose: " << one_line(e.what()) << "\n";
    return 1;
  }
  out << "cause: " << d.cause << "\n";
  for (const auto& c : d.causes) {
    out << "  " << c.cause << ": " << c.signal << " fit " << std::fixed << std::setprecision(2)
        << c.baseline_fit_percent << " % -> " << c.extended_fit_percent << " % (gain " << c.gain_percent_points
        << " pp, confidence " << c.confidence << ")" << std::defaultfloat;
    for (const auto& p : c.parameters) out << " " << p.name << "=" << std::setprecision(5) << p.value;
    out << "\n";
  }
  if (!o.catalog_path.empty()) {
    try {
      catalog::Catalog c(o.catalog_path);
      const auto run = diag::catalog_run_of(c, o.data_path, o.rig_name);
      const double start_s = d.t.empty() ? 0.0 : d.t.front();
      const double end_s = d.t.empty() ? 0.0 : d.t.back();
      const int64_t id = c.add_diagnosis(diag::catalog_record(
          d, {run.id, start_s, end_s, catalog::utc_seconds(run.start_utc) + start_s, run.rig_name}));
      out << "catalog: diagnosis " << id << " of run " << run.id << " in " << o.catalog_path << "\n";
    } catch (const std::exception& e) {
      err << "rigctl diagnose: catalog: " << one_line(e.what()) << "\n";
      return 1;
    }
  }
  auto write = [&](const std::string& path, auto&& fn) -> bool {
    std::ofstream f(path);
    if (!f) {
      err << "rigctl diagnose: cannot write '" << path << "'\n";
      return false;
    }
    fn(f);
    return static_cast<bool>(f);
  };
  if (!o.json_path.empty() && !write(o.json_path, [&](std::ostream& f) { diag::write_json(d, f); })) return 1;
  if (!o.report_path.empty() && !write(o.report_path, [&](std::ostream& f) { diag::write_report(d, f); })) return 1;
  return 0;
}

}  // namespace rigctl
