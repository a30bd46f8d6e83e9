#include "tools/iterate/mimo_drive_player.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "tools/identify/channel_view.hpp"
#include "tools/identify/excitation_profile.hpp"
#include "tools/identify/identify_run_defaults.hpp"
#include "tools/identify/identify_analysis.hpp"
#include "tools/run/rig_assembly.hpp"
#include "tools/run/run_command.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {

namespace {


}  // namespace

MimoPlayResult play_drives(const RigConfig& config, const std::vector<std::vector<double>>& drives,
                           const std::vector<double>& ops, const std::vector<std::string>& channels,
                           const PlaySettings& s, const std::atomic<bool>& stop, std::ostream& out) {
  const std::size_t n = channel_count(config);
  if (drives.size() != n || ops.size() != n) {
    throw std::invalid_argument("play: " + std::to_string(n) + " channels need as many drives and operating points");
  }
  const double dt = config.loop.period_s;
  std::vector<std::vector<double>> deviation(n);
  std::vector<LeadIn> leads;
  for (std::size_t i = 0; i < n; ++i) {
    if (drives[i].size() != drives.front().size()) throw std::invalid_argument("play: drives of different lengths");
    for (double v : drives[i]) deviation[i].push_back(v - ops[i]);
    leads.push_back(lead_in_to(channel_view(config, i), ops[i]));
  }
  const AlignedExcitation aligned(std::move(leads), deviation, s.settle_s, dt, kIdentifyTailS);
  auto profile = [&](std::size_t i) { return aligned.profile(i); };
  RunOptions ro;
  ro.config_path = config.file;
  ro.case_name = config.case_name;
  ro.fast = s.fast;
  ro.realtime = s.realtime;
  ro.csv_path = s.csv_path;
  ro.log_path = s.log_path;
  ro.profile_override = [&] { return profile(0); };
  ro.more_profile_override = [&](std::size_t i) { return profile(i); };
  std::ostringstream run_out;
  const RunReport report = run_rig(config, ro, stop, run_out);
  MimoPlayResult r;
  if (report.loop.end_event.code != EventCode::kProfileFinished || stop.load()) {
    r.end_reason = stop.load() ? "stop requested" : report.end_reason;
    out << run_out.str();
    return r;
  }
  const std::string first = channel_setpoint_name(setpoint_name_for(config.rig), 0);
  RunFileOptions columns;
  columns.required.push_back(first);
  for (const auto& c : channels) {
    if (std::find(columns.required.begin(), columns.required.end(), c) == columns.required.end()) columns.required.push_back(c);
  }
  const RunFile run = read_run_file(s.csv_path, columns);
  const auto settle_ticks = static_cast<std::size_t>(std::lround(aligned.hold_s(0) / run.dt));
  const std::size_t start = find_excitation_start(run.col(first), ops[0], deviation[0], settle_ticks);
  for (const auto& c : channels) {
    const auto& y = run.col(c);
    r.channels.emplace_back(y.begin() + static_cast<std::ptrdiff_t>(start),
                            y.begin() + static_cast<std::ptrdiff_t>(start + drives.front().size()));
  }
  r.drive_start_s = run.t[start];
  r.completed = true;
  return r;
}

}  // namespace rigctl
