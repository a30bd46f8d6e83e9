// Kinds are types (issue 13, item 4): every kind a config, a run file or a
// command line names is an enum whose text names are a contract. The names
// round-trip, and an unknown name in a config is an error naming the file,
// the line, the key and the known names.
#include <gtest/gtest.h>

#include <set>
#include <string>
#include <vector>

#include "config/rig_config.hpp"
#include "config_edit.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {
namespace {

using test::config_error_of;
using test::edit;
using test::line_of;
using test::shipped_config;

// Every enumerator that has a name: each value of the 8-bit underlying type
// whose to_string is not the fallback.
template <typename Kind>
std::vector<Kind> named_enumerators() {
  std::vector<Kind> out;
  for (int v = 0; v <= 255; ++v) {
    const auto k = static_cast<Kind>(v);
    if (to_string(k) != "unknown") out.push_back(k);
  }
  return out;
}

// The known names are exactly `names` (the contract), every one parses back
// to its enumerator, and the known list holds every named enumerator but
// those in `not_named_in_text`.
template <typename Kind>
void expect_round_trip(const std::vector<std::string>& names, const std::set<Kind>& not_named_in_text = {}) {
  std::vector<std::string> known;
  for (const Kind k : KindNames<Kind>::known) {
    known.emplace_back(to_string(k));
    const auto parsed = kind_from_string<Kind>(to_string(k));
    ASSERT_TRUE(parsed.has_value()) << to_string(k);
    EXPECT_EQ(*parsed, k);
    EXPECT_EQ(parse_kind<Kind>(to_string(k)), k);
  }
  EXPECT_EQ(known, names);
  std::set<Kind> listed(KindNames<Kind>::known.begin(), KindNames<Kind>::known.end());
  for (const Kind k : named_enumerators<Kind>()) {
    EXPECT_TRUE(listed.count(k) == 1 || not_named_in_text.count(k) == 1)
        << to_string(k) << " has a name but is missing from KindNames::known";
  }
  for (const Kind k : not_named_in_text) EXPECT_FALSE(kind_from_string<Kind>(to_string(k)).has_value()) << k;
  EXPECT_FALSE(kind_from_string<Kind>("").has_value());
  EXPECT_FALSE(kind_from_string<Kind>("unknown").has_value());
  EXPECT_FALSE(kind_from_string<Kind>(names.front() + " ").has_value()) << "names match exactly";
  EXPECT_THROW(parse_kind<Kind>("no_such_kind"), std::invalid_argument);
}

TEST(Kinds, RigKindNamesRoundTrip) { expect_round_trip<RigKind>({"quarter_car", "pneumatic_rotary", "half_car", "two_poster"}); }

TEST(Kinds, DriverKindNamesRoundTrip) { expect_round_trip<DriverKind>({"sim", "modbus", "modbus_canopen"}); }

TEST(Kinds, ControllerKindNamesRoundTrip) {
  expect_round_trip<ControllerKind>({"pi", "pvp", "passive", "fuzzy", "skyhook", "lqr"});
}

TEST(Kinds, ProfileKindNamesRoundTrip) { expect_round_trip<ProfileKind>({"ramp_steps", "sine", "csv", "hold"}); }

TEST(Kinds, DetectorKindNamesRoundTripAndInvalidIsNotConfigurable) {
  expect_round_trip<DetectorKind>({"range", "rate", "tracking_error", "valve_saturation", "sample_age", "overruns",
                                   "open_circuit", "stuck"},
                                  {DetectorKind::kInvalid});
}

TEST(Kinds, RunFileRigNamesRoundTripAndMatchTheControlledRigs) {
  expect_round_trip<RunFileRig>({"quarter_car", "pneumatic_rotary", "half_car", "linear_axis", "damper"});
  for (const RigKind k : KindNames<RigKind>::known) {
    if (k == RigKind::kTwoPoster) {
      EXPECT_FALSE(run_file_rig(k).has_value());  // no diagnosis model of it yet
      continue;
    }
    ASSERT_TRUE(run_file_rig(k).has_value()) << to_string(k);
    EXPECT_EQ(to_string(*run_file_rig(k)), to_string(k));
  }
}

TEST(Kinds, UnknownNameMessageListsTheKnownNames) {
  EXPECT_EQ(unknown_kind_message<ControllerKind>("pid"),
            "unknown controller 'pid' (known: pi, pvp, passive, fuzzy, skyhook, lqr)");
  try {
    parse_kind<RigKind>("bicycle");
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "unknown rig kind 'bicycle' (known: quarter_car, pneumatic_rotary, half_car, two_poster)");
  }
}

TEST(Kinds, KindsPrintByName) {
  std::ostringstream out;
  out << RigKind::kPneumaticRotary << " " << ControllerKind::kLqr << " " << DetectorKind::kStuck;
  EXPECT_EQ(out.str(), "pneumatic_rotary lqr stuck");
}

TEST(Kinds, EachRigRunsItsOwnControllers) {
  EXPECT_EQ(controllers_of(RigKind::kQuarterCar), std::vector<ControllerKind>{ControllerKind::kPi});
  EXPECT_EQ(controllers_of(RigKind::kPneumaticRotary), std::vector<ControllerKind>{ControllerKind::kPvp});
  // The two-poster's posts are position loops: either position controller.
  EXPECT_EQ(controllers_of(RigKind::kTwoPoster), (std::vector<ControllerKind>{ControllerKind::kPi, ControllerKind::kPvp}));
  // The order `rigctl compare` runs and reports them in: passive first.
  EXPECT_EQ(controllers_of(RigKind::kHalfCar),
            (std::vector<ControllerKind>{ControllerKind::kPassive, ControllerKind::kFuzzy, ControllerKind::kSkyhook,
                                         ControllerKind::kLqr}));
}

TEST(Kinds, DriverKindsSayWhatTheyNeed) {
  EXPECT_TRUE(is_simulated(DriverKind::kSim));
  EXPECT_FALSE(is_simulated(DriverKind::kModbus));
  EXPECT_FALSE(is_simulated(DriverKind::kModbusCanopen));
  EXPECT_FALSE(uses_modbus_daq(DriverKind::kSim));
  EXPECT_TRUE(uses_modbus_daq(DriverKind::kModbus));
  EXPECT_TRUE(uses_modbus_daq(DriverKind::kModbusCanopen));
  EXPECT_FALSE(uses_canopen_valve(DriverKind::kModbus));
  EXPECT_TRUE(uses_canopen_valve(DriverKind::kModbusCanopen));
}

// One kind field of a shipped config edited to `bad`: the whole error is
// "bad.yaml:LINE: KEY: MESSAGE", LINE the edited line.
void expect_kind_error(const std::string& config, const std::string& pattern, const std::string& bad,
                       const std::string& key, const std::string& message) {
  const std::string yaml = edit(shipped_config(config), pattern, bad);
  const int line = line_of(yaml, bad);
  ASSERT_GT(line, 0);
  EXPECT_EQ(config_error_of(yaml), "bad.yaml:" + std::to_string(line) + ": " + key + ": " + message);
}

TEST(KindsInConfig, UnknownRigKind) {
  expect_kind_error("quarter_car.yaml", "rig: quarter_car", "rig: quarter_cat", "rig",
                    "unknown rig kind 'quarter_cat' (known: quarter_car, pneumatic_rotary, half_car, two_poster)");
}

TEST(KindsInConfig, UnknownDriver) {
  expect_kind_error("quarter_car.yaml", "driver: sim", "driver: ethercat", "driver",
                    "unknown driver 'ethercat' (known: sim, modbus, modbus_canopen)");
}

TEST(KindsInConfig, UnknownController) {
  const std::string message = "unknown controller 'pid' (known: pi, pvp, passive, fuzzy, skyhook, lqr)";
  expect_kind_error("quarter_car.yaml", "  type: pi", "  type: pid", "controller.type", message);
  expect_kind_error("pneumatic_rotary.yaml", "  type: pvp", "  type: pid", "controller.type", message);
  expect_kind_error("half_car.yaml", "  type: fuzzy ", "  type: pid ", "controller.type", message);
}

TEST(KindsInConfig, AKnownControllerOfAnotherRigIsRefused) {
  expect_kind_error("quarter_car.yaml", "  type: pi", "  type: pvp", "controller.type",
                    "controller 'pvp' is for the pneumatic_rotary rig, not quarter_car (quarter_car runs: pi)");
  expect_kind_error("pneumatic_rotary.yaml", "  type: pvp", "  type: fuzzy", "controller.type",
                    "controller 'fuzzy' is for the half_car rig, not pneumatic_rotary (pneumatic_rotary runs: pvp)");
  expect_kind_error("half_car.yaml", "  type: fuzzy ", "  type: pi ", "controller.type",
                    "controller 'pi' is for the quarter_car rig, not half_car (half_car runs: passive, fuzzy, skyhook, lqr)");
  expect_kind_error("half_car.yaml", "  controller: passive ", "  controller: pvp ", "optimize.controller",
                    "controller 'pvp' is for the pneumatic_rotary rig, not half_car (half_car runs: passive, fuzzy, skyhook, lqr)");
}

TEST(KindsInConfig, UnknownOptimizeController) {
  expect_kind_error("half_car.yaml", "  controller: passive ", "  controller: active ", "optimize.controller",
                    "unknown controller 'active' (known: pi, pvp, passive, fuzzy, skyhook, lqr)");
}

TEST(KindsInConfig, UnknownProfile) {
  expect_kind_error("quarter_car.yaml", "  type: ramp_steps", "  type: square", "profile.type",
                    "unknown profile 'square' (known: ramp_steps, sine, csv, hold)");
}

TEST(KindsInConfig, UnknownDetector) {
  const std::string known = "(known: range, rate, tracking_error, valve_saturation, sample_age, overruns, open_circuit, stuck)";
  expect_kind_error("quarter_car.yaml", "x_r_rate: \\{type: rate,", "x_r_rate: {type: jerk,",
                    "safety.detectors.x_r_rate.type", "unknown detector 'jerk' " + known);
  // Every input gets its plausibility check by itself: never configured.
  expect_kind_error("quarter_car.yaml", "x_r_rate: \\{type: rate,", "x_r_rate: {type: invalid,",
                    "safety.detectors.x_r_rate.type", "unknown detector 'invalid' " + known);
}

// The shipped configs name every kind they use by its contract name.
TEST(KindsInConfig, ShippedConfigsParseToTheirKinds) {
  const RigConfig q = parse_rig_config(shipped_config("quarter_car.yaml"), "q.yaml");
  EXPECT_EQ(q.rig, RigKind::kQuarterCar);
  EXPECT_EQ(q.driver, DriverKind::kSim);
  EXPECT_EQ(q.controller.type, ControllerKind::kPi);
  EXPECT_EQ(q.profile.type, ProfileKind::kRampSteps);
  std::vector<DetectorKind> detectors;
  for (const auto& d : q.safety.detectors) detectors.push_back(d.type);
  EXPECT_EQ(detectors, (std::vector<DetectorKind>{
                           DetectorKind::kOpenCircuit, DetectorKind::kRate, DetectorKind::kTrackingError,
                           DetectorKind::kValveSaturation, DetectorKind::kStuck, DetectorKind::kSampleAge,
                           DetectorKind::kOverruns, DetectorKind::kRate, DetectorKind::kRange, DetectorKind::kRange,
                           DetectorKind::kOverruns}));
  const RigConfig h = parse_rig_config(shipped_config("half_car.yaml"), "h.yaml");
  EXPECT_EQ(h.rig, RigKind::kHalfCar);
  EXPECT_EQ(h.controller.type, ControllerKind::kFuzzy);
  EXPECT_EQ(h.profile.type, ProfileKind::kHold);
  EXPECT_EQ(h.suspension_optimize.controller, ControllerKind::kPassive);
}

}  // namespace
}  // namespace rigctl
