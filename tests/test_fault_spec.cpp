#include <gtest/gtest.h>

#include "tools/fault_spec.hpp"

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
}
