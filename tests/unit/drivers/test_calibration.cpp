// Raw-to-SI calibration of the Modbus DAQ channels: linear and table, both
// ways, and the checks made at construction.
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "drivers/modbus/calibration.hpp"
#include "allocation_counter.hpp"

using namespace rigctl;


namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

template <typename F>
std::string error_of(F f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "<no exception>";
}

// A nonlinear transducer with rising SI: si = raw^2 / 100 sampled at 0, 10, 20, 30.
TableCalibration rising() {
  const std::vector<CalibrationPoint> points = {{0, 0}, {10, 1}, {20, 4}, {30, 9}};
  return TableCalibration(points);
}

// Falling SI (e.g. a sensor wired so counts fall as the rod extends).
TableCalibration falling() {
  const std::vector<double> raw = {-100, 0, 50, 200};
  const std::vector<double> si = {0.2, 0.1, 0.0, -0.3};
  return TableCalibration(raw, si);
}

}  // namespace

TEST(LinearCalibration, ConvertsBothWays) {
  // 16-bit ADC counts of a +-10 V input onto a 0.2 m LVDT span: 32768 counts = 0.1 m.
  const LinearCalibration c(0.1 / 32768.0, 0.05);
  EXPECT_DOUBLE_EQ(c.to_si(0.0), 0.05);
  EXPECT_DOUBLE_EQ(c.to_si(32768.0), 0.15);
  EXPECT_DOUBLE_EQ(c.to_si(-32768.0), -0.05);
  EXPECT_DOUBLE_EQ(c.to_raw(0.15), 32768.0);
  EXPECT_DOUBLE_EQ(c.to_raw(0.05), 0.0);
  EXPECT_DOUBLE_EQ(c.to_raw(-0.05), -32768.0);
  for (double raw = -40000; raw <= 40000; raw += 777.7) {
    EXPECT_NEAR(c.to_raw(c.to_si(raw)), raw, 1e-9) << raw;
  }
}

TEST(LinearCalibration, NegativeGainAndIdentity) {
  const LinearCalibration c(-2.0, 3.0);
  EXPECT_DOUBLE_EQ(c.to_si(1.0), 1.0);
  EXPECT_DOUBLE_EQ(c.to_si(-1.0), 5.0);
  EXPECT_DOUBLE_EQ(c.to_raw(5.0), -1.0);
  EXPECT_DOUBLE_EQ(c.to_raw(3.0), 0.0);

  const LinearCalibration id;
  EXPECT_EQ(id.gain(), 1.0);
  EXPECT_EQ(id.offset(), 0.0);
  EXPECT_EQ(id.to_si(12.5), 12.5);
  EXPECT_EQ(id.to_raw(-7.25), -7.25);
}

TEST(LinearCalibration, FromTwoPoints) {
  // A 0..10 V channel, counts 0..32000, onto 0..200 bar.
  const LinearCalibration c = LinearCalibration::from_points(0.0, 0.0, 32000.0, 200e5);
  EXPECT_DOUBLE_EQ(c.gain(), 625.0);
  EXPECT_DOUBLE_EQ(c.offset(), 0.0);
  // A 4..20 mA current loop read as 6400..32000 counts onto -0.1..0.1 m.
  const LinearCalibration loop = LinearCalibration::from_points(6400.0, -0.1, 32000.0, 0.1);
  EXPECT_NEAR(loop.to_si(6400.0), -0.1, 1e-15);
  EXPECT_NEAR(loop.to_si(32000.0), 0.1, 1e-15);
  EXPECT_NEAR(loop.to_si(19200.0), 0.0, 1e-15);
  EXPECT_NEAR(loop.to_raw(0.0), 19200.0, 1e-9);
}

TEST(LinearCalibration, RejectsZeroOrNonFiniteGain) {
  const std::string zero = error_of([] { LinearCalibration(0.0, 1.0); });
  EXPECT_NE(zero.find("gain"), std::string::npos) << zero;
  EXPECT_THROW(LinearCalibration(-0.0, 0.0), std::invalid_argument);
  EXPECT_THROW(LinearCalibration(kNan, 0.0), std::invalid_argument);
  EXPECT_THROW(LinearCalibration(std::numeric_limits<double>::infinity(), 0.0), std::invalid_argument);
  EXPECT_THROW(LinearCalibration(1.0, kNan), std::invalid_argument);
  EXPECT_THROW(LinearCalibration(1.0, -std::numeric_limits<double>::infinity()), std::invalid_argument);
  EXPECT_THROW(LinearCalibration::from_points(5.0, 0.0, 5.0, 1.0), std::invalid_argument);
  EXPECT_THROW(LinearCalibration::from_points(0.0, 1.0, 5.0, 1.0), std::invalid_argument);
  EXPECT_THROW(LinearCalibration::from_points(0.0, kNan, 5.0, 1.0), std::invalid_argument);
  EXPECT_NO_THROW(LinearCalibration(1e-12, -5.0));
}

TEST(TableCalibration, InterpolatesAndHitsBreakpointsExactly) {
  const TableCalibration t = rising();
  EXPECT_EQ(t.size(), 4u);
  EXPECT_TRUE(t.si_increasing());
  EXPECT_EQ(t.to_si(0.0), 0.0);
  EXPECT_EQ(t.to_si(10.0), 1.0);
  EXPECT_EQ(t.to_si(20.0), 4.0);
  EXPECT_EQ(t.to_si(30.0), 9.0);
  EXPECT_DOUBLE_EQ(t.to_si(5.0), 0.5);
  EXPECT_DOUBLE_EQ(t.to_si(15.0), 2.5);
  EXPECT_DOUBLE_EQ(t.to_si(27.5), 7.75);
  EXPECT_EQ(t.to_raw(0.0), 0.0);
  EXPECT_EQ(t.to_raw(1.0), 10.0);
  EXPECT_EQ(t.to_raw(4.0), 20.0);
  EXPECT_EQ(t.to_raw(9.0), 30.0);
  EXPECT_DOUBLE_EQ(t.to_raw(0.5), 5.0);
  EXPECT_DOUBLE_EQ(t.to_raw(2.5), 15.0);
  EXPECT_DOUBLE_EQ(t.to_raw(7.75), 27.5);
}

TEST(TableCalibration, EveryBreakpointMapsExactlyOntoItsPartner) {
  // Values chosen so that the naive a + (b - a) * 1 misses b by one ulp on the
  // last segment, in both columns: the table's ends must still be exact.
  const std::vector<double> raw = {0.0, 2.94, 7.69};
  for (const std::vector<double>& si : {std::vector<double>{-0.9, -0.372, 0.917},
                                        std::vector<double>{1.0, 0.917, -0.372}}) {
    const TableCalibration t(raw, si);
    for (std::size_t i = 0; i < raw.size(); ++i) {
      EXPECT_EQ(t.to_si(raw[i]), si[i]) << "point " << i;
      EXPECT_EQ(t.to_raw(si[i]), raw[i]) << "point " << i;
    }
  }
}

TEST(TableCalibration, ExtrapolatesTheEndSegmentsLinearly) {
  const TableCalibration t = rising();
  // Below: first segment's slope 0.1 per count. Above: last segment's slope 0.5.
  EXPECT_DOUBLE_EQ(t.to_si(-10.0), -1.0);
  EXPECT_DOUBLE_EQ(t.to_si(-100.0), -10.0);
  EXPECT_DOUBLE_EQ(t.to_si(40.0), 14.0);
  EXPECT_DOUBLE_EQ(t.to_si(50.0), 19.0);
  EXPECT_DOUBLE_EQ(t.to_raw(-1.0), -10.0);
  EXPECT_DOUBLE_EQ(t.to_raw(14.0), 40.0);
  EXPECT_DOUBLE_EQ(t.to_raw(19.0), 50.0);
  // Not clamped: motion beyond the table still shows.
  EXPECT_GT(t.to_si(31.0), t.to_si(30.0));
  EXPECT_LT(t.to_si(-1.0), t.to_si(0.0));
  EXPECT_TRUE(t.in_table(0.0));
  EXPECT_TRUE(t.in_table(30.0));
  EXPECT_FALSE(t.in_table(30.001));
  EXPECT_FALSE(t.in_table(-0.001));
  EXPECT_FALSE(t.in_table(kNan));
  EXPECT_EQ(t.raw_min(), 0.0);
  EXPECT_EQ(t.raw_max(), 30.0);
}

TEST(TableCalibration, DecreasingSiColumnBothWays) {
  const TableCalibration t = falling();
  EXPECT_FALSE(t.si_increasing());
  EXPECT_DOUBLE_EQ(t.to_si(-100.0), 0.2);
  EXPECT_DOUBLE_EQ(t.to_si(-50.0), 0.15);
  EXPECT_DOUBLE_EQ(t.to_si(25.0), 0.05);
  EXPECT_DOUBLE_EQ(t.to_si(125.0), -0.15);
  EXPECT_DOUBLE_EQ(t.to_si(-200.0), 0.3);    // extrapolated, slope -0.001
  EXPECT_DOUBLE_EQ(t.to_si(300.0), -0.5);    // extrapolated, slope -0.002
  EXPECT_DOUBLE_EQ(t.to_raw(0.15), -50.0);
  EXPECT_DOUBLE_EQ(t.to_raw(0.05), 25.0);
  EXPECT_DOUBLE_EQ(t.to_raw(-0.15), 125.0);
  EXPECT_DOUBLE_EQ(t.to_raw(0.3), -200.0);
  EXPECT_DOUBLE_EQ(t.to_raw(-0.5), 300.0);
  EXPECT_EQ(t.to_raw(0.1), 0.0);
  EXPECT_EQ(t.to_raw(-0.3), 200.0);
}

TEST(TableCalibration, RoundTripsEverywhere) {
  for (const TableCalibration& t : {rising(), falling()}) {
    for (double raw = -300.0; raw <= 300.0; raw += 0.37) {
      EXPECT_NEAR(t.to_raw(t.to_si(raw)), raw, 1e-9) << raw;
    }
  }
}

TEST(TableCalibration, NanStaysNan) {
  EXPECT_TRUE(std::isnan(rising().to_si(kNan)));
  EXPECT_TRUE(std::isnan(rising().to_raw(kNan)));
  EXPECT_TRUE(std::isnan(falling().to_si(kNan)));
  EXPECT_TRUE(std::isnan(falling().to_raw(kNan)));
  EXPECT_TRUE(std::isnan(LinearCalibration(2.0, 1.0).to_si(kNan)));
  EXPECT_TRUE(std::isnan(LinearCalibration(2.0, 1.0).to_raw(kNan)));
}

TEST(TableCalibration, TwoPointTableIsALine) {
  const std::vector<CalibrationPoint> points = {{0, 1}, {4, 9}};
  const TableCalibration t(points);
  const LinearCalibration l(2.0, 1.0);
  for (double raw = -20; raw <= 20; raw += 0.5) {
    EXPECT_DOUBLE_EQ(t.to_si(raw), l.to_si(raw)) << raw;
    EXPECT_DOUBLE_EQ(t.to_raw(l.to_si(raw)), raw) << raw;
  }
}

TEST(TableCalibration, RejectsRawColumnNotStrictlyIncreasing) {
  const std::string equal = error_of([] {
    const std::vector<CalibrationPoint> p = {{0, 0}, {1, 1}, {1, 2}, {3, 3}};
    TableCalibration t(p);
  });
  EXPECT_NE(equal.find("point 2"), std::string::npos) << equal;
  EXPECT_NE(equal.find("raw"), std::string::npos) << equal;

  const std::string decreasing = error_of([] {
    const std::vector<CalibrationPoint> p = {{0, 0}, {1, 1}, {2, 2}, {3, 3}, {2.5, 4}};
    TableCalibration t(p);
  });
  EXPECT_NE(decreasing.find("point 4"), std::string::npos) << decreasing;
}

TEST(TableCalibration, RejectsNonMonotonicSiNamingThePoint) {
  const std::string reverse = error_of([] {
    const std::vector<CalibrationPoint> p = {{0, 0}, {1, 1}, {2, 2}, {3, 1.5}, {4, 5}};
    TableCalibration t(p);
  });
  EXPECT_NE(reverse.find("point 3"), std::string::npos) << reverse;
  EXPECT_NE(reverse.find("SI"), std::string::npos) << reverse;

  const std::string flat = error_of([] {
    const std::vector<CalibrationPoint> p = {{0, 5}, {1, 4}, {2, 4}};
    TableCalibration t(p);
  });
  EXPECT_NE(flat.find("point 2"), std::string::npos) << flat;

  const std::string flat_start = error_of([] {
    const std::vector<CalibrationPoint> p = {{0, 5}, {1, 5}, {2, 6}};
    TableCalibration t(p);
  });
  EXPECT_NE(flat_start.find("point 1"), std::string::npos) << flat_start;

  const std::string falling_then_rising = error_of([] {
    const std::vector<double> raw = {0, 1, 2, 3};
    const std::vector<double> si = {3, 2, 1, 1.5};
    TableCalibration t(raw, si);
  });
  EXPECT_NE(falling_then_rising.find("point 3"), std::string::npos) << falling_then_rising;
}

TEST(TableCalibration, RejectsShortMismatchedOrNonFiniteTables) {
  EXPECT_THROW(TableCalibration(std::vector<CalibrationPoint>{}), std::invalid_argument);
  EXPECT_THROW(TableCalibration(std::vector<CalibrationPoint>{{0, 0}}), std::invalid_argument);
  const std::vector<double> raw3 = {0, 1, 2};
  const std::vector<double> si2 = {0, 1};
  EXPECT_THROW(TableCalibration(raw3, si2), std::invalid_argument);
  const std::string nan = error_of([] {
    const std::vector<CalibrationPoint> p = {{0, 0}, {1, kNan}, {2, 2}};
    TableCalibration t(p);
  });
  EXPECT_NE(nan.find("point 1"), std::string::npos) << nan;
  EXPECT_THROW(TableCalibration(std::vector<CalibrationPoint>{{0, 0}, {std::numeric_limits<double>::infinity(), 1}}),
               std::invalid_argument);
}

TEST(Calibration, DispatchesToTheKindHeld) {
  const Calibration identity;
  ASSERT_NE(identity.linear(), nullptr);
  EXPECT_EQ(identity.table(), nullptr);
  EXPECT_EQ(identity.to_si(3.5), 3.5);
  EXPECT_EQ(identity.to_raw(-3.5), -3.5);

  const Calibration linear = LinearCalibration(0.5, -1.0);
  ASSERT_NE(linear.linear(), nullptr);
  EXPECT_EQ(linear.table(), nullptr);
  EXPECT_DOUBLE_EQ(linear.to_si(4.0), 1.0);
  EXPECT_DOUBLE_EQ(linear.to_raw(1.0), 4.0);

  const Calibration table = rising();
  ASSERT_NE(table.table(), nullptr);
  EXPECT_EQ(table.linear(), nullptr);
  EXPECT_DOUBLE_EQ(table.to_si(15.0), 2.5);
  EXPECT_DOUBLE_EQ(table.to_raw(14.0), 40.0);

  // A value type: copies are independent and equal in behaviour.
  std::vector<Calibration> channels = {identity, linear, table};
  channels[0] = table;
  EXPECT_DOUBLE_EQ(channels[0].to_si(15.0), 2.5);
  EXPECT_DOUBLE_EQ(channels[2].to_si(15.0), 2.5);
  EXPECT_DOUBLE_EQ(channels[1].to_si(4.0), 1.0);
}

TEST(Calibration, ConversionsDoNotAllocate) {
  const std::vector<Calibration> channels = {Calibration(), LinearCalibration(0.25, 3.0), rising(), falling()};
  double sum = 0.0;
  const long before = rigctl::test::allocation_count();
  for (int i = 0; i < 10000; ++i) {
    const double x = i * 0.07 - 350.0;
    for (const Calibration& c : channels) sum += c.to_raw(c.to_si(x));
  }
  EXPECT_EQ(rigctl::test::allocation_count() - before, 0);
  EXPECT_TRUE(std::isfinite(sum));
}
