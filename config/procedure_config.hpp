// Reader of a procedure file (docs/procedures.md): strict like the configs,
// every error names the file, line and key path (`steps[2].sine.cycles`).
#pragma once

#include <string>

#include "rt/procedure/procedure_spec.hpp"
#include "rt/sample.hpp"

namespace rigctl {

struct ProcedureContext {
  const ChannelLayout* layout = nullptr;  // channel names of the rig's inputs
  int feedback_input = 0;                 // the controlled input (the default peak-valley channel)
  double period_s = 0.0025;
};

// Reads and checks the file. A `drive` step keeps its file and column
// (drive_path, drive_column) for the run layer to read
// (tools/procedure/procedure_loader.hpp). Throws ConfigError.
ProcedureSpec load_procedure(const std::string& path, const ProcedureContext& context);
ProcedureSpec procedure_from_string(const std::string& text, const std::string& name, const ProcedureContext& context);

// FNV-1a 64 of a file's bytes as 16 hex digits: a recovery file names the
// procedure and config it was written for. Throws ConfigError when the file
// cannot be read.
std::string file_hash(const std::string& path);
std::string text_hash(const std::string& text);

}  // namespace rigctl
