#include "tools/iterate/road_target_command.hpp"

#include <cmath>
#include <stdexcept>

#include "config/config_reader.hpp"
#include "tools/identify/identify_plan.hpp"
#include "tools/iterate/rpc3_file.hpp"

namespace rigctl {

IsoRoadClass iso_road_class_from_letter(const std::string& letter) {
  static const std::string classes = "ABCDE";
  const auto i = classes.find(letter);
  if (letter.size() != 1 || i == std::string::npos) throw std::invalid_argument("road class '" + letter + "': one of A, B, C, D, E");
  return static_cast<IsoRoadClass>(i);
}

RoadTarget run_road_target(const RoadTargetOptions& o, std::ostream& out) {
  const RigConfig c = load_rig_config(o.config_path);
  if (c.rig != RigKind::kQuarterCar) throw std::invalid_argument(o.config_path + ": road-target needs a quarter-car config");
  RoadTargetSpec spec = o.spec;
  spec.period_s = c.loop.period_s;
  spec.offset = default_operating_point(c);
  const RoadTarget t = make_road_target(c.quarter_car, spec);
  if (is_rpc3_path(o.out_path)) {
    Rpc3File f;
    f.time_type = rpc3_time_type_for(o.out_path);
    f.period_s = spec.period_s;
    f.channels = {{o.channel, "m", t.wheel}, {"road", "m", t.road}};
    write_rpc3_file(f, o.out_path);
  } else {
    write_road_target(t, spec, o.channel, o.out_path);
  }
  double lo = t.wheel.front(), hi = lo, v = 0.0;
  for (std::size_t i = 0; i < t.wheel.size(); ++i) {
    lo = std::min(lo, t.wheel[i]);
    hi = std::max(hi, t.wheel[i]);
    if (i > 0) v = std::max(v, std::abs(t.wheel[i] - t.wheel[i - 1]) / spec.period_s);
  }
  out << "road-target: " << t.t.size() << " samples of " << o.channel << " in " << lo << " .. " << hi
      << " m, peak velocity " << v << " m/s -> " << o.out_path << "\n";
  return t;
}

}  // namespace rigctl
