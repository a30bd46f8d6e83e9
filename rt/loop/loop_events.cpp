#include "rt/loop/loop_events.hpp"

namespace rigctl {

void LoopEvents::log_state_changes(const RigStateMachine& machine, int64_t tick, int64_t t_ns) noexcept {
  for (; changes_logged_ < machine.change_count(); ++changes_logged_) {
    const StateChange& c = machine.changes()[changes_logged_];
    EventRecord e = loop_event(tick, t_ns, c.to,
                               Event{EventCode::kStateChanged, -1, static_cast<double>(c.from), static_cast<uint8_t>(c.to), 0});
    e.from = c.from;
    e.cause = c.cause;
    log(e);
  }
}

}  // namespace rigctl
