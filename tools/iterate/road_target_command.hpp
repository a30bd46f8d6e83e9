// `rigctl road-target CONFIG --out TARGET.csv`: a drive iteration's target,
// the wheel displacement of the config's quarter car over an ISO 8608 road
// (tools/iterate/road_target.hpp), as a run file or an RPC III file.
#pragma once

#include <ostream>
#include <string>

#include "tools/iterate/road_target.hpp"

namespace rigctl {

struct RoadTargetOptions {
  std::string config_path;
  std::string channel = "x_w";
  std::string out_path;
  RoadTargetSpec spec;
};

// "A".."E"; throws std::invalid_argument naming the classes.
IsoRoadClass iso_road_class_from_letter(const std::string& letter);

RoadTarget run_road_target(const RoadTargetOptions& options, std::ostream& out);

}  // namespace rigctl
