#include "tools/health/health_command.hpp"

#include <cstdlib>
#include <fstream>
#include <stdexcept>

#include "config/config_reader.hpp"
#include "tools/health/health_report.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl::health {

namespace {

std::string one_line(std::string s) {
  for (auto& c : s)
    if (c == '\n' || c == '\r') c = ' ';
  return s;
}

template <typename Fn>
void write_file(const std::string& path, Fn&& fn) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write '" + path + "'");
  fn(f);
  if (!f) throw std::runtime_error("write to '" + path + "' failed");
}

// The PNG by tools/plots/plot_health.py from the trends' JSON.
void plot(const std::string& json_path, const std::string& png_path) {
  const char* dir = std::getenv("RIGCTL_PLOTS_DIR");
  const std::string script = std::string(dir != nullptr ? dir : RIGCTL_PLOTS_DIR) + "/plot_health.py";
  const std::string cmd = "/usr/bin/python3 '" + script + "' '" + json_path + "' --out '" + png_path + "'";
  if (std::system(cmd.c_str()) != 0)
    throw std::runtime_error("plotting failed (" + cmd + "); matplotlib comes with tools/scripts/setup.sh --plots");
}

// Whether any run of the rig recorded the oil temperature.
bool temperature_measured(catalog::Catalog& c, const std::string& rig) {
  catalog::RunFilter f;
  f.rig = rig;
  f.channels.push_back({"T_oil", catalog::Statistic::kMax, catalog::ChannelCondition::Op::kGreater, -1e9});
  return !c.runs(f).empty();
}

}  // namespace

int run_health_analyse(const AnalyseOptions& o, const std::atomic<bool>& stop, std::ostream& out, std::ostream& err) {
  try {
    const auto r = analyse_run(o, stop, out);
    std::size_t undetermined = 0;
    for (const auto& w : r.windows) undetermined += w.undetermined.empty() ? 0 : 1;
    out << "health analyse: run " << r.run_id << ", " << r.windows.size() << " windows diagnosed into " << o.catalog_path
        << " (" << undetermined << " could not determine every parameter)\n";
    return 0;
  } catch (const RunFileError& e) {
    err << "rigctl health analyse: " << one_line(e.what()) << "\n";
    return 2;
  } catch (const ConfigError& e) {
    err << "rigctl health analyse: config error: " << one_line(e.what()) << "\n";
    return 2;
  } catch (const std::exception& e) {
    err << "rigctl health analyse: " << one_line(e.what()) << "\n";
    return 1;
  }
}

int run_health_report(const ReportOptions& o, std::ostream& out, std::ostream& err) {
  try {
    catalog::Catalog c(o.catalog_path);
    HealthTrends h = build_trends(c, o.rig_name, o.trends);
    if (h.diagnoses == 0) {
      err << "rigctl health report: no diagnosis of rig '" << o.rig_name << "' in " << o.catalog_path
          << " (rigctl health analyse RUN --catalog ... enters them)\n";
      return 2;
    }
    h.temperature_measured = temperature_measured(c, o.rig_name);
    out << "health report: " << o.rig_name << ", " << h.diagnoses << " diagnosed windows\n";
    for (const auto& p : h.parameters) {
      out << "  " << p.name << ": " << p.points.size() << " trended, " << p.undetermined << " undetermined, "
          << p.alarms.size() << " alarm(s)\n";
      for (const auto& a : p.alarms) {
        const bool added = o.store_alarms && c.add_alarm(a);
        out << "    ALARM " << a.message << (added ? " (new)" : "") << "\n";
      }
    }
    if (!h.temperature_measured) out << "  temperature could not be separated: no T_oil channel in the rig's runs\n";
    std::string json = o.json_path;
    if (json.empty() && !o.png_path.empty()) json = o.png_path + ".json";
    if (!json.empty()) write_file(json, [&](std::ostream& f) { write_trends_json(h, f); });
    if (!o.html_path.empty()) write_file(o.html_path, [&](std::ostream& f) { write_health_html(h, f); });
    if (!o.png_path.empty()) plot(json, o.png_path);
    return 0;
  } catch (const std::exception& e) {
    err << "rigctl health report: " << one_line(e.what()) << "\n";
    return 1;
  }
}

}  // namespace rigctl::health
