// Road inputs under the two wheels of the half car (seed 001): the bump of
// eqs. 9-10, the one-wheel input, and a random road of an ISO 8608 class.
//
// Bump (eqs. 9-10), per wheel, with tau the time since that wheel reached
// the bump (the front wheel at start_time, the rear wheel t_d = (a+b)/V
// later in the pitch plane, eq. 11):
//   z_r(tau) = a0/2 (1 - cos(2 pi V tau / lambda0))   for 0 <= tau <= cycles lambda0 / V
//            = 0                                        otherwise
// The paper's eq. 9 gives the interval 0 <= t <= 2 lambda0 / V, which holds
// two full periods of the cosine (two consecutive humps of height a0 and
// length lambda0 each); `cycles` defaults to 2 for that literal reading, 1
// gives the single hump most papers of this family use. With the paper's
// a0 = 0.05 m, lambda0 = 0.20 m, V = 20 m/s one hump lasts 10 ms (a 100 Hz
// event: an impulse to the wheel, not a slow ramp).
//
// ISO 8608 random road: displacement PSD Gd(n) = Gd(n0) (n/n0)^-2 with
// n0 = 0.1 cycle/m, over the standard's band 0.011 <= n <= 2.83 cycle/m,
// generated once per track by an inverse FFT on a uniform grid and read by
// cubic Hermite interpolation (iso_road_table.hpp says why and how); the
// track repeats after `length` (at least 5 km by default). Gd(n0) is the
// class's geometric mean of ISO 8608:1995 Table 1
// (1e-6 m^3): A 16, B 64, C 256, D 1024, E 4096 (class limits 32, 128, 512,
// 2048, 8192). The road fades in over `fade_in_distance` (half-cosine
// window) so that a run starting at rest sees no step.
//
// Bump train: equal 1 - cos humps (BumpTrainSpec) added to any kind.
//
// Wheel arrangement: in line (pitch plane) both wheels run on one track and
// wheel 2 (rear) sees it wheelbase/V later; side by side (roll plane) both
// wheels reach a bump at the same time, and the ISO road has two
// independent tracks (left/right coherence is not modelled).
#pragma once

#include <array>
#include <cstdint>
#include <memory>

#include "plant/half_car/iso_road_table.hpp"

namespace rigctl {

enum class RoadKind {
  kFlat,     // z_r = 0
  kBump,     // eqs. 9-10
  kIso8608,  // random road of one ISO 8608 class
};

// Which wheels see the road: both, or only one (the "one-wheel input" of the
// paper, e.g. only the front axle or only the left side hits the bump).
enum class RoadWheels { kBoth, kWheel1, kWheel2 };

enum class IsoRoadClass { kA, kB, kC, kD, kE };

// Gd(n0) of the class, ISO 8608:1995 Table 1 geometric mean [m^3].
double iso8608_gd_n0(IsoRoadClass c);

struct BumpSpec {
  double amplitude = 0.05;   // a0 [m], paper
  double wavelength = 0.20;  // lambda0 [m], paper
  double start_time = 0.5;   // [s] wheel 1 reaches the bump (chosen: 0.5 s of rest first)
  double cycles = 2.0;       // humps: eq. 9's interval 0 <= t <= 2 lambda0 / V holds two
};

// A series of equal 1 - cos humps laid on top of any road kind (speed bumps,
// or potholes with a negative amplitude): hump k starts at
// start_time + k interval under wheel 1 (wheel 2 follows as for the other
// kinds) and lasts wavelength / V. Used where a road must make the tyres
// leave the ground at known, repeated instants (the diagnosis runs).
struct BumpTrainSpec {
  double amplitude = 0.0;   // [m] hump height (negative: a dip); 0 = no train
  double wavelength = 1.0;  // [m] hump length
  double start_time = 1.0;  // [s] wheel 1 reaches the first hump
  double interval = 1.0;    // [s] from one hump to the next; at least one hump's duration
  int count = 0;            // humps
};

struct IsoRoadSpec {
  IsoRoadClass road_class = IsoRoadClass::kC;
  double gd_n0 = 0.0;       // [m^3] Gd(n0); 0 = the class's geometric mean
  uint64_t seed = 1;
  double n_min = 0.011;     // [cycle/m] ISO 8608 band
  double n_max = 2.83;      // [cycle/m]
  double length = 5000.0;   // [m] at least this before the track repeats
  double fade_in_distance = 10.0;  // [m]
};

struct RoadProfileSpec {
  RoadKind kind = RoadKind::kBump;
  RoadWheels wheels = RoadWheels::kBoth;
  BumpSpec bump;
  IsoRoadSpec iso;
  BumpTrainSpec train;  // added to whichever kind
};

enum class WheelArrangement {
  kInLine,      // pitch plane: wheel 2 follows wheel 1 at `wheelbase`
  kSideBySide,  // roll plane: both wheels abreast
};

struct RoadSample {
  double z = 0.0;   // [m]
  double dz = 0.0;  // [m/s]
};

class RoadProfile {
 public:
  // speed: vehicle speed V [m/s] > 0. wheelbase: a + b [m] (in line only).
  // Generates the ISO road here (a few ms); at() never allocates. Copies
  // share the generated road.
  RoadProfile(const RoadProfileSpec& spec, double speed, WheelArrangement arrangement, double wheelbase);

  // Road height and rate under wheel (0 = wheel 1, 1 = wheel 2) at time t.
  RoadSample at(int wheel, double t) const noexcept;
  double height(int wheel, double t) const noexcept { return at(wheel, t).z; }

  // Delay of the wheel's input behind wheel 1's: wheelbase / V for wheel 2
  // in line (eq. 11), else 0.
  double delay(int wheel) const noexcept;

  // ISO road height of a track (0 or 1) at distance x [m], without the
  // fade-in; for tests of the class statistics.
  double track_height(int track, double x) const noexcept;
  // Variance of the ISO class over the band, Gd(n0) n0^2 (1/n_min - 1/n_max)
  // [m^2]; 0 for the other kinds.
  double iso_variance() const noexcept;
  // The generated ISO road (null for the other kinds).
  const IsoRoadTable* iso_table() const noexcept { return iso_table_.get(); }

  const RoadProfileSpec& spec() const noexcept { return spec_; }
  double speed() const noexcept { return speed_; }

 private:
  RoadSample bump(double tau) const noexcept;
  RoadSample train(double t_wheel) const noexcept;
  RoadSample iso(int track, double x) const noexcept;

  RoadProfileSpec spec_;
  double speed_;
  WheelArrangement arrangement_;
  double wheelbase_;
  double gd_n0_ = 0.0;
  std::shared_ptr<const IsoRoadTable> iso_table_;
};

}  // namespace rigctl
