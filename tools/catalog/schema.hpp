// The catalog's schema, versioned by SQLite's user_version and migrated one
// version at a time when a newer rigctl opens an older file
// (docs/rig-health.md 1.2). Version 1: runs and their channel statistics.
// Version 2: the process of a running run (for repair), diagnoses with
// their parameters, causes and fits, and the health alarms.
#pragma once

#include "tools/catalog/sqlite_db.hpp"

namespace rigctl::catalog {

inline constexpr int kSchemaVersion = 2;

// Brings the file to kSchemaVersion inside one transaction (an interrupted
// migration leaves the old version intact). Throws CatalogError for a file
// newer than this program (it would not know what it may change).
void migrate(Database& db);

}  // namespace rigctl::catalog
