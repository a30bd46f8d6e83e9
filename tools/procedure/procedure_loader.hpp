// A procedure file for a run: config/procedure_config.hpp's reading plus the
// drive steps' files (run files, docs/run-files.md) resampled to the loop's
// period. The drive file's path is relative to the procedure file.
#pragma once

#include <string>

#include "config/procedure_config.hpp"

namespace rigctl {

// Throws ConfigError naming the procedure file, the step and the problem.
ProcedureSpec load_procedure_for_run(const std::string& path, const ProcedureContext& context);

}  // namespace rigctl
