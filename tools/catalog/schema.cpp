#include "tools/catalog/schema.hpp"

#include <array>
#include <string>

namespace rigctl::catalog {

namespace {

// Version 0 -> 1: the runs and their channel statistics. Kept as it was
// first written: files of version 1 exist and are migrated from it.
constexpr const char* kToVersion1 = R"sql(
CREATE TABLE runs (
  id INTEGER PRIMARY KEY,
  rig_kind TEXT NOT NULL,
  rig_name TEXT NOT NULL,
  config_path TEXT NOT NULL DEFAULT '',
  config_sha256 TEXT NOT NULL DEFAULT '',
  revision TEXT NOT NULL DEFAULT '',
  start_utc TEXT NOT NULL,
  duration_s REAL NOT NULL DEFAULT 0,
  profile TEXT NOT NULL DEFAULT '',
  end_reason TEXT NOT NULL,
  end_detail TEXT NOT NULL DEFAULT '',
  trips INTEGER NOT NULL DEFAULT 0,
  samples INTEGER NOT NULL DEFAULT 0,
  log_path TEXT NOT NULL UNIQUE,
  log_bytes INTEGER NOT NULL DEFAULT 0,
  log_sha256 TEXT NOT NULL DEFAULT '',
  entered_by TEXT NOT NULL
);
CREATE INDEX runs_by_rig_start ON runs(rig_name, start_utc);
CREATE TABLE channel_stats (
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  channel TEXT NOT NULL,
  unit TEXT NOT NULL DEFAULT '',
  count INTEGER NOT NULL,
  min REAL, max REAL, mean REAL, std REAL, rms REAL,
  PRIMARY KEY (run_id, channel)
);
)sql";

// Version 1 -> 2: the process of a running run; diagnoses (a whole run or
// one window of it) with their calibrated parameters, named causes and fits;
// the health alarms.
constexpr const char* kToVersion2 = R"sql(
ALTER TABLE runs ADD COLUMN pid INTEGER NOT NULL DEFAULT 0;
ALTER TABLE runs ADD COLUMN host TEXT NOT NULL DEFAULT '';
CREATE TABLE diagnoses (
  id INTEGER PRIMARY KEY,
  run_id INTEGER NOT NULL REFERENCES runs(id) ON DELETE CASCADE,
  window_start_s REAL NOT NULL,
  window_end_s REAL NOT NULL,
  time_utc_s REAL NOT NULL,
  rig_name TEXT NOT NULL,
  cause TEXT NOT NULL,
  unexplained INTEGER NOT NULL DEFAULT 0,
  excitation TEXT NOT NULL DEFAULT '',
  revision TEXT NOT NULL DEFAULT '',
  elapsed_s REAL NOT NULL DEFAULT 0
);
CREATE INDEX diagnoses_by_rig_time ON diagnoses(rig_name, time_utc_s);
CREATE TABLE diagnosis_parameters (
  diagnosis_id INTEGER NOT NULL REFERENCES diagnoses(id) ON DELETE CASCADE,
  role TEXT NOT NULL,
  name TEXT NOT NULL,
  unit TEXT NOT NULL DEFAULT '',
  nominal REAL,
  value REAL,
  sigma REAL,
  tolerance REAL,
  determined INTEGER NOT NULL,
  stands_for TEXT NOT NULL DEFAULT '',
  PRIMARY KEY (diagnosis_id, role, name)
);
CREATE TABLE diagnosis_causes (
  diagnosis_id INTEGER NOT NULL REFERENCES diagnoses(id) ON DELETE CASCADE,
  rank INTEGER NOT NULL,
  cause TEXT NOT NULL,
  signal TEXT NOT NULL DEFAULT '',
  confidence REAL,
  gain_pp REAL,
  baseline_fit_percent REAL,
  extended_fit_percent REAL,
  PRIMARY KEY (diagnosis_id, rank)
);
CREATE TABLE diagnosis_fits (
  diagnosis_id INTEGER NOT NULL REFERENCES diagnoses(id) ON DELETE CASCADE,
  signal TEXT NOT NULL,
  baseline_fit_percent REAL,
  extended_fit_percent REAL,
  PRIMARY KEY (diagnosis_id, signal)
);
CREATE TABLE alarms (
  id INTEGER PRIMARY KEY,
  rig_name TEXT NOT NULL,
  parameter TEXT NOT NULL,
  stands_for TEXT NOT NULL DEFAULT '',
  direction INTEGER NOT NULL,
  size_relative REAL NOT NULL,
  size_sigma REAL NOT NULL,
  since_utc_s REAL NOT NULL,
  raised_utc_s REAL NOT NULL,
  diagnosis_id INTEGER REFERENCES diagnoses(id) ON DELETE SET NULL,
  message TEXT NOT NULL,
  UNIQUE (rig_name, parameter, since_utc_s, direction)
);
)sql";

constexpr std::array<const char*, kSchemaVersion> kMigrations{kToVersion1, kToVersion2};

}  // namespace

void migrate(Database& db) {
  // A reader of a current file takes no write lock; a migration re-reads the
  // version under its lock (another process may have migrated meanwhile).
  if (db.user_version() == kSchemaVersion) return;
  Transaction tx(db);
  const int found = db.user_version();
  if (found > kSchemaVersion) {
    throw CatalogError("catalog '" + db.path() + "': schema version " + std::to_string(found) +
                       " is newer than this rigctl's " + std::to_string(kSchemaVersion) + "; use a newer rigctl");
  }
  for (int v = found; v < kSchemaVersion; ++v) db.exec(kMigrations[static_cast<std::size_t>(v)]);
  if (found != kSchemaVersion) db.set_user_version(kSchemaVersion);
  tx.commit();
}

}  // namespace rigctl::catalog
