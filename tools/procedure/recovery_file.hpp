// A procedure's recovery file (docs/procedures.md, "Resume"): a few
// `key: value` lines a person can read (what it belongs to, where the test
// was), then the recovery itself as bytes with their length and checksum.
// Written whole to a temporary file, fsync'd, renamed over the old one and
// the folder fsync'd: after a crash or a power cut the file is the old one
// or the new one, never a mixture. A file whose checksum does not match is
// refused (it was not written by this program, or the disk lost it).
#pragma once

#include <string>

#include "rt/procedure/procedure_state.hpp"

namespace rigctl {

struct RecoveryIdentity {
  std::string procedure_path;
  std::string procedure_hash;  // config/procedure_config.hpp file_hash
  std::string config_path;
  std::string config_hash;
};

struct RecoveryFile {
  RecoveryIdentity identity;
  ProcedureRecovery recovery;
};

// Throws std::runtime_error naming the file on a write failure.
void write_recovery_file(const std::string& path, const RecoveryIdentity& id, const ProcedureRecovery& r);
// Throws std::runtime_error naming the file and what is wrong with it.
RecoveryFile read_recovery_file(const std::string& path);
// The resume's check: the procedure and config are the ones the recovery
// was written for. Throws std::runtime_error naming which one differs.
void check_recovery_identity(const RecoveryFile& file, const RecoveryIdentity& now, const std::string& path);

}  // namespace rigctl
