#include "tools/catalog/catalog_command.hpp"

#include <nlohmann/json.hpp>

#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "config/config_reader.hpp"
#include "config/rig_config.hpp"
#include "tools/catalog/run_summary.hpp"

namespace rigctl {

namespace {

using catalog::CatalogError;
using catalog::RunEntry;

// Bad input on the command line: exit 2.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Target {
  std::string path;
  std::string rig_name;
};

Target catalog_target(const CatalogCommandOptions& o) {
  Target t{o.catalog_path, o.rig_name};
  if (!o.config_path.empty()) {
    const RigConfig config = load_rig_config(o.config_path);
    if (t.path.empty() && config.catalog) t.path = config.catalog->path;
    if (t.rig_name.empty()) t.rig_name = config.catalog && !config.catalog->rig_name.empty() ? config.catalog->rig_name
                                                                                            : std::string(to_string(config.rig));
  }
  if (t.path.empty()) throw UsageError("no catalog: give --catalog FILE, or --config with a catalog: section");
  return t;
}

catalog::RunFilter parse_filter(const CatalogCommandOptions& o) {
  catalog::RunFilter f;
  f.rig = o.rig;
  f.since = o.since;
  f.until = o.until;
  if (!o.end_reason.empty()) {
    const auto r = kind_from_string<catalog::EndReason>(o.end_reason);
    if (!r) throw UsageError("--end-reason: " + unknown_kind_message<catalog::EndReason>(o.end_reason));
    f.end_reason = *r;
  }
  for (const auto& w : o.where) {
    try {
      f.channels.push_back(catalog::parse_channel_condition(w));
    } catch (const CatalogError& e) {
      throw UsageError(e.what());
    }
  }
  return f;
}

void print_table(const std::vector<RunEntry>& runs, std::ostream& out) {
  out << std::left << std::setw(5) << "id" << std::setw(28) << "start (UTC)" << std::setw(16) << "rig" << std::setw(10)
      << "duration" << std::setw(12) << "end" << std::setw(6) << "trips" << "profile / log\n";
  for (const auto& r : runs) {
    std::ostringstream d;
    d << std::fixed << std::setprecision(1) << r.duration_s << " s";
    out << std::left << std::setw(5) << r.id << std::setw(28) << r.start_utc << std::setw(16) << r.rig_name << std::setw(10)
        << d.str() << std::setw(12) << to_string(r.end_reason) << std::setw(6) << r.trips << r.profile
        << (r.profile.empty() ? "" : " / ") << r.log_path << "\n";
  }
  out << runs.size() << " run" << (runs.size() == 1 ? "" : "s") << "\n";
}

nlohmann::json run_json(const RunEntry& r) {
  nlohmann::json j{{"id", r.id},           {"rig_kind", r.rig_kind},     {"rig_name", r.rig_name},
                   {"config_path", r.config_path}, {"config_sha256", r.config_sha256}, {"revision", r.revision},
                   {"start_utc", r.start_utc},     {"duration_s", r.duration_s},       {"profile", r.profile},
                   {"end_reason", std::string(to_string(r.end_reason))}, {"end_detail", r.end_detail},
                   {"trips", r.trips},             {"samples", r.samples},             {"log_path", r.log_path},
                   {"log_bytes", r.log_bytes},     {"log_sha256", r.log_sha256},
                   {"entered_by", std::string(to_string(r.entered_by))}};
  nlohmann::json channels = nlohmann::json::object();
  for (const auto& c : r.channels) {
    channels[c.channel] = {{"unit", c.unit}, {"count", c.count}, {"min", c.min}, {"max", c.max},
                           {"mean", c.mean}, {"std", c.std},     {"rms", c.rms}};
  }
  j["channels"] = channels;
  return j;
}

void show_run(catalog::Catalog& c, int64_t id, std::ostream& out) {
  const auto r = c.run(id);
  if (!r) throw UsageError("no run " + std::to_string(id) + " in " + c.database().path());
  out << "run " << r->id << ": " << r->rig_name << " (" << r->rig_kind << "), started " << r->start_utc << ", "
      << r->duration_s << " s, " << to_string(r->end_reason) << (r->end_detail.empty() ? "" : " (" + r->end_detail + ")")
      << ", " << r->trips << " trips, " << r->samples << " samples\n"
      << "  profile: " << r->profile << "\n  config: " << r->config_path << " sha256 " << r->config_sha256 << "\n"
      << "  rigctl: " << r->revision << "\n  log: " << r->log_path << " (" << r->log_bytes << " bytes, sha256 "
      << r->log_sha256 << ")\n  entered by: " << to_string(r->entered_by) << "\n";
  out << "  " << std::left << std::setw(14) << "channel" << std::setw(8) << "unit" << std::right << std::setw(14)
      << "min" << std::setw(14) << "max" << std::setw(14) << "mean" << std::setw(14) << "std" << std::setw(14) << "rms"
      << "\n";
  for (const auto& s : r->channels) {
    out << "  " << std::left << std::setw(14) << s.channel << std::setw(8) << s.unit << std::right
        << std::setprecision(6) << std::setw(14) << s.min << std::setw(14) << s.max << std::setw(14) << s.mean
        << std::setw(14) << s.std << std::setw(14) << s.rms << "\n";
  }
  for (const auto& d : c.diagnoses(id)) {
    out << "  diagnosis " << d.id << " of " << d.window_start_s << ".." << d.window_end_s << " s: " << d.cause
        << (d.excitation.empty() ? "" : " (undetermined: " + d.excitation + ")") << "\n";
  }
}

int add_records(catalog::Catalog& c, const CatalogCommandOptions& o, const Target& t, std::ostream& out) {
  if (o.records.empty()) throw UsageError("catalog add: name at least one RUN.lcm or RUN.csv");
  for (const auto& path : o.records) {
    RunEntry e = catalog::summarise_record(path, o.channel_prefix);
    e.rig_name = t.rig_name.empty() ? e.rig_kind : t.rig_name;
    e.entered_by = catalog::EnteredBy::kAdd;
    const int64_t id = c.add_run(e);
    out << "catalog add: " << e.log_path << " entered as run " << id << " (" << e.rig_name << ", "
        << to_string(e.end_reason) << ", " << e.duration_s << " s, " << e.channels.size() << " channels)\n";
  }
  return 0;
}

}  // namespace

int run_catalog_command(CatalogAction action, const CatalogCommandOptions& o, std::ostream& out, std::ostream& err) {
  try {
    const Target t = catalog_target(o);
    catalog::Catalog c(t.path);
    switch (action) {
      case CatalogAction::kAdd: return add_records(c, o, t, out);
      case CatalogAction::kList: print_table(c.runs(parse_filter(o)), out); return 0;
      case CatalogAction::kShow: show_run(c, o.run_id, out); return 0;
      case CatalogAction::kQuery: {
        nlohmann::json all = nlohmann::json::array();
        for (const auto& r : c.runs(parse_filter(o))) all.push_back(run_json(*c.run(r.id)));
        out << all.dump(2) << "\n";
        return 0;
      }
      case CatalogAction::kRepair: repair_catalog(c, o.log_dir, t.rig_name, o.channel_prefix, out); return 0;
    }
  } catch (const UsageError& e) {
    err << "rigctl catalog: " << e.what() << "\n";
    return 2;
  } catch (const ConfigError& e) {
    err << "rigctl catalog: config error: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    err << "rigctl catalog: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace rigctl
