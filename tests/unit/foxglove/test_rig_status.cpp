// Rig state and trips as Foxglove statuses: set with an id while active,
// removed when they clear (a fault reset, or resuming from a hold).
#include <gtest/gtest.h>

#include "foxglove/telemetry/rig_status.hpp"
#include "state_message.hpp"

using namespace rigctl::foxglove;

namespace {

rigctl::state_t state(const std::string& safety, const std::string& event = "", const std::string& message = "") {
  return rigctl::test::state_message(safety, event, message);
}

TEST(RigStatus, StateChangesReplaceOneStatusWithALevelForTheState) {
  RigStatus status;
  auto changes = status.update(state("running"));
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].id, RigStatus::kStateId);
  EXPECT_EQ(changes[0].level, StatusLevel::kInfo);
  EXPECT_TRUE(status.update(state("running")).empty());  // no change, nothing sent
  changes = status.update(state("holding"));
  ASSERT_EQ(changes.size(), 1u);
  EXPECT_EQ(changes[0].level, StatusLevel::kWarning);
}

TEST(RigStatus, AnInterlockIsAnErrorUntilTheFaultIsReset) {
  RigStatus status;
  status.update(state("running"));
  auto changes = status.update(state("faulted", "limit_tripped", "x_r = 0.3 m outside its limits (action interlock)"));
  ASSERT_EQ(changes.size(), 2u);
  EXPECT_EQ(changes[0].level, StatusLevel::kError);  // the rig state
  EXPECT_EQ(changes[1].id, "trip:limit_tripped:x_r");
  EXPECT_EQ(changes[1].level, StatusLevel::kError);
  EXPECT_NE(changes[1].message.find("x_r = 0.3 m"), std::string::npos);
  changes = status.update(state("off", "fault_reset", "every fault cleared"));
  ASSERT_GE(changes.size(), 1u);
  EXPECT_TRUE(changes[0].remove);
  EXPECT_EQ(changes[0].id, "trip:limit_tripped:x_r");
  for (const auto& c : status.update(state("off", "fault_reset"))) EXPECT_FALSE(c.remove) << "removed twice: " << c.id;
}

TEST(RigStatus, AHoldTripIsAWarningThatClearsWhenTheRigResumes) {
  RigStatus status;
  status.update(state("running"));
  const auto trip = status.update(state("holding", "tracking_error", "x_r tracking error 0.03 m over its limit (action hold)"));
  ASSERT_EQ(trip.size(), 2u);
  EXPECT_EQ(trip[1].level, StatusLevel::kWarning);
  const auto resumed = status.update(state("running"));
  ASSERT_EQ(resumed.size(), 2u);
  EXPECT_TRUE(resumed[0].remove);
  EXPECT_EQ(resumed[0].id, "trip:tracking_error:x_r");
  EXPECT_FALSE(resumed[1].remove);
}

TEST(RigStatus, OrdinaryEventsAreNoTrips) {
  EXPECT_TRUE(is_trip_event("limit_tripped"));
  EXPECT_TRUE(is_trip_event("sensor_stuck"));
  EXPECT_FALSE(is_trip_event("run_started"));
  EXPECT_FALSE(is_trip_event("command_accepted"));
  EXPECT_FALSE(is_trip_event(""));
}

}  // namespace
