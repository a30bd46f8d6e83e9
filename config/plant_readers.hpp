// Readers of each rig kind's `plant:` section, with the unit conversions of
// the config edge (degrees, bar, per-cent) done here.
#pragma once

#include "config/config_reader.hpp"
#include "plant/half_car/half_car_params.hpp"
#include "plant/pneumatic_rotary/pneumatic_rotary_params.hpp"
#include "plant/quarter_car/quarter_car_params.hpp"
#include "plant/two_poster/two_poster_plant.hpp"

namespace rigctl {

void read_quarter_car_plant(ConfigReader r, QuarterCarParams& p);
void read_pneumatic_rotary_plant(ConfigReader r, PneumaticRotaryParams& p);
void read_half_car_plant(ConfigReader r, HalfCarParams& p);
void read_two_poster_plant(ConfigReader r, TwoPosterParams& p);

}  // namespace rigctl
