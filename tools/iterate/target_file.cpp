#include "tools/iterate/target_file.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "tools/iterate/resample.hpp"
#include "tools/iterate/rpc3_file.hpp"
#include "tools/runfile/run_file.hpp"

namespace rigctl {

namespace {

// A channel number: digits only (a channel's name is never all digits in
// either format's practice; a name like "12" would have to be given by number).
bool is_number(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
}

Target from_rpc3(const std::string& path, const std::string& channel) {
  const Rpc3File f = read_rpc3_file(path);
  Target t;
  t.file_period_s = f.period_s;
  if (is_number(channel)) {
    const std::size_t n = std::stoul(channel);
    if (n < 1 || n > f.channels.size()) {
      throw Rpc3Error(path + ": no channel number " + channel + " (the file has " + std::to_string(f.channels.size()) + ")");
    }
    t.channel = f.channels[n - 1].name;
    t.values = f.channels[n - 1].values;
    return t;
  }
  t.channel = channel;
  t.values = f.channel(channel, path);
  return t;
}

// The run file's header row (the first line not starting with '#'), split at commas.
std::vector<std::string> header_of(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line) && (line.empty() || line[0] == '#')) {
  }
  if (!in && line.empty()) throw RunFileError(path + ": no header row");
  std::vector<std::string> names;
  std::stringstream row(line);
  for (std::string cell; std::getline(row, cell, ',');) names.push_back(cell);
  return names;
}

Target from_run_file(const std::string& path, const std::string& channel) {
  std::string name = channel;
  if (is_number(channel)) {
    const std::vector<std::string> header = header_of(path);
    const std::size_t n = std::stoul(channel);
    if (n < 1 || n + 1 > header.size()) {
      throw RunFileError(path + ": no column number " + channel + " after t (the file has " +
                         std::to_string(header.size() - 1) + ")");
    }
    name = header[n];
  }
  RunFileOptions columns;
  columns.required = {name};
  const RunFile run = read_run_file(path, columns);
  Target t;
  t.channel = name;
  t.file_period_s = run.dt;
  t.start_s = run.t.front();
  t.values = run.col(name);
  return t;
}

}  // namespace

Target read_target(const std::string& path, const std::string& channel, double period_s, double max_length_s) {
  Target t = is_rpc3_path(path) ? from_rpc3(path, channel) : from_run_file(path, channel);
  t.duration_s = static_cast<double>(t.values.size()) * t.file_period_s;
  if (t.duration_s > max_length_s) {
    throw std::invalid_argument(path + ": the target is " + std::to_string(t.duration_s) + " s long, more than the " +
                                std::to_string(max_length_s) + " s a drive may last (--max-length); cut it into parts");
  }
  t.values = resample(t.values, t.file_period_s, period_s);
  return t;
}

}  // namespace rigctl
