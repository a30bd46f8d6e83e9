// A road simulator's target made from a road: the wheel displacement of a
// quarter car driven at a constant speed over an ISO 8608 random road
// (plant/half_car/road_profile.hpp generates the road), through its tyre.
// Vehicle: the rig's own wheel, body, tyre, spring and damper
// (QuarterCarParams), linear, integrated with RK4 at a tenth of the loop
// period. The result is limited to the iteration's band (what a
// road-simulator target holds after its measurement's own filters), faded in
// and out so the rig starts and ends at rest, and laid about `offset` (the
// rig's mid-stroke).
#pragma once

#include <string>
#include <vector>

#include "plant/half_car/road_profile.hpp"
#include "plant/quarter_car/quarter_car_params.hpp"

namespace rigctl {

struct RoadTargetSpec {
  IsoRoadClass road_class = IsoRoadClass::kC;
  uint64_t seed = 1;
  double speed_m_s = 5.0;     // [m/s]
  double duration_s = 20.0;   // [s] the target's length, fades included
  double period_s = 0.0025;   // [s] the rig loop's period: one target sample per tick
  double band_min_hz = 0.5;   // [Hz]
  double band_max_hz = 30.0;  // [Hz]
  double fade_s = 1.0;        // [s] half-cosine fade at each end
  double offset = 0.08;       // [m] the level the target moves about (mid-stroke)
  double lead_s = 5.0;        // [s] driven before the record starts: the vehicle's start transient is left out
};

struct RoadTarget {
  std::vector<double> t;        // [s] from 0
  std::vector<double> road;     // [m] the road under the tyre
  std::vector<double> wheel;    // [m] wheel displacement: the target
};

// Throws std::invalid_argument naming a bad field.
RoadTarget make_road_target(const QuarterCarParams& vehicle, const RoadTargetSpec& spec);

// Writes `t,<channel>,road` as a run file with metadata naming the road.
void write_road_target(const RoadTarget& target, const RoadTargetSpec& spec, const std::string& channel,
                       const std::string& path);

// A half-cosine fade in over the first `fade` samples and out over the last.
void fade_ends(std::vector<double>& x, std::size_t fade);

}  // namespace rigctl
