#include "rt/loop/command_sources.hpp"

namespace rigctl {

bool StopRequestSource::next(OperatorCommand& command) noexcept {
  if (!requested_ || given_) return false;
  given_ = true;
  command = OperatorCommand{OperatorCommandKind::kStop, 0.0, 0};
  return true;
}

bool OperatorQueueSource::next(OperatorCommand& command) noexcept {
  if (queue_ == nullptr || taken_ >= kMaxPerTick || !queue_->try_pop(command)) return false;
  ++taken_;
  return true;
}

void AutomaticSequence::restart(bool enabled) noexcept {
  next_step_ = enabled ? 0 : kSteps.size();
  refused_this_tick_ = false;
}

bool AutomaticSequence::next(OperatorCommand& command) noexcept {
  if (refused_this_tick_ || next_step_ >= kSteps.size()) return false;
  command = OperatorCommand{kSteps[next_step_], 0.0, 0};
  return true;
}

void AutomaticSequence::answered(bool accepted) noexcept {
  if (accepted) {
    ++next_step_;
  } else {
    refused_this_tick_ = true;  // not yet: the same step again next tick
  }
}

}  // namespace rigctl
