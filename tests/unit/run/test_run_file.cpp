// Run-file reader (tools/run_file.*) against docs/run-files.md section 1.
#include <gtest/gtest.h>

#include <sstream>

#include "tools/runfile/run_file.hpp"

namespace rigctl {
namespace {

std::string rows(int n, double dt = 0.001) {
  std::ostringstream os;
  for (int i = 0; i < n; ++i) os << i * dt << "," << 0.1 * i << "," << -0.2 * i << "\n";
  return os.str();
}

RunFile parse(const std::string& text, RunFileOptions o = {}) {
  std::istringstream in(text);
  return parse_run_file(in, "run.csv", o);
}

std::string error_of(const std::string& text, RunFileOptions o = {}) {
  try {
    parse(text, o);
  } catch (const RunFileError& e) {
    return e.what();
  }
  return "";
}

RunFileOptions damper() { return run_file_columns(RunFileRig::kDamper); }

TEST(RunFile, MetadataHeaderAndColumns) {
  const auto rf = parse("# rig: damper\n# sample_rate_hz: 1000\n# note: a: b\nt,x,f,extra\n" + [] {
    std::ostringstream os;
    for (int i = 0; i < 20; ++i) os << i * 0.001 << "," << i << "," << 2 * i << ",junk\n";
    return os.str();
  }(), damper());
  ASSERT_EQ(rf.size(), 20u);
  EXPECT_EQ(*rf.meta("rig"), "damper");
  EXPECT_EQ(*rf.meta("note"), "a: b");
  EXPECT_DOUBLE_EQ(*rf.meta_number("sample_rate_hz"), 1000.0);
  EXPECT_NEAR(rf.dt, 0.001, 1e-12);
  EXPECT_FALSE(rf.resampled);
  EXPECT_DOUBLE_EQ(rf.col("f")[3], 6.0);
  EXPECT_FALSE(rf.has("extra"));  // unknown column ignored, even with text in it
  EXPECT_EQ(rf.header.size(), 4u);
}

TEST(RunFile, CrLfAndBom) {
  std::string text = "\xEF\xBB\xBFt,x,f\r\n";
  for (int i = 0; i < 12; ++i) text += std::to_string(i * 0.01) + ",1,2\r\n";
  const auto rf = parse(text, damper());
  EXPECT_EQ(rf.size(), 12u);
  EXPECT_DOUBLE_EQ(rf.col("f")[0], 2.0);
}

TEST(RunFile, MissingRequiredColumnNamed) {
  const auto e = error_of("t,x,g\n" + rows(20), damper());
  EXPECT_NE(e.find("missing required column 'f'"), std::string::npos) << e;
}

TEST(RunFile, TimeMustComeFirst) {
  const auto e = error_of("x,t,f\n" + rows(20), damper());
  EXPECT_NE(e.find("first column must be 't'"), std::string::npos) << e;
}

TEST(RunFile, EmptyCellNamesLineAndColumn) {
  std::string text = "t,x,f\n" + rows(5) + "0.005,,1\n" + rows(20).substr(0, 0);
  const auto e = error_of(text, damper());
  EXPECT_NE(e.find("line 7, column 'x'"), std::string::npos) << e;
  EXPECT_NE(e.find("empty cell"), std::string::npos) << e;
}

TEST(RunFile, NanAndTextRejected) {
  EXPECT_NE(error_of("t,x,f\n" + rows(5) + "0.005,1,nan\n", damper()).find("line 7, column 'f'"), std::string::npos);
  EXPECT_NE(error_of("t,x,f\n" + rows(5) + "0.005,abc,1\n", damper()).find("not a number: 'abc'"), std::string::npos);
  EXPECT_NE(error_of("t,x,f\n" + rows(5) + "0.005,1.5x,1\n", damper()).find("not a number"), std::string::npos);
  EXPECT_NE(error_of("t,x,f\n" + rows(5) + "0.005,inf,1\n", damper()).find("not a finite number"), std::string::npos);
}

TEST(RunFile, ShortAndLongRows) {
  const auto e = error_of("t,x,f\n" + rows(5) + "0.005,1\n", damper());
  EXPECT_NE(e.find("line 7: short row"), std::string::npos) << e;
  EXPECT_NE(e.find("'f' missing"), std::string::npos) << e;
  EXPECT_NE(error_of("t,x,f\n" + rows(5) + "0.005,1,2,3\n", damper()).find("line 7: 4 cells"), std::string::npos);
}

TEST(RunFile, DropBadRowsCountsThem) {
  auto o = damper();
  o.drop_bad_rows = true;
  std::ostringstream os;
  os << "t,x,f\n";
  for (int i = 0; i < 30; ++i) {
    if (i == 10) os << i * 0.001 << ",nan,1\n";
    else if (i == 11) os << i * 0.001 << ",1\n";
    else os << i * 0.001 << "," << i << ",1\n";
  }
  // dropping two rows leaves a 3-step gap, which is then rejected...
  EXPECT_NE(error_of(os.str(), o).find("a gap"), std::string::npos);
  // ...while a dropped bad row without a gap (duplicated sample) is counted.
  std::ostringstream ok;
  ok << "t,x,f\n";
  for (int i = 0; i < 30; ++i) {
    ok << i * 0.001 << "," << i << ",1\n";
    if (i == 10) ok << i * 0.001 << ",oops,1\n";
  }
  const auto rf = parse(ok.str(), o);
  EXPECT_EQ(rf.dropped_rows, 1u);
  EXPECT_EQ(rf.size(), 30u);
}

TEST(RunFile, TimeNotIncreasingNamesLine) {
  std::string text = "t,x,f\n0,1,1\n0.001,1,1\n0.001,1,1\n" + rows(20).substr(0, 0);
  for (int i = 3; i < 20; ++i) text += std::to_string(i * 0.001) + ",1,1\n";
  const auto e = error_of(text, damper());
  EXPECT_NE(e.find("line 4: time does not increase"), std::string::npos) << e;
}

TEST(RunFile, GapRejectedWithLine) {
  std::string text = "t,x,f\n";
  for (int i = 0; i < 20; ++i) text += std::to_string((i < 10 ? i : i + 5) * 0.001) + ",1,1\n";
  const auto e = error_of(text, damper());
  EXPECT_NE(e.find("line 12: time step"), std::string::npos) << e;
  EXPECT_NE(e.find("gap"), std::string::npos) << e;
}

TEST(RunFile, JitterResampledToMedianStep) {
  std::string text = "t,x,f\n";
  for (int i = 0; i < 41; ++i) {
    const double t = i * 0.01 + (i % 2 ? 0.002 : 0.0) * (i < 40);
    text += std::to_string(t) + "," + std::to_string(2.0 * t) + ",1\n";
  }
  const auto rf = parse(text, damper());
  EXPECT_TRUE(rf.resampled);
  EXPECT_NEAR(rf.dt, 0.01, 0.0021);
  for (std::size_t i = 0; i < rf.size(); ++i) EXPECT_NEAR(rf.col("x")[i], 2.0 * rf.t[i], 1e-9);
}

TEST(RunFile, TooFewRowsAndNoHeader) {
  EXPECT_NE(error_of("# rig: damper\n", damper()).find("no header"), std::string::npos);
  EXPECT_NE(error_of("t,x,f\n0,1,1\n", damper()).find("only 1 data rows"), std::string::npos);
}

TEST(RunFile, DuplicateColumnAndUnknownRig) {
  EXPECT_NE(error_of("t,x,x,f\n" + rows(20), damper()).find("duplicate column 'x'"), std::string::npos);
  try {
    run_file_rig_from_string("bicycle");
    FAIL();
  } catch (const RunFileError& e) {
    EXPECT_STREQ(e.what(), "unknown rig kind 'bicycle' (known: quarter_car, pneumatic_rotary, half_car, linear_axis, damper)");
  }
  EXPECT_EQ(run_file_columns(run_file_rig_from_string("quarter_car")).required.size(), 5u);
}

TEST(RunFile, BadMetadataNumberNamed) {
  const auto rf = parse("# kp: fast\nt,x,f\n" + rows(20), damper());
  try {
    rf.meta_number("kp");
    FAIL();
  } catch (const RunFileError& e) {
    EXPECT_NE(std::string(e.what()).find("metadata 'kp'"), std::string::npos);
  }
}

TEST(RunFile, MissingFile) {
  EXPECT_THROW(read_run_file("/nonexistent/run.csv", damper()), RunFileError);
}

}  // namespace
}  // namespace rigctl
