// Where the loop hands a procedure's recovery (rt/procedure/procedure_state.hpp)
// when a cycle, a pass or a step ends and at least every few seconds. The
// writer (tools/procedure/recovery_writer.hpp) writes it to disk off the
// tick; `offer` must not allocate or lock, and may wait only in simulated
// time (a --fast run keeps its recovery file in step with the loop).
#pragma once

#include "rt/procedure/procedure_state.hpp"

namespace rigctl {

class RecoverySink {
 public:
  virtual ~RecoverySink() = default;
  virtual void offer(const ProcedureRecovery& recovery) noexcept = 0;
};

}  // namespace rigctl
