#include "tools/run/console_station.hpp"

#include <cmath>

#include <fmt/format.h>

#include "rt/safety/detector_kind.hpp"

namespace rigctl {

namespace {

// "min -0.012, max 0.172": the bounds a detector has (infinite: none).
std::string bounds(double min, double max) {
  std::string out;
  if (std::isfinite(min)) out += fmt::format("min {:g}", min);
  if (std::isfinite(max)) out += fmt::format("{}max {:g}", out.empty() ? "" : ", ", max);
  return out;
}

std::string threshold(const DetectorConfig& d) {
  std::string out;
  switch (d.type) {
    case DetectorKind::kOverruns:
      out = fmt::format("more than {} late ticks in {:g} s", d.max_count, d.window_s);
      break;
    case DetectorKind::kStuck:
      out = fmt::format("changes <= {:g} while |{}| >= {:g}", d.tolerance, d.output, d.command_min);
      break;
    default:
      out = bounds(d.min, d.max);
  }
  if (d.duration_s > 0.0) out += fmt::format(" for {:g} s", d.duration_s);
  return out;
}

}  // namespace

foxglove::StationDescription console_station(const RigConfig& config, const ChannelLayout& layout,
                                             const std::string& setpoint_name,
                                             const std::vector<std::string>& more_setpoint_names) {
  foxglove::StationDescription s;
  s.rig = std::string(to_string(config.rig));
  for (const auto& l : config.limits) {
    s.detectors.push_back({"limits." + l.channel, "range", l.channel, bounds(l.min, l.max),
                           std::string(to_string(config.safety.limits_action))});
  }
  for (const auto& d : config.safety.detectors) {
    const std::string channel = d.channel.empty() ? d.output : d.channel;
    s.detectors.push_back({d.name, std::string(to_string(d.type)), channel, threshold(d), std::string(to_string(d.action))});
  }
  // Demand and feedback, what drives the valve, then the pressures: the
  // channels an operator watches on every rig kind; the page offers the rest.
  // Every control channel's demand and feedback on a rig with several.
  if (!setpoint_name.empty()) s.demands.emplace_back(setpoint_name, config.controller.feedback);
  for (std::size_t i = 0; i < more_setpoint_names.size() && i < config.more_channels.size(); ++i) {
    s.demands.emplace_back(more_setpoint_names[i], config.more_channels[i].controller.feedback);
  }
  if (setpoint_name.empty()) s.scope_channels.push_back(config.controller.feedback);
  for (const auto& [demand, feedback] : s.demands) {
    s.scope_channels.push_back(demand);
    s.scope_channels.push_back(feedback);
  }
  for (const auto& o : layout.outputs) s.scope_channels.push_back(o.name);
  for (const auto& i : layout.inputs) {
    bool fed_back = i.name == config.controller.feedback;
    for (const auto& ch : config.more_channels) fed_back = fed_back || i.name == ch.controller.feedback;
    if (i.unit == "Pa" && !fed_back) s.scope_channels.push_back(i.name);
  }
  return s;
}

}  // namespace rigctl
