// The catalog's diagnoses and alarms (docs/rig-health.md 2 and 4).
#include "tools/catalog/catalog.hpp"

namespace rigctl::catalog {

namespace {

void write_parameters(Database& db, int64_t id, const std::vector<ParameterRecord>& parameters) {
  auto s = db.prepare(
      "INSERT INTO diagnosis_parameters (diagnosis_id, role, name, unit, nominal, value, sigma, tolerance, determined, "
      "stands_for) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)");
  for (const auto& p : parameters) {
    s.reset();
    s.bind(1, id).bind(2, p.role).bind(3, p.name).bind(4, p.unit).bind(5, p.nominal).bind(6, p.value);
    s.bind(7, p.sigma).bind(8, p.tolerance).bind(9, p.determined ? 1 : 0).bind(10, p.stands_for);
    s.run();
  }
}

void write_causes(Database& db, int64_t id, const std::vector<CauseRecord>& causes) {
  auto s = db.prepare(
      "INSERT INTO diagnosis_causes (diagnosis_id, rank, cause, signal, confidence, gain_pp, baseline_fit_percent, "
      "extended_fit_percent) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)");
  for (std::size_t i = 0; i < causes.size(); ++i) {
    const auto& c = causes[i];
    s.reset();
    s.bind(1, id).bind(2, static_cast<int64_t>(i + 1)).bind(3, c.cause).bind(4, c.signal).bind(5, c.confidence);
    s.bind(6, c.gain_pp).bind(7, c.baseline_fit_percent).bind(8, c.extended_fit_percent);
    s.run();
  }
}

void write_fits(Database& db, int64_t id, const std::vector<FitRecord>& fits) {
  auto s = db.prepare(
      "INSERT INTO diagnosis_fits (diagnosis_id, signal, baseline_fit_percent, extended_fit_percent) "
      "VALUES (?1, ?2, ?3, ?4)");
  for (const auto& f : fits) {
    s.reset();
    s.bind(1, id).bind(2, f.signal).bind(3, f.baseline_fit_percent).bind(4, f.extended_fit_percent);
    s.run();
  }
}

void read_details(Database& db, DiagnosisEntry& d) {
  auto p = db.prepare(
      "SELECT role, name, unit, nominal, value, sigma, tolerance, determined, stands_for FROM diagnosis_parameters "
      "WHERE diagnosis_id = ?1 ORDER BY rowid");
  p.bind(1, d.id);
  while (p.step()) {
    d.parameters.push_back({p.text(0), p.text(1), p.text(2), p.maybe_real(3), p.maybe_real(4), p.maybe_real(5),
                            p.maybe_real(6), p.integer(7) != 0, p.text(8)});
  }
  auto c = db.prepare(
      "SELECT cause, signal, confidence, gain_pp, baseline_fit_percent, extended_fit_percent FROM diagnosis_causes "
      "WHERE diagnosis_id = ?1 ORDER BY rank");
  c.bind(1, d.id);
  while (c.step()) d.causes.push_back({c.text(0), c.text(1), c.real(2), c.real(3), c.real(4), c.real(5)});
  auto f = db.prepare(
      "SELECT signal, baseline_fit_percent, extended_fit_percent FROM diagnosis_fits WHERE diagnosis_id = ?1 "
      "ORDER BY rowid");
  f.bind(1, d.id);
  while (f.step()) d.fits.push_back({f.text(0), f.real(1), f.maybe_real(2)});
}

constexpr const char* kDiagnosisColumns =
    "id, run_id, window_start_s, window_end_s, time_utc_s, rig_name, cause, unexplained, excitation, revision, "
    "elapsed_s";

DiagnosisEntry read_diagnosis(const Statement& s) {
  DiagnosisEntry d;
  d.id = s.integer(0);
  d.run_id = s.integer(1);
  d.window_start_s = s.real(2);
  d.window_end_s = s.real(3);
  d.time_utc_s = s.real(4);
  d.rig_name = s.text(5);
  d.cause = s.text(6);
  d.unexplained = s.integer(7) != 0;
  d.excitation = s.text(8);
  d.revision = s.text(9);
  d.elapsed_s = s.real(10);
  return d;
}

}  // namespace

int64_t Catalog::add_diagnosis(const DiagnosisEntry& d) {
  Transaction tx(db_);
  auto s = db_.prepare(
      "INSERT INTO diagnoses (run_id, window_start_s, window_end_s, time_utc_s, rig_name, cause, unexplained, "
      "excitation, revision, elapsed_s) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)");
  s.bind(1, d.run_id).bind(2, d.window_start_s).bind(3, d.window_end_s).bind(4, d.time_utc_s).bind(5, d.rig_name);
  s.bind(6, d.cause).bind(7, d.unexplained ? 1 : 0).bind(8, d.excitation).bind(9, d.revision).bind(10, d.elapsed_s);
  s.run();
  const int64_t id = db_.last_insert_id();
  write_parameters(db_, id, d.parameters);
  write_causes(db_, id, d.causes);
  write_fits(db_, id, d.fits);
  tx.commit();
  return id;
}

std::vector<DiagnosisEntry> Catalog::diagnoses(int64_t run_id) {
  auto s = db_.prepare(std::string("SELECT ") + kDiagnosisColumns +
                       " FROM diagnoses WHERE run_id = ?1 ORDER BY window_start_s, id");
  s.bind(1, run_id);
  std::vector<DiagnosisEntry> out;
  while (s.step()) out.push_back(read_diagnosis(s));
  for (auto& d : out) read_details(db_, d);
  return out;
}

std::vector<DiagnosisEntry> Catalog::rig_diagnoses(const std::string& rig_name) {
  auto s = db_.prepare(std::string("SELECT ") + kDiagnosisColumns +
                       " FROM diagnoses WHERE rig_name = ?1 ORDER BY time_utc_s, id");
  s.bind(1, rig_name);
  std::vector<DiagnosisEntry> out;
  while (s.step()) out.push_back(read_diagnosis(s));
  for (auto& d : out) read_details(db_, d);
  return out;
}

bool Catalog::add_alarm(const AlarmEntry& a) {
  Transaction tx(db_);
  auto s = db_.prepare(
      "INSERT OR IGNORE INTO alarms (rig_name, parameter, stands_for, direction, size_relative, size_sigma, "
      "since_utc_s, raised_utc_s, diagnosis_id, message) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10)");
  s.bind(1, a.rig_name).bind(2, a.parameter).bind(3, a.stands_for).bind(4, a.direction).bind(5, a.size_relative);
  s.bind(6, a.size_sigma).bind(7, a.since_utc_s).bind(8, a.raised_utc_s);
  if (a.diagnosis_id) {
    s.bind(9, *a.diagnosis_id);
  } else {
    s.bind_null(9);
  }
  s.bind(10, a.message);
  s.run();
  auto changes = db_.prepare("SELECT changes()");
  changes.step();
  const bool added = changes.integer(0) > 0;
  tx.commit();
  return added;
}

std::vector<AlarmEntry> Catalog::alarms(const std::string& rig_name) {
  auto s = db_.prepare(
      "SELECT id, rig_name, parameter, stands_for, direction, size_relative, size_sigma, since_utc_s, raised_utc_s, "
      "diagnosis_id, message FROM alarms WHERE rig_name = ?1 ORDER BY raised_utc_s, id");
  s.bind(1, rig_name);
  std::vector<AlarmEntry> out;
  while (s.step()) {
    AlarmEntry a;
    a.id = s.integer(0);
    a.rig_name = s.text(1);
    a.parameter = s.text(2);
    a.stands_for = s.text(3);
    a.direction = static_cast<int>(s.integer(4));
    a.size_relative = s.real(5);
    a.size_sigma = s.real(6);
    a.since_utc_s = s.real(7);
    a.raised_utc_s = s.real(8);
    if (!s.is_null(9)) a.diagnosis_id = s.integer(9);
    a.message = s.text(10);
    out.push_back(a);
  }
  return out;
}

}  // namespace rigctl::catalog
