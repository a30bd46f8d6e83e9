// The ISO 8608 road table: the interpolated height is smooth (its slope is
// the height's derivative, with no jumps at the grid's knots), the track
// repeats after its length, the variance is the class's, and a bad spec is
// refused naming what is wrong. The class PSD itself is checked through
// RoadProfile in test_half_car_model.cpp (HalfCarRoad.*).
#include "plant/half_car/iso_road_table.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace rigctl {
namespace {

IsoRoadTableSpec class_c() {
  IsoRoadTableSpec s;
  s.gd_n0 = 256e-6;
  s.seed = 11;
  return s;
}

TEST(IsoRoadTable, GridHoldsEightPointsPerShortestWaveAndAtLeastTheLength) {
  const IsoRoadTable road(class_c());
  EXPECT_NEAR(road.step(), 1.0 / (8.0 * 2.83), 1e-12);
  EXPECT_GE(road.length(), 5000.0);
  EXPECT_LT(road.length(), 2 * 5000.0);  // the next power of two of points, no more
}

TEST(IsoRoadTable, SlopeIsTheDerivativeOfTheHeight) {
  const IsoRoadTable road(class_c());
  const double h = 1e-5;  // [m] central difference; its own error is far below the slopes (1e-2)
  double worst = 0.0, biggest = 0.0;
  for (double x = 0.0; x < 200.0; x += 0.0137) {
    const double numeric = (road.at(0, x + h).z - road.at(0, x - h).z) / (2 * h);
    worst = std::max(worst, std::abs(numeric - road.at(0, x).slope));
    biggest = std::max(biggest, std::abs(road.at(0, x).slope));
  }
  EXPECT_GT(biggest, 1e-3);  // the road has slopes to compare
  EXPECT_LT(worst, 1e-4 * biggest);
}

TEST(IsoRoadTable, HeightAndSlopeAreContinuousAcrossKnots) {
  const IsoRoadTable road(class_c());
  const double eps = 1e-9;
  for (int k = 1; k < 2000; k += 7) {
    const double x = k * road.step();
    const auto below = road.at(1, x - eps), above = road.at(1, x + eps);
    EXPECT_NEAR(below.z, above.z, 1e-9) << "knot " << k;
    EXPECT_NEAR(below.slope, above.slope, 1e-6) << "knot " << k;
  }
}

TEST(IsoRoadTable, TrackRepeatsAfterItsLengthAndTracksDiffer) {
  const IsoRoadTable road(class_c());
  for (double x = 0.3; x < 50.0; x += 1.7) {
    EXPECT_NEAR(road.at(0, x).z, road.at(0, x + road.length()).z, 1e-9);
    EXPECT_NEAR(road.at(0, x).z, road.at(0, x - road.length()).z, 1e-9);
  }
  double difference = 0.0;
  for (double x = 0.0; x < 100.0; x += 0.5) difference += std::abs(road.at(0, x).z - road.at(1, x).z);
  EXPECT_GT(difference, 0.1);
}

TEST(IsoRoadTable, VarianceIsTheClassBandsAndTheSampleAgrees) {
  const IsoRoadTable road(class_c());
  const double band = 256e-6 * 0.01 * (1.0 / 0.011 - 1.0 / 2.83);  // Gd(n0) n0^2 (1/n_min - 1/n_max)
  EXPECT_NEAR(road.variance(), band, 0.02 * band);  // the bins' sum against the integral
  double sum = 0.0, sq = 0.0;
  int n = 0;
  for (double x = 0.0; x < road.length(); x += road.step()) {
    const double z = road.at(0, x).z;
    sum += z;
    sq += z * z;
    ++n;
  }
  const double var = sq / n - (sum / n) * (sum / n);
  EXPECT_NEAR(var, road.variance(), 1e-3 * road.variance());  // one whole period: Parseval
}

std::string error_of(const IsoRoadTableSpec& s) {
  try {
    const IsoRoadTable road(s);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(IsoRoadTable, BadSpecsAreRefusedSayingWhy) {
  IsoRoadTableSpec s = class_c();
  s.n_max = s.n_min;
  EXPECT_NE(error_of(s).find("n_min < n_max"), std::string::npos);
  s = class_c();
  s.min_length = 50.0;  // shorter than the longest wave, 1 / 0.011 = 91 m
  EXPECT_NE(error_of(s).find("longest wave"), std::string::npos);
  s = class_c();
  s.gd_n0 = -1.0;
  EXPECT_NE(error_of(s).find("Gd(n0)"), std::string::npos);
  EXPECT_EQ(error_of(class_c()), "");
}

}  // namespace
}  // namespace rigctl
