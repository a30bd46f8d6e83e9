#include <gtest/gtest.h>

#include "drivers/sim/fault_spec.hpp"

using namespace rigctl;

TEST(FaultSpec, ParsesEveryKind) {
  auto f = parse_fault_spec("silence@5:1.5");
  EXPECT_EQ(f.kind, FaultKind::kSilence);
  EXPECT_DOUBLE_EQ(f.at_s, 5.0);
  EXPECT_DOUBLE_EQ(f.duration_s, 1.5);
  EXPECT_EQ(parse_fault_spec("silence@5").duration_s, 0.0);
  EXPECT_EQ(parse_fault_spec("drop@2.5").kind, FaultKind::kDrop);
  f = parse_fault_spec("late@1:0.02:3");
  EXPECT_EQ(f.kind, FaultKind::kLate);
  EXPECT_DOUBLE_EQ(f.delay_s, 0.02);
  EXPECT_DOUBLE_EQ(f.duration_s, 3.0);
  f = parse_fault_spec("exception@4:x_r:2");
  EXPECT_EQ(f.kind, FaultKind::kException);
  EXPECT_EQ(f.channel, "x_r");
  EXPECT_EQ(f.code, 2);
  EXPECT_EQ(parse_fault_spec("stuck@4:x_b").kind, FaultKind::kStuck);
  EXPECT_EQ(parse_fault_spec("rail@4:p1").channel, "p1");
  EXPECT_DOUBLE_EQ(parse_fault_spec("heartbeat@3:0.5").duration_s, 0.5);
  f = parse_fault_spec("emcy@3:0x5000:1");
  EXPECT_EQ(f.code, 0x5000);
  EXPECT_EQ(f.error_register, 1);
  f = parse_fault_spec("hold@3:0.5");
  EXPECT_EQ(f.kind, FaultKind::kHold);
  EXPECT_DOUBLE_EQ(f.duration_s, 0.5);
  EXPECT_TRUE(fault_on_wire(FaultKind::kHold));
  EXPECT_FALSE(fault_in_process(FaultKind::kHold));
}

TEST(FaultSpec, BadSpecsNameWhatIsWrong) {
  const auto message = [](const std::string& spec) {
    try {
      parse_fault_spec(spec);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message("drop").find("KIND@TIME"), std::string::npos);
  EXPECT_NE(message("melt@1").find("unknown kind 'melt'"), std::string::npos);
  EXPECT_NE(message("drop@-1").find("time '-1'"), std::string::npos);
  EXPECT_NE(message("late@1").find("late@TIME:DELAY"), std::string::npos);
  EXPECT_NE(message("exception@1:x_r:0").find("1..255"), std::string::npos);
  EXPECT_NE(message("stuck@1:").find("channel"), std::string::npos);
  EXPECT_NE(message("emcy@1:zz:1").find("EMCY code 'zz'"), std::string::npos);
  EXPECT_NE(message("hold@1").find("hold@TIME:DURATION"), std::string::npos);
}

TEST(FaultSpec, ParsesTheSimulatedDriversKinds) {
  auto f = parse_fault_spec("noise@5:x_r:0.005:0.5");
  EXPECT_EQ(f.kind, FaultKind::kNoise);
  EXPECT_EQ(f.channel, "x_r");
  EXPECT_DOUBLE_EQ(f.value, 0.005);
  EXPECT_DOUBLE_EQ(f.duration_s, 0.5);
  EXPECT_EQ(parse_fault_spec("noise@5:x_r:0.005").duration_s, 0.0);
  f = parse_fault_spec("nan@2:p1:0.1");
  EXPECT_EQ(f.kind, FaultKind::kNan);
  EXPECT_DOUBLE_EQ(f.duration_s, 0.1);
  f = parse_fault_spec("offset@5:x_r:-0.01");
  EXPECT_EQ(f.kind, FaultKind::kOffset);
  EXPECT_DOUBLE_EQ(f.value, -0.01);
  f = parse_fault_spec("overrun@5:25");
  EXPECT_EQ(f.kind, FaultKind::kOverrun);
  EXPECT_EQ(f.count, 25);
  EXPECT_EQ(f.stall_periods, 2);
  EXPECT_EQ(parse_fault_spec("overrun@5:3:7").stall_periods, 7);
  f = parse_fault_spec("supply@5:1e6");
  EXPECT_EQ(f.kind, FaultKind::kSupply);
  EXPECT_DOUBLE_EQ(f.value, 1e6);
  f = parse_fault_spec("burst@5:p2:2e-6");
  EXPECT_EQ(f.kind, FaultKind::kBurst);
  EXPECT_EQ(f.channel, "p2");
  EXPECT_DOUBLE_EQ(f.value, 2e-6);
  EXPECT_DOUBLE_EQ(parse_fault_spec("burst@5:p1").value, 1e-6);
  // Where each can be injected: rig-sim's wire, the simulated driver, or both.
  EXPECT_TRUE(fault_on_wire(FaultKind::kDrop));
  EXPECT_FALSE(fault_in_process(FaultKind::kDrop));
  EXPECT_TRUE(fault_in_process(FaultKind::kStuck));
  EXPECT_TRUE(fault_on_wire(FaultKind::kStuck));
  EXPECT_FALSE(fault_on_wire(FaultKind::kBurst));
}

TEST(FaultSpec, BadSimulatedDriverSpecsNameWhatIsWrong) {
  const auto message = [](const std::string& spec) {
    try {
      parse_fault_spec(spec);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message("noise@1:x_r").find("noise@TIME:CHANNEL:SD"), std::string::npos);
  EXPECT_NE(message("noise@1:x_r:-1").find("noise SD '-1'"), std::string::npos);
  EXPECT_NE(message("offset@1:x_r:abc").find("offset 'abc'"), std::string::npos);
  EXPECT_NE(message("overrun@1:0").find("at least 1"), std::string::npos);
  EXPECT_NE(message("supply@1:-5").find("supply pressure '-5'"), std::string::npos);
  EXPECT_NE(message("burst@1:p3").find("not p1 or p2"), std::string::npos);
  EXPECT_NE(message("nan@1:").find("channel"), std::string::npos);
}

// The config's `faults:` list and `rigctl run --fault`: each fault only where it can act.
#include <fstream>
#include <sstream>

#include "config/config_reader.hpp"
#include "config/rig_config.hpp"
#include "config_edit.hpp"
#include "process.hpp"

using rigctl::test::shipped_config;

TEST(FaultSpec, ConfigFaultsListIsReadAndABadEntryIsNamed) {
  const RigConfig c = parse_rig_config(shipped_config() + "\nfaults: [\"stuck@5:x_r\", \"burst@6:p2\"]\n", "q.yaml");
  ASSERT_EQ(c.faults.size(), 2u);
  EXPECT_EQ(c.faults[0].kind, FaultKind::kStuck);
  EXPECT_EQ(c.faults[1].kind, FaultKind::kBurst);
  try {
    parse_rig_config(shipped_config() + "\nfaults: [\"stuck@5:x_r\", \"melt@6\"]\n", "q.yaml");
    FAIL() << "a bad fault was accepted";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("faults[1]"), std::string::npos) << what;
    EXPECT_NE(what.find("unknown kind 'melt'"), std::string::npos) << what;
  }
}

TEST(FaultSpec, EachFaultIsAcceptedOnlyWhereItCanAct) {
  const std::string rigctl = RIGCTL_BINARY;
  const std::string config = std::string(RIGCTL_SOURCE_DIR) + "/config/quarter_car.yaml";
  // A wire fault given to the simulated driver, and a channel it does not have.
  auto r = rigctl::test::run_command(rigctl + " run " + config + " --fast --duration 0.1 --log /dev/null --events /dev/null --fault drop@3");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("acts on the wire"), std::string::npos) << r.output;
  r = rigctl::test::run_command(rigctl + " run " + config + " --fast --duration 0.1 --log /dev/null --events /dev/null --fault nan@1:q9");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("no input channel 'q9'"), std::string::npos) << r.output;
  // An in-process fault given to rig-sim.
  r = rigctl::test::run_command(rigctl + " rig-sim " + config + " --modbus 127.0.0.1:0 --duration 0.1 --fault burst@1:p1");
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("simulated driver"), std::string::npos) << r.output;
}
