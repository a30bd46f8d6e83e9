// The loop's command sources and their order: a stop request before the
// operator's commands, both before the automatic sequence; the operator's
// commands bounded per tick; the automatic sequence advancing only on
// acceptance and never starting the rig again once the run is ending.
#include <gtest/gtest.h>

#include <functional>
#include <vector>

#include "rt/loop/command_sources.hpp"

using namespace rigctl;
using K = OperatorCommandKind;

namespace {

struct Taken {
  K kind;
  EventSource origin;
  uint64_t sequence;
};

// One tick's commands; `accept` answers for the state machine.
std::vector<Taken> take(CommandSources& sources, const std::function<bool(K)>& accept = [](K) { return true; }) {
  std::vector<Taken> taken;
  sources.take([&](const OperatorCommand& c, const CommandSource& source) {
    taken.push_back({c.kind, source.origin(), c.sequence});
    return accept(c.kind);
  });
  return taken;
}

std::vector<K> kinds(const std::vector<Taken>& taken) {
  std::vector<K> out;
  for (const auto& t : taken) out.push_back(t.kind);
  return out;
}

}  // namespace

TEST(CommandSources, AStopRequestBeatsTheAutomaticSequenceInTheSameTick) {
  CommandSources sources;
  sources.restart(true);
  sources.request_stop();  // seen on the very tick the sequence would reset and arm
  const auto taken = take(sources);
  ASSERT_EQ(taken.size(), 1u);
  EXPECT_EQ(taken[0].kind, K::kStop);
  EXPECT_EQ(taken[0].origin, EventSource::kSignal);
  EXPECT_TRUE(take(sources).empty()) << "one stop per request, and the sequence never starts the rig again";
}

TEST(CommandSources, TheStopGoesInBeforeTheOperatorsCommands) {
  SpscQueue<OperatorCommand> queue(16);
  CommandSources sources;
  sources.attach_operator_queue(&queue);
  sources.restart(false);
  ASSERT_TRUE(queue.try_push({K::kHold, 0.0, 7}));
  sources.request_stop();
  const auto taken = take(sources);
  ASSERT_EQ(taken.size(), 2u);
  EXPECT_EQ(taken[0].origin, EventSource::kSignal);
  EXPECT_EQ(taken[1].origin, EventSource::kOperator);
  EXPECT_EQ(taken[1].sequence, 7u);
}

TEST(CommandSources, OperatorCommandsComeBeforeTheAutomaticSequence) {
  SpscQueue<OperatorCommand> queue(16);
  CommandSources sources;
  sources.attach_operator_queue(&queue);
  sources.restart(true);
  ASSERT_TRUE(queue.try_push({K::kHold, 0.0, 1}));
  const auto taken = take(sources);
  ASSERT_EQ(taken.size(), 6u);
  EXPECT_EQ(taken[0].origin, EventSource::kOperator);
  const std::vector<K> sequence = kinds({taken.begin() + 1, taken.end()});
  EXPECT_EQ(sequence, (std::vector<K>{K::kReset, K::kHydraulicsLow, K::kHydraulicsHigh, K::kArm, K::kStart}));
  for (std::size_t i = 1; i < taken.size(); ++i) EXPECT_EQ(taken[i].origin, EventSource::kAutomatic);
}

TEST(CommandSources, OperatorCommandsAreBoundedPerTick) {
  SpscQueue<OperatorCommand> queue(32);
  CommandSources sources;
  sources.attach_operator_queue(&queue);
  sources.restart(false);
  for (uint64_t seq = 1; seq <= 20; ++seq) ASSERT_TRUE(queue.try_push({K::kSetpoint, 0.0, seq}));
  const auto first = take(sources), second = take(sources), third = take(sources);
  ASSERT_EQ(first.size(), static_cast<std::size_t>(OperatorQueueSource::kMaxPerTick));
  ASSERT_EQ(second.size(), static_cast<std::size_t>(OperatorQueueSource::kMaxPerTick));
  ASSERT_EQ(third.size(), 4u);
  EXPECT_EQ(first.front().sequence, 1u);
  EXPECT_EQ(second.front().sequence, 9u) << "the rest wait in the queue, in order";
  EXPECT_EQ(third.back().sequence, 20u);
  EXPECT_TRUE(take(sources).empty());
}

TEST(CommandSources, TheAutomaticSequenceWaitsForTheNextTickAfterARefusal) {
  CommandSources sources;
  sources.restart(true);
  bool pressure_reached = false;
  const auto accept = [&](K k) { return k != K::kHydraulicsHigh || pressure_reached; };
  EXPECT_EQ(kinds(take(sources, accept)), (std::vector<K>{K::kReset, K::kHydraulicsLow, K::kHydraulicsHigh}));
  EXPECT_EQ(kinds(take(sources, accept)), (std::vector<K>{K::kHydraulicsHigh})) << "tried once per tick";
  pressure_reached = true;
  EXPECT_EQ(kinds(take(sources, accept)), (std::vector<K>{K::kHydraulicsHigh, K::kArm, K::kStart}));
  EXPECT_TRUE(take(sources, accept).empty()) << "the sequence is done";
}

TEST(CommandSources, TheAutomaticSequenceNeverStartsTheRigOnceTheRunIsEnding) {
  CommandSources sources;
  sources.restart(true);
  const auto refuse_arm = [](K k) { return k != K::kArm; };
  EXPECT_EQ(take(sources, refuse_arm).back().kind, K::kArm);
  sources.run_ending();
  EXPECT_TRUE(take(sources).empty());
}

TEST(CommandSources, WithAnOperatorThereIsNoAutomaticSequence) {
  CommandSources sources;
  sources.restart(false);
  EXPECT_TRUE(take(sources).empty());
  EXPECT_TRUE(take(sources).empty());
}

TEST(CommandSources, ANewRunForgetsTheLastRunsStop) {
  CommandSources sources;
  sources.restart(true);
  sources.request_stop();
  take(sources);
  sources.restart(true);
  EXPECT_EQ(take(sources).front().kind, K::kReset);
}
