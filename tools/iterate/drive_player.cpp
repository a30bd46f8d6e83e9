#include "tools/iterate/drive_player.hpp"

#include <algorithm>
#include <sstream>

#include "tools/identify/excitation_profile.hpp"
#include "tools/identify/identify_analysis.hpp"
#include "tools/run/rig_assembly.hpp"
#include "tools/run/run_command.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {

namespace {

// Held at the operating point after the drive, so that the run's controlled
// stop never cuts into the record.
constexpr double kTailS = 0.5;

}  // namespace

PlayResult play_drive(const RigConfig& config, const std::vector<double>& drive, const std::string& channel,
                      const PlaySettings& s, const std::atomic<bool>& stop, std::ostream& out) {
  std::vector<double> deviation(drive.size());
  for (std::size_t i = 0; i < drive.size(); ++i) deviation[i] = drive[i] - s.operating_point;
  const LeadIn lead = lead_in_to(config, s.operating_point);

  RunOptions ro;
  ro.config_path = config.file;
  ro.case_name = config.case_name;
  ro.fast = s.fast;
  ro.realtime = s.realtime;
  ro.csv_path = s.csv_path;
  ro.log_path = s.log_path;
  ro.profile_override = [&] {
    return std::make_unique<ExcitationProfile>(lead, s.settle_s, deviation, config.loop.period_s, kTailS);
  };
  std::ostringstream run_out;  // the run's own report: the iteration reports per iteration instead
  const RunReport report = run_rig(config, ro, stop, run_out);
  PlayResult r;
  // Only a run that played its whole demand ends on the profile's end; any
  // other end (a trip, a detector's controlled stop, a stop request) leaves
  // an incomplete record.
  if (report.loop.end_event.code != EventCode::kProfileFinished || stop.load()) {
    r.end_reason = stop.load() ? "stop requested" : report.end_reason;
    out << run_out.str();
    return r;
  }
  const std::string setpoint = setpoint_name_for(config.rig);
  RunFileOptions columns;
  for (const std::string& name : {setpoint, channel, config.controller.feedback, config.controller.output}) {
    if (std::find(columns.required.begin(), columns.required.end(), name) == columns.required.end()) columns.required.push_back(name);
  }
  const RunFile run = read_run_file(s.csv_path, columns);
  const auto settle_ticks = static_cast<std::size_t>(s.settle_s / run.dt);
  const std::size_t start = find_excitation_start(run.col(setpoint), s.operating_point, deviation, settle_ticks);
  auto over_drive = [&](const std::string& name) {
    const auto& y = run.col(name);
    return std::vector<double>(y.begin() + static_cast<std::ptrdiff_t>(start),
                               y.begin() + static_cast<std::ptrdiff_t>(start + drive.size()));
  };
  r.response = over_drive(channel);
  r.feedback = over_drive(config.controller.feedback);
  r.command = over_drive(config.controller.output);
  r.drive_start_s = run.t[start];
  r.completed = true;
  return r;
}

}  // namespace rigctl
