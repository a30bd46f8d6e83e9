// ScopedFifoPriority (rt/realtime.hpp): the calling thread runs SCHED_FIFO
// at the priority given while the object lives (where the system allows it;
// otherwise the refusal is reported and nothing changes) and has its old
// policy back afterwards.
#include <gtest/gtest.h>
#include <pthread.h>
#include <sched.h>

#include <cerrno>

#include "rt/realtime.hpp"

using namespace rigctl;

namespace {
struct Policy {
  int policy = -1;
  int priority = -1;
};
Policy current() {
  Policy p;
  sched_param param{};
  pthread_getschedparam(pthread_self(), &p.policy, &param);
  p.priority = param.sched_priority;
  return p;
}
}  // namespace

TEST(ScopedFifoPriority, RaisesTheCallingThreadAndRestoresIt) {
  const Policy before = current();
  {
    ScopedFifoPriority raised(12);
    const Policy during = current();
    if (raised.error() != 0) {
      // Not permitted here (no CAP_SYS_NICE): reported, nothing changed.
      EXPECT_EQ(raised.error(), EPERM);
      EXPECT_EQ(during.policy, before.policy);
      EXPECT_EQ(during.priority, before.priority);
    } else {
      EXPECT_EQ(during.policy, SCHED_FIFO);
      EXPECT_EQ(during.priority, 12);
    }
  }
  const Policy after = current();
  EXPECT_EQ(after.policy, before.policy);
  EXPECT_EQ(after.priority, before.priority);
}

TEST(ScopedFifoPriority, PriorityZeroChangesNothing) {
  const Policy before = current();
  ScopedFifoPriority none(0);
  EXPECT_EQ(none.error(), 0);
  EXPECT_EQ(current().policy, before.policy);
}
