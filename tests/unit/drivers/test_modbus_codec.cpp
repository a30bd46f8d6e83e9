// Register decoding and encoding of the Modbus DAQ (every data format and
// word order), the config-name parsers and the batched read plan.
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <limits>
#include <new>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "drivers/modbus/modbus_codec.hpp"
#include "allocation_counter.hpp"

using namespace rigctl;


namespace {

constexpr std::array kAllOrders = {WordOrder::kHighFirst, WordOrder::kLowFirst, WordOrder::kHighFirstByteSwapped,
                                   WordOrder::kLowFirstByteSwapped};
constexpr std::array kAllFormats = {DataFormat::kInt16, DataFormat::kUint16, DataFormat::kInt32,
                                    DataFormat::kUint32, DataFormat::kFloat32};

struct Pattern {
  DataFormat format;
  WordOrder order;
  std::array<uint16_t, 2> regs;  // regs[1] unused for 16-bit formats
  double value;
};

std::string describe(const Pattern& p) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%s %s {0x%04X, 0x%04X}", std::string(to_string(p.format)).c_str(),
                std::string(to_string(p.order)).c_str(), p.regs[0], p.regs[1]);
  return buf;
}

// Known register images. 32-bit values with four distinct bytes show every
// byte's place; the extremes show sign handling.
const std::vector<Pattern>& known_patterns() {
  using enum DataFormat;
  using enum WordOrder;
  static const std::vector<Pattern> patterns = {
      // 16-bit: word order does not matter, byte swap does.
      {kInt16, kHighFirst, {0xFFFF, 0}, -1.0},
      {kInt16, kLowFirst, {0xFFFF, 0}, -1.0},
      {kInt16, kHighFirst, {0x8000, 0}, -32768.0},
      {kInt16, kHighFirst, {0x7FFF, 0}, 32767.0},
      {kInt16, kHighFirst, {0x0102, 0}, 258.0},
      {kInt16, kLowFirst, {0x0102, 0}, 258.0},
      {kInt16, kHighFirstByteSwapped, {0x0102, 0}, 513.0},
      {kInt16, kLowFirstByteSwapped, {0x0102, 0}, 513.0},
      {kInt16, kHighFirstByteSwapped, {0x0080, 0}, -32768.0},
      {kInt16, kLowFirstByteSwapped, {0xFEFF, 0}, -2.0},
      {kUint16, kHighFirst, {0xFFFF, 0}, 65535.0},
      {kUint16, kLowFirst, {0x8000, 0}, 32768.0},
      {kUint16, kHighFirstByteSwapped, {0x0080, 0}, 32768.0},
      {kUint16, kLowFirstByteSwapped, {0x3412, 0}, 0x1234},
      {kUint16, kHighFirst, {0x0000, 0}, 0.0},
      // uint32 0x12345678 in each order.
      {kUint32, kHighFirst, {0x1234, 0x5678}, 0x12345678},
      {kUint32, kLowFirst, {0x5678, 0x1234}, 0x12345678},
      {kUint32, kHighFirstByteSwapped, {0x3412, 0x7856}, 0x12345678},
      {kUint32, kLowFirstByteSwapped, {0x7856, 0x3412}, 0x12345678},
      {kUint32, kHighFirst, {0xFFFF, 0xFFFF}, 4294967295.0},
      {kUint32, kLowFirst, {0x0000, 0x8000}, 2147483648.0},
      {kUint32, kHighFirst, {0x0000, 0x0001}, 1.0},
      {kUint32, kLowFirst, {0x0001, 0x0000}, 1.0},
      // int32 extremes and -1.
      {kInt32, kHighFirst, {0x8000, 0x0000}, -2147483648.0},
      {kInt32, kLowFirst, {0x0000, 0x8000}, -2147483648.0},
      {kInt32, kHighFirstByteSwapped, {0x0080, 0x0000}, -2147483648.0},
      {kInt32, kLowFirstByteSwapped, {0x0000, 0x0080}, -2147483648.0},
      {kInt32, kHighFirst, {0x7FFF, 0xFFFF}, 2147483647.0},
      {kInt32, kLowFirst, {0xFFFF, 0x7FFF}, 2147483647.0},
      {kInt32, kHighFirstByteSwapped, {0xFF7F, 0xFFFF}, 2147483647.0},
      {kInt32, kLowFirstByteSwapped, {0xFFFF, 0xFF7F}, 2147483647.0},
      {kInt32, kHighFirst, {0xFFFF, 0xFFFF}, -1.0},
      {kInt32, kHighFirst, {0xFFFE, 0x1DC0}, -123456.0},  // 0xFFFE1DC0
      {kInt32, kLowFirst, {0x1DC0, 0xFFFE}, -123456.0},
      {kInt32, kHighFirstByteSwapped, {0xFEFF, 0xC01D}, -123456.0},
      {kInt32, kLowFirstByteSwapped, {0xC01D, 0xFEFF}, -123456.0},
      // float32 1.5f = 0x3FC00000, -2.5f = 0xC0200000, 0.1f = 0x3DCCCCCD.
      {kFloat32, kHighFirst, {0x3FC0, 0x0000}, 1.5},
      {kFloat32, kLowFirst, {0x0000, 0x3FC0}, 1.5},
      {kFloat32, kHighFirstByteSwapped, {0xC03F, 0x0000}, 1.5},
      {kFloat32, kLowFirstByteSwapped, {0x0000, 0xC03F}, 1.5},
      {kFloat32, kHighFirst, {0xC020, 0x0000}, -2.5},
      {kFloat32, kLowFirst, {0x0000, 0xC020}, -2.5},
      {kFloat32, kHighFirst, {0x3DCC, 0xCCCD}, static_cast<double>(0.1f)},
      {kFloat32, kLowFirst, {0xCCCD, 0x3DCC}, static_cast<double>(0.1f)},
      {kFloat32, kHighFirstByteSwapped, {0xCC3D, 0xCDCC}, static_cast<double>(0.1f)},
      {kFloat32, kLowFirstByteSwapped, {0xCDCC, 0xCC3D}, static_cast<double>(0.1f)},
      {kFloat32, kHighFirst, {0x7F7F, 0xFFFF}, static_cast<double>(FLT_MAX)},
      {kFloat32, kHighFirst, {0x0000, 0x0001}, static_cast<double>(std::numeric_limits<float>::denorm_min())},
  };
  return patterns;
}

}  // namespace

TEST(ModbusCodec, RegisterCount) {
  EXPECT_EQ(register_count(DataFormat::kInt16), 1);
  EXPECT_EQ(register_count(DataFormat::kUint16), 1);
  EXPECT_EQ(register_count(DataFormat::kInt32), 2);
  EXPECT_EQ(register_count(DataFormat::kUint32), 2);
  EXPECT_EQ(register_count(DataFormat::kFloat32), 2);
}

TEST(ModbusCodec, DecodesKnownPatterns) {
  for (const Pattern& p : known_patterns()) {
    EXPECT_EQ(decode_registers(p.regs.data(), p.format, p.order), p.value) << describe(p);
  }
}

TEST(ModbusCodec, EncodesKnownPatterns) {
  for (const Pattern& p : known_patterns()) {
    std::array<uint16_t, 2> regs = {0xAAAA, 0xAAAA};
    EXPECT_EQ(encode_registers(p.value, p.format, p.order, regs.data()), EncodeStatus::kOk) << describe(p);
    EXPECT_EQ(regs[0], p.regs[0]) << describe(p);
    if (register_count(p.format) == 2) {
      EXPECT_EQ(regs[1], p.regs[1]) << describe(p);
    } else {
      EXPECT_EQ(regs[1], 0xAAAA) << describe(p) << ": a 16-bit encode must not touch the next register";
    }
  }
}

TEST(ModbusCodec, CombineAndSplitPlaceEveryByte) {
  const std::array<std::array<uint16_t, 2>, 4> expected = {{{0xA1B2, 0xC3D4},    // ABCD
                                                            {0xC3D4, 0xA1B2},    // CDAB
                                                            {0xB2A1, 0xD4C3},    // BADC
                                                            {0xD4C3, 0xB2A1}}};  // DCBA
  for (std::size_t i = 0; i < kAllOrders.size(); ++i) {
    uint16_t regs[2] = {0, 0};
    split_registers(0xA1B2C3D4u, kAllOrders[i], regs);
    EXPECT_EQ(regs[0], expected[i][0]) << to_string(kAllOrders[i]);
    EXPECT_EQ(regs[1], expected[i][1]) << to_string(kAllOrders[i]);
    EXPECT_EQ(combine_registers(expected[i].data(), kAllOrders[i]), 0xA1B2C3D4u) << to_string(kAllOrders[i]);
  }
}

TEST(ModbusCodec, FloatNanAndInfinityDecodeAsSuch) {
  for (const WordOrder order : kAllOrders) {
    uint16_t regs[2];
    split_registers(0x7FC00000u, order, regs);  // quiet NaN
    EXPECT_TRUE(std::isnan(decode_registers(regs, DataFormat::kFloat32, order))) << to_string(order);
    split_registers(0xFF800000u, order, regs);  // -inf
    EXPECT_EQ(decode_registers(regs, DataFormat::kFloat32, order), -std::numeric_limits<double>::infinity());
    split_registers(0x7F800000u, order, regs);  // +inf
    EXPECT_EQ(decode_registers(regs, DataFormat::kFloat32, order), std::numeric_limits<double>::infinity());
  }
}

TEST(ModbusCodec, IntegerRoundTripsAreExact) {
  std::mt19937_64 rng(42);
  struct Range {
    DataFormat format;
    double lo, hi;
  };
  const std::array<Range, 4> ranges = {{{DataFormat::kInt16, -32768.0, 32767.0},
                                        {DataFormat::kUint16, 0.0, 65535.0},
                                        {DataFormat::kInt32, -2147483648.0, 2147483647.0},
                                        {DataFormat::kUint32, 0.0, 4294967295.0}}};
  for (const Range& r : ranges) {
    std::vector<double> values = {r.lo, r.lo + 1, r.hi - 1, r.hi, std::round((r.lo + r.hi) / 2)};
    if (r.lo < 0) values.insert(values.end(), {-1.0, 0.0, 1.0});
    std::uniform_int_distribution<int64_t> dist(static_cast<int64_t>(r.lo), static_cast<int64_t>(r.hi));
    for (int i = 0; i < 2000; ++i) values.push_back(static_cast<double>(dist(rng)));
    for (const WordOrder order : kAllOrders) {
      for (const double v : values) {
        uint16_t regs[2] = {0, 0};
        ASSERT_EQ(encode_registers(v, r.format, order, regs), EncodeStatus::kOk) << v;
        ASSERT_EQ(decode_registers(regs, r.format, order), v) << to_string(r.format) << " " << to_string(order);
      }
    }
  }
}

TEST(ModbusCodec, FloatRoundTripsToNearestFloat) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> mantissa(-1.0, 1.0);
  std::uniform_int_distribution<int> exponent(-40, 40);
  for (const WordOrder order : kAllOrders) {
    for (int i = 0; i < 5000; ++i) {
      const double v = std::ldexp(mantissa(rng), exponent(rng));
      uint16_t regs[2];
      ASSERT_EQ(encode_registers(v, DataFormat::kFloat32, order, regs), EncodeStatus::kOk);
      const double back = decode_registers(regs, DataFormat::kFloat32, order);
      ASSERT_EQ(back, static_cast<double>(static_cast<float>(v))) << v << " " << to_string(order);
      // A value that already is a float survives exactly, whatever the order.
      uint16_t again[2];
      ASSERT_EQ(encode_registers(back, DataFormat::kFloat32, order, again), EncodeStatus::kOk);
      ASSERT_EQ(decode_registers(again, DataFormat::kFloat32, order), back);
    }
  }
}

TEST(ModbusCodec, EncodeRoundsToNearestTiesAwayFromZero) {
  struct Case {
    DataFormat format;
    double in, out;
  };
  const Case cases[] = {
      {DataFormat::kInt16, 2.4999, 2},    {DataFormat::kInt16, 2.5, 3},     {DataFormat::kInt16, -2.5, -3},
      {DataFormat::kInt16, -2.4999, -2},  {DataFormat::kInt16, 0.4, 0},     {DataFormat::kInt16, -0.4, 0},
      {DataFormat::kInt16, 100.7, 101},   {DataFormat::kUint16, 0.5, 1},    {DataFormat::kUint16, -0.4, 0},
      {DataFormat::kUint16, 65534.6, 65535}, {DataFormat::kInt32, -123456.5, -123457},
      {DataFormat::kInt32, 1e6 + 0.49, 1e6}, {DataFormat::kUint32, 4294967294.5, 4294967295.0},
  };
  for (const Case& c : cases) {
    for (const WordOrder order : kAllOrders) {
      uint16_t regs[2] = {0, 0};
      EXPECT_EQ(encode_registers(c.in, c.format, order, regs), EncodeStatus::kOk) << c.in;
      EXPECT_EQ(decode_registers(regs, c.format, order), c.out) << to_string(c.format) << " " << c.in;
    }
  }
}

TEST(ModbusCodec, EncodeSaturatesInsteadOfWrapping) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  struct Case {
    DataFormat format;
    double in, out;
  };
  const Case cases[] = {
      {DataFormat::kInt16, 32767.5, 32767},          {DataFormat::kInt16, 40000, 32767},
      {DataFormat::kInt16, 65535, 32767},            {DataFormat::kInt16, -32768.5, -32768},
      {DataFormat::kInt16, -40000, -32768},          {DataFormat::kInt16, kInf, 32767},
      {DataFormat::kInt16, -kInf, -32768},           {DataFormat::kUint16, -1, 0},
      {DataFormat::kUint16, -0.5, 0},                {DataFormat::kUint16, 65535.5, 65535},
      {DataFormat::kUint16, 70000, 65535},           {DataFormat::kUint16, -kInf, 0},
      {DataFormat::kInt32, 2147483647.5, 2147483647}, {DataFormat::kInt32, 1e10, 2147483647},
      {DataFormat::kInt32, -1e10, -2147483648.0},    {DataFormat::kInt32, kInf, 2147483647},
      {DataFormat::kUint32, -5, 0},                  {DataFormat::kUint32, 5e9, 4294967295.0},
      {DataFormat::kUint32, 1e300, 4294967295.0},    {DataFormat::kUint32, -kInf, 0},
      {DataFormat::kFloat32, 1e40, FLT_MAX},         {DataFormat::kFloat32, -1e40, -FLT_MAX},
      {DataFormat::kFloat32, kInf, FLT_MAX},         {DataFormat::kFloat32, -kInf, -FLT_MAX},
  };
  for (const Case& c : cases) {
    for (const WordOrder order : kAllOrders) {
      uint16_t regs[2] = {0, 0};
      EXPECT_EQ(encode_registers(c.in, c.format, order, regs), EncodeStatus::kSaturated)
          << to_string(c.format) << " " << c.in;
      EXPECT_EQ(decode_registers(regs, c.format, order), c.out) << to_string(c.format) << " " << c.in;
    }
  }
  // The last in-range values are not flagged.
  uint16_t regs[2];
  EXPECT_EQ(encode_registers(32767.4, DataFormat::kInt16, WordOrder::kHighFirst, regs), EncodeStatus::kOk);
  EXPECT_EQ(encode_registers(-32768.4, DataFormat::kInt16, WordOrder::kHighFirst, regs), EncodeStatus::kOk);
  EXPECT_EQ(encode_registers(FLT_MAX, DataFormat::kFloat32, WordOrder::kHighFirst, regs), EncodeStatus::kOk);
}

TEST(ModbusCodec, EncodeRejectsNanAndWritesNothing) {
  const double nans[] = {std::numeric_limits<double>::quiet_NaN(), -std::numeric_limits<double>::quiet_NaN(),
                         std::numeric_limits<double>::signaling_NaN()};
  for (const DataFormat format : kAllFormats) {
    for (const WordOrder order : kAllOrders) {
      for (const double nan : nans) {
        uint16_t regs[2] = {0x1234, 0x5678};
        EXPECT_EQ(encode_registers(nan, format, order, regs), EncodeStatus::kRejected) << to_string(format);
        EXPECT_EQ(regs[0], 0x1234) << to_string(format) << " " << to_string(order);
        EXPECT_EQ(regs[1], 0x5678) << to_string(format) << " " << to_string(order);
      }
    }
  }
}

TEST(ModbusCodec, DecodeAndEncodeDoNotAllocate) {
  uint16_t regs[2] = {0x3FC0, 0};
  double sum = 0.0;
  const long before = rigctl::test::allocation_count();
  for (int i = 0; i < 1000; ++i) {
    for (const DataFormat format : kAllFormats) {
      for (const WordOrder order : kAllOrders) {
        (void)encode_registers(i * 0.75 - 300.0, format, order, regs);
        sum += decode_registers(regs, format, order);
      }
    }
  }
  EXPECT_EQ(rigctl::test::allocation_count() - before, 0);
  EXPECT_TRUE(std::isfinite(sum));
}

TEST(ModbusCodec, ParsesConfigNames) {
  EXPECT_EQ(data_format_from_string("int16"), DataFormat::kInt16);
  EXPECT_EQ(data_format_from_string("uint16"), DataFormat::kUint16);
  EXPECT_EQ(data_format_from_string("int32"), DataFormat::kInt32);
  EXPECT_EQ(data_format_from_string("uint32"), DataFormat::kUint32);
  EXPECT_EQ(data_format_from_string("float32"), DataFormat::kFloat32);
  EXPECT_EQ(word_order_from_string("high_first"), WordOrder::kHighFirst);
  EXPECT_EQ(word_order_from_string("abcd"), WordOrder::kHighFirst);
  EXPECT_EQ(word_order_from_string("low_first"), WordOrder::kLowFirst);
  EXPECT_EQ(word_order_from_string("cdab"), WordOrder::kLowFirst);
  EXPECT_EQ(word_order_from_string("high_first_byte_swapped"), WordOrder::kHighFirstByteSwapped);
  EXPECT_EQ(word_order_from_string("badc"), WordOrder::kHighFirstByteSwapped);
  EXPECT_EQ(word_order_from_string("low_first_byte_swapped"), WordOrder::kLowFirstByteSwapped);
  EXPECT_EQ(word_order_from_string("dcba"), WordOrder::kLowFirstByteSwapped);
  EXPECT_EQ(register_type_from_string("input"), RegisterType::kInputRegister);
  EXPECT_EQ(register_type_from_string("holding"), RegisterType::kHoldingRegister);

  // Canonical names parse back to the same value.
  for (const DataFormat f : kAllFormats) EXPECT_EQ(data_format_from_string(to_string(f)), f);
  for (const WordOrder o : kAllOrders) EXPECT_EQ(word_order_from_string(to_string(o)), o);
  for (const RegisterType t : {RegisterType::kInputRegister, RegisterType::kHoldingRegister}) {
    EXPECT_EQ(register_type_from_string(to_string(t)), t);
  }
  // Every listed name parses.
  EXPECT_EQ(data_format_names().size(), 5u);
  EXPECT_EQ(word_order_names().size(), 8u);
  EXPECT_EQ(register_type_names().size(), 2u);
  for (const auto n : data_format_names()) EXPECT_NO_THROW(data_format_from_string(n)) << n;
  for (const auto n : word_order_names()) EXPECT_NO_THROW(word_order_from_string(n)) << n;
  for (const auto n : register_type_names()) EXPECT_NO_THROW(register_type_from_string(n)) << n;
}

namespace {
template <typename F>
std::string error_of(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "<no exception>";
}
}  // namespace

TEST(ModbusCodec, UnknownNamesThrowListingTheAcceptedOnes) {
  const std::string f = error_of([] { data_format_from_string("float64"); });
  EXPECT_NE(f.find("'float64'"), std::string::npos) << f;
  for (const auto n : data_format_names()) EXPECT_NE(f.find(std::string(n)), std::string::npos) << f;

  const std::string o = error_of([] { word_order_from_string("big"); });
  EXPECT_NE(o.find("'big'"), std::string::npos) << o;
  for (const auto n : word_order_names()) EXPECT_NE(o.find(std::string(n)), std::string::npos) << o;

  const std::string t = error_of([] { register_type_from_string("coil"); });
  EXPECT_NE(t.find("'coil'"), std::string::npos) << t;
  EXPECT_NE(t.find("input"), std::string::npos) << t;
  EXPECT_NE(t.find("holding"), std::string::npos) << t;

  // Exact names only: no case folding, no surrounding blanks, no empty name.
  EXPECT_THROW(data_format_from_string("INT16"), std::invalid_argument);
  EXPECT_THROW(data_format_from_string(" int16"), std::invalid_argument);
  EXPECT_THROW(word_order_from_string("ABCD"), std::invalid_argument);
  EXPECT_THROW(register_type_from_string(""), std::invalid_argument);
}

// ---------------------------------------------------------------------------
// Read plan

namespace {

ModbusPoint pt(int unit, RegisterType type, int address, DataFormat format = DataFormat::kInt16) {
  return ModbusPoint{unit, type, address, format, WordOrder::kHighFirst};
}
constexpr auto kIn = RegisterType::kInputRegister;
constexpr auto kHold = RegisterType::kHoldingRegister;

// Invariants every plan must satisfy, whatever the input.
void check_plan(const std::vector<ModbusPoint>& points, const ReadPlan& plan, const ReadPlanOptions& options) {
  ASSERT_EQ(plan.where.size(), points.size());
  std::vector<bool> used(plan.blocks.size(), false);
  for (std::size_t i = 0; i < points.size(); ++i) {
    const PointLocation& w = plan.where[i];
    ASSERT_GE(w.block, 0);
    ASSERT_LT(w.block, static_cast<int>(plan.blocks.size()));
    const ReadBlock& b = plan.blocks[static_cast<std::size_t>(w.block)];
    used[static_cast<std::size_t>(w.block)] = true;
    EXPECT_EQ(b.unit_id, points[i].unit_id) << "point " << i;
    EXPECT_EQ(b.type, points[i].type) << "point " << i;
    EXPECT_EQ(b.address + w.offset, points[i].address) << "point " << i;
    EXPECT_GE(w.offset, 0) << "point " << i;
    EXPECT_LE(w.offset + register_count(points[i].format), b.count) << "point " << i;
  }
  for (std::size_t k = 0; k < plan.blocks.size(); ++k) {
    EXPECT_TRUE(used[k]) << "block " << k << " serves no point";
    EXPECT_GE(plan.blocks[k].count, 1);
    EXPECT_LE(plan.blocks[k].count, options.max_registers);
    EXPECT_LE(plan.blocks[k].address + plan.blocks[k].count, 65536);
  }
}

}  // namespace

TEST(ModbusReadPlan, EmptyInputGivesEmptyPlan) {
  const ReadPlan plan = plan_reads({});
  EXPECT_TRUE(plan.blocks.empty());
  EXPECT_TRUE(plan.where.empty());
}

TEST(ModbusReadPlan, ContiguousPointsShareOneBlock) {
  // The quarter-car rig's inputs on one module: 3 LVDTs, 2 velocities, 2
  // pressures (float32), load cell (int32), in scrambled config order.
  const std::vector<ModbusPoint> points = {
      pt(1, kIn, 5),  pt(1, kIn, 3), pt(1, kIn, 4), pt(1, kIn, 6, DataFormat::kFloat32),
      pt(1, kIn, 0),  pt(1, kIn, 1), pt(1, kIn, 2), pt(1, kIn, 8, DataFormat::kInt32)};
  const ReadPlan plan = plan_reads(points, ReadPlanOptions{.max_gap = 0});
  check_plan(points, plan, ReadPlanOptions{.max_gap = 0});
  ASSERT_EQ(plan.blocks.size(), 1u);
  EXPECT_EQ(plan.blocks[0].unit_id, 1);
  EXPECT_EQ(plan.blocks[0].type, kIn);
  EXPECT_EQ(plan.blocks[0].address, 0);
  EXPECT_EQ(plan.blocks[0].count, 10);
  const int offsets[] = {5, 3, 4, 6, 0, 1, 2, 8};
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(plan.where[i].block, 0);
    EXPECT_EQ(plan.where[i].offset, offsets[i]) << "point " << i;
  }
}

TEST(ModbusReadPlan, SmallGapsAreBridgedLargeOnesSplit) {
  // Gaps (unused registers): 2 between 1 and 4, 3 between 5 and 9.
  const std::vector<ModbusPoint> points = {pt(1, kIn, 0), pt(1, kIn, 1), pt(1, kIn, 4), pt(1, kIn, 5),
                                           pt(1, kIn, 9)};
  {
    const ReadPlanOptions o{.max_gap = 0};
    const ReadPlan plan = plan_reads(points, o);
    check_plan(points, plan, o);
    ASSERT_EQ(plan.blocks.size(), 3u);
    EXPECT_EQ(plan.blocks[0].address, 0);
    EXPECT_EQ(plan.blocks[0].count, 2);
    EXPECT_EQ(plan.blocks[1].address, 4);
    EXPECT_EQ(plan.blocks[1].count, 2);
    EXPECT_EQ(plan.blocks[2].address, 9);
    EXPECT_EQ(plan.blocks[2].count, 1);
  }
  {
    const ReadPlanOptions o{.max_gap = 2};
    const ReadPlan plan = plan_reads(points, o);
    check_plan(points, plan, o);
    ASSERT_EQ(plan.blocks.size(), 2u);
    EXPECT_EQ(plan.blocks[0].address, 0);
    EXPECT_EQ(plan.blocks[0].count, 6);
    EXPECT_EQ(plan.where[3].offset, 5);
    EXPECT_EQ(plan.blocks[1].address, 9);
  }
  {
    const ReadPlanOptions o{.max_gap = 3};
    const ReadPlan plan = plan_reads(points, o);
    check_plan(points, plan, o);
    ASSERT_EQ(plan.blocks.size(), 1u);
    EXPECT_EQ(plan.blocks[0].count, 10);
    EXPECT_EQ(plan.where[4].offset, 9);
  }
}

TEST(ModbusReadPlan, SplitsByUnitIdAndRegisterType) {
  const std::vector<ModbusPoint> points = {pt(2, kIn, 0), pt(1, kHold, 1), pt(1, kIn, 0), pt(1, kHold, 0),
                                           pt(1, kIn, 1), pt(2, kIn, 1)};
  const ReadPlanOptions o{.max_gap = 10};
  const ReadPlan plan = plan_reads(points, o);
  check_plan(points, plan, o);
  ASSERT_EQ(plan.blocks.size(), 3u);
  // Sorted by unit, then input before holding.
  EXPECT_EQ(plan.blocks[0].unit_id, 1);
  EXPECT_EQ(plan.blocks[0].type, kIn);
  EXPECT_EQ(plan.blocks[1].unit_id, 1);
  EXPECT_EQ(plan.blocks[1].type, kHold);
  EXPECT_EQ(plan.blocks[2].unit_id, 2);
  EXPECT_EQ(plan.blocks[2].type, kIn);
  for (const ReadBlock& b : plan.blocks) {
    EXPECT_EQ(b.address, 0);
    EXPECT_EQ(b.count, 2);
  }
  EXPECT_EQ(plan.where[0].block, 2);
  EXPECT_EQ(plan.where[1].block, 1);
  EXPECT_EQ(plan.where[1].offset, 1);
  EXPECT_EQ(plan.where[2].block, 0);
}

TEST(ModbusReadPlan, RespectsThe125RegisterLimit) {
  std::vector<ModbusPoint> points;
  for (int a = 0; a < 126; ++a) points.push_back(pt(1, kIn, a));
  const ReadPlan plan = plan_reads(points);
  check_plan(points, plan, {});
  ASSERT_EQ(plan.blocks.size(), 2u);
  EXPECT_EQ(plan.blocks[0].address, 0);
  EXPECT_EQ(plan.blocks[0].count, 125);
  EXPECT_EQ(plan.blocks[1].address, 125);
  EXPECT_EQ(plan.blocks[1].count, 1);
  EXPECT_EQ(plan.where[125].block, 1);
  EXPECT_EQ(plan.where[125].offset, 0);

  // 64 float32 channels are 128 registers: a 32-bit point is never split, so
  // the first block stops at 124 registers (62 floats).
  points.clear();
  for (int k = 0; k < 64; ++k) points.push_back(pt(1, kIn, 2 * k, DataFormat::kFloat32));
  const ReadPlan floats = plan_reads(points);
  check_plan(points, floats, {});
  ASSERT_EQ(floats.blocks.size(), 2u);
  EXPECT_EQ(floats.blocks[0].count, 124);
  EXPECT_EQ(floats.blocks[1].address, 124);
  EXPECT_EQ(floats.blocks[1].count, 4);

  // A smaller configured limit.
  const ReadPlanOptions small{.max_gap = 0, .max_registers = 4};
  points.clear();
  for (int a = 0; a < 10; ++a) points.push_back(pt(1, kIn, a));
  const ReadPlan plan4 = plan_reads(points, small);
  check_plan(points, plan4, small);
  ASSERT_EQ(plan4.blocks.size(), 3u);
  EXPECT_EQ(plan4.blocks[2].address, 8);
  EXPECT_EQ(plan4.blocks[2].count, 2);
}

TEST(ModbusReadPlan, OverlappingPointsShareRegisters) {
  // One register read as int16 and uint16, and a float32 whose low word is
  // also read on its own.
  const std::vector<ModbusPoint> points = {pt(1, kIn, 10), pt(1, kIn, 10, DataFormat::kUint16),
                                           pt(1, kIn, 11, DataFormat::kFloat32), pt(1, kIn, 12)};
  const ReadPlanOptions o{.max_gap = 0};
  const ReadPlan plan = plan_reads(points, o);
  check_plan(points, plan, o);
  ASSERT_EQ(plan.blocks.size(), 1u);
  EXPECT_EQ(plan.blocks[0].address, 10);
  EXPECT_EQ(plan.blocks[0].count, 3);
}

TEST(ModbusReadPlan, RandomPointSetsSatisfyTheInvariants) {
  std::mt19937_64 rng(2024);
  for (int trial = 0; trial < 300; ++trial) {
    std::vector<ModbusPoint> points;
    const int n = 1 + static_cast<int>(rng() % 60);
    for (int i = 0; i < n; ++i) {
      points.push_back(ModbusPoint{1 + static_cast<int>(rng() % 3), (rng() % 2) ? kIn : kHold,
                                   static_cast<int>(rng() % 400), kAllFormats[rng() % kAllFormats.size()],
                                   WordOrder::kHighFirst});
    }
    const ReadPlanOptions o{.max_gap = static_cast<int>(rng() % 6),
                            .max_registers = 2 + static_cast<int>(rng() % 124)};
    const ReadPlan plan = plan_reads(points, o);
    check_plan(points, plan, o);
    // Same (unit, type) neighbours in the block list are split for a reason:
    // the gap is too large or the merge would exceed the limit.
    for (std::size_t k = 1; k < plan.blocks.size(); ++k) {
      const ReadBlock& a = plan.blocks[k - 1];
      const ReadBlock& b = plan.blocks[k];
      if (a.unit_id != b.unit_id || a.type != b.type) continue;
      EXPECT_GT(b.address, a.address + a.count - 1) << "blocks overlap";
      const bool gap_too_large = b.address - (a.address + a.count) > o.max_gap;
      const bool too_long = b.address + b.count - a.address > o.max_registers;
      EXPECT_TRUE(gap_too_large || too_long) << "trial " << trial << " block " << k;
    }
  }
}

TEST(ModbusReadPlan, RejectsBadPointsNamingTheIndex) {
  const std::string unit = error_of([] {
    plan_reads(std::vector<ModbusPoint>{pt(1, kIn, 0), pt(256, kIn, 1)});
  });
  EXPECT_NE(unit.find("point 1"), std::string::npos) << unit;
  EXPECT_NE(unit.find("unit id"), std::string::npos) << unit;

  const std::string negative = error_of([] { plan_reads(std::vector<ModbusPoint>{pt(1, kIn, -1)}); });
  EXPECT_NE(negative.find("point 0"), std::string::npos) << negative;

  // A 32-bit point at the last address would need register 65536.
  const std::string last = error_of([] {
    plan_reads(std::vector<ModbusPoint>{pt(1, kIn, 0), pt(1, kIn, 1), pt(1, kIn, 65535, DataFormat::kFloat32)});
  });
  EXPECT_NE(last.find("point 2"), std::string::npos) << last;
  EXPECT_NO_THROW(plan_reads(std::vector<ModbusPoint>{pt(1, kIn, 65535), pt(0, kIn, 65534, DataFormat::kInt32)}));
  EXPECT_NO_THROW(plan_reads(std::vector<ModbusPoint>{pt(255, kHold, 0)}));
}

TEST(ModbusReadPlan, RejectsBadOptions) {
  const std::vector<ModbusPoint> points = {pt(1, kIn, 0)};
  EXPECT_THROW(plan_reads(points, ReadPlanOptions{.max_gap = -1}), std::invalid_argument);
  EXPECT_THROW(plan_reads(points, ReadPlanOptions{.max_gap = 0, .max_registers = 126}), std::invalid_argument);
  EXPECT_THROW(plan_reads(points, ReadPlanOptions{.max_gap = 0, .max_registers = 1}), std::invalid_argument);
  EXPECT_NO_THROW(plan_reads(points, ReadPlanOptions{.max_gap = 0, .max_registers = 2}));
  EXPECT_NO_THROW(plan_reads(points, ReadPlanOptions{.max_gap = 0, .max_registers = 125}));
}
