// The tick's step durations as one line of text, for the run's closing
// summary and the bench: "read 3.1, check 1.2, ... us".
#pragma once

#include <string>

#include "rt/tick_stages.hpp"

namespace rigctl {

std::string describe_stages(const StageDurations& ns);

}  // namespace rigctl
