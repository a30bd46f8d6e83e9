// RPC III time histories (.rsp, .drv, .tim): written and read back, and a
// malformed file refused with the keyword or record that is wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <numbers>

#include "tools/iterate/rpc3_file.hpp"

namespace rigctl {
namespace {

Rpc3File two_channels(std::size_t n) {
  Rpc3File f;
  f.time_type = "RESPONSE";
  f.period_s = 0.0025;
  Rpc3Channel a{"x_w", "m", {}}, b{"road", "m", {}};
  for (std::size_t i = 0; i < n; ++i) {
    const double t = static_cast<double>(i) * f.period_s;
    a.values.push_back(0.08 + 0.01 * std::sin(2 * std::numbers::pi * 1.3 * t));
    b.values.push_back(-0.002 + 0.02 * std::cos(2 * std::numbers::pi * 7.1 * t));
  }
  f.channels = {a, b};
  return f;
}

std::string temp_path(const std::string& name) { return (std::filesystem::path(::testing::TempDir()) / name).string(); }

// The keyword record `index` (0-based) of a written file, overwritten.
void set_record(std::string& bytes, std::size_t index, const std::string& key, const std::string& value) {
  std::memset(bytes.data() + index * 128, 0, 128);
  std::memcpy(bytes.data() + index * 128, key.data(), key.size());
  std::memcpy(bytes.data() + index * 128 + 32, value.data(), value.size());
}

TEST(Rpc3File, ShortIntegerRoundTripKeepsEveryChannelWithinOneCount) {
  const Rpc3File f = two_channels(5000);  // not a whole number of frames: the last is padded
  const std::string path = temp_path("round_trip.rsp");
  write_rpc3_file(f, path, Rpc3DataType::kShortInteger);
  const Rpc3File back = read_rpc3_file(path);
  EXPECT_EQ(back.time_type, "RESPONSE");
  EXPECT_DOUBLE_EQ(back.period_s, 0.0025);
  ASSERT_EQ(back.channels.size(), 2u);
  for (std::size_t c = 0; c < 2; ++c) {
    const auto& in = f.channels[c].values;
    const auto& out = back.channels[c].values;
    EXPECT_EQ(back.channels[c].name, f.channels[c].name);
    EXPECT_EQ(back.channels[c].unit, "m");
    ASSERT_EQ(out.size(), 5120u);  // 5 frames of 1024 points
    double peak = 0.0;
    for (double v : in) peak = std::max(peak, std::abs(v));
    const double count = peak / 32752.0;
    for (std::size_t i = 0; i < in.size(); ++i) ASSERT_NEAR(out[i], in[i], 0.51 * count) << "channel " << c << " point " << i;
    for (std::size_t i = in.size(); i < out.size(); ++i) ASSERT_NEAR(out[i], in.back(), 0.51 * count);
  }
}

TEST(Rpc3File, FloatingPointRoundTripIsExactToSinglePrecision) {
  const Rpc3File f = two_channels(3000);
  const std::string path = temp_path("round_trip.drv");
  Rpc3File drive = f;
  drive.time_type = rpc3_time_type_for(path);
  write_rpc3_file(drive, path, Rpc3DataType::kFloatingPoint);
  const Rpc3File back = read_rpc3_file(path);
  EXPECT_EQ(back.time_type, "DRIVE");
  const auto& in = f.channel("road", "f");
  const auto& out = back.channel("road", path);
  for (std::size_t i = 0; i < in.size(); ++i) ASSERT_EQ(out[i], static_cast<double>(static_cast<float>(in[i])));
}

TEST(Rpc3File, ExtensionsOfTimeHistories) {
  EXPECT_TRUE(is_rpc3_path("a/b.rsp"));
  EXPECT_TRUE(is_rpc3_path("b.DRV"));
  EXPECT_TRUE(is_rpc3_path("b.tim"));
  EXPECT_FALSE(is_rpc3_path("b.csv"));
  EXPECT_EQ(rpc3_time_type_for("x.tim"), "RESPONSE");
}

TEST(Rpc3File, MalformedHeadersAreRefusedNamingWhatIsWrong) {
  const std::string good = rpc3_bytes(two_channels(2048), Rpc3DataType::kShortInteger);
  ASSERT_NO_THROW(parse_rpc3(good, "good.rsp"));
  auto fails_with = [](const std::string& bytes, const std::string& text) {
    try {
      parse_rpc3(bytes, "bad.rsp");
      ADD_FAILURE() << "accepted; expected an error with '" << text << "'";
    } catch (const Rpc3Error& e) {
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("bad.rsp"), std::string::npos) << e.what();
    }
  };
  fails_with(good.substr(0, 300), "shorter than one 512-byte header block");
  std::string b = good;
  set_record(b, 0, "FILE_TYPE", "TIME_HISTORY");
  fails_with(b, "header record 1 is 'FILE_TYPE', expected FORMAT");
  b = good;
  set_record(b, 0, "FORMAT", "BINARY_IEEE_BIG_END");
  fails_with(b, "FORMAT BINARY_IEEE_BIG_END is not read");
  b = good;
  set_record(b, 2, "NUM_PARAMS", "999");
  fails_with(b, "NUM_PARAMS 999 do not fit");
  b = good;
  set_record(b, 1, "NUM_HEADER_BLOCKS", "two");
  fails_with(b, "NUM_HEADER_BLOCKS: 'two' is not a number");
  b = good;
  set_record(b, 5, "DELTA_X", "0.0025");  // record 6 held DELTA_T
  fails_with(b, "header keyword DELTA_T missing");
  fails_with(good.substr(0, good.size() - 100), "the data hold fewer than the header's 2 frames");
}

TEST(Rpc3File, AMissingChannelNamesTheChannelsTheFileHas) {
  const Rpc3File f = two_channels(100);
  try {
    f.channel("x_b", "t.rsp");
    FAIL();
  } catch (const Rpc3Error& e) {
    EXPECT_NE(std::string(e.what()).find("no channel 'x_b' (channels: x_w, road)"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace rigctl
