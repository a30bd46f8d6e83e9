// One realisation of an ISO 8608 random road track, generated once and read
// by interpolation at every integration stage.
//
// Why a table: the road used to be a sum of 200 cosines evaluated at every
// RK4 stage of both wheels (80 evaluations of 200 cosines per 2.5 ms
// period), which made the half car on a random road 100 times slower than
// on a bump. Here the road is laid out on a uniform grid by one inverse FFT
// of its spectrum, and a query costs one cubic Hermite interpolation.
//
// Spectrum: displacement PSD Gd(n) = Gd(n0) (n/n0)^-2 (n0 = 0.1 cycle/m)
// on the FFT's bins n_k = k / L inside [n_min, n_max], each bin a cosine of
// amplitude sqrt(2 Gd(n_k) / L) (the bin's variance Gd(n_k) dn, dn = 1/L)
// and a uniform random phase from a 64-bit Mersenne twister seeded by the
// road's seed (same seed, same road, on every platform). The track repeats
// after L, which is chosen at least `min_length` (default 5 km: over four
// minutes at 20 m/s, and 55 periods of the longest standard wave, 91 m).
//
// The grid step is 1/(8 n_max) (0.044 m for the standard band): eight
// points per shortest wave, where cubic Hermite interpolation with the exact
// slopes (from the same FFT: the spectrum times i 2 pi n) errs by less than
// 0.1 % of that wave's amplitude ((2 pi / 8)^4 / 384).
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

namespace rigctl {

struct IsoRoadTableSpec {
  double gd_n0 = 256e-6;  // [m^3] Gd(n0)
  double n_min = 0.011;   // [cycle/m]
  double n_max = 2.83;    // [cycle/m]
  uint64_t seed = 1;
  int tracks = 2;               // independent tracks (left and right)
  double min_length = 5000.0;   // [m] the track repeats after at least this
};

class IsoRoadTable {
 public:
  // Throws std::invalid_argument on a bad spec (names the field).
  explicit IsoRoadTable(const IsoRoadTableSpec& spec);

  struct Point {
    double z;      // [m]
    double slope;  // dz/dx [-]
  };
  // Height and slope of `track` at distance x [m] (any x: the track repeats).
  Point at(int track, double x) const noexcept;

  double length() const noexcept { return step_ * static_cast<double>(points_); }  // [m]
  double step() const noexcept { return step_; }                                  // [m]
  // Variance the realisation carries: the sum of its bins' variances [m^2].
  double variance() const noexcept { return variance_; }

 private:
  struct Knot {
    float z;          // [m]
    float slope_step; // slope * step [m]: what the Hermite basis multiplies
  };
  void generate(const IsoRoadTableSpec& spec);

  double step_ = 0.0;
  std::size_t points_ = 0;  // per track, a power of two
  double variance_ = 0.0;
  std::vector<std::vector<Knot>> tracks_;
};

}  // namespace rigctl
