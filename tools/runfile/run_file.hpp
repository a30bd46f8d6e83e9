// Reader of run files, docs/run-files.md section 1: optional
// `# key: value` metadata lines, one header row, one row per sample, `t`
// first and strictly increasing, SI columns.
//
// Decisions the contract leaves open:
//  * Time. The median step is the sample period. Steps within 1 % of it are
//    taken as uniform (timestamp jitter of real DAQs, e.g. EMPS). Steps between
//    0.5x and 1.5x the median are jitter: every checked column is resampled to
//    the uniform grid of the median step by linear interpolation and
//    `resampled` is set. A step above 1.5x the median is a gap (lost samples):
//    rejected with the line number, because interpolating across it would
//    invent data. A step below 0.5x the median is rejected likewise.
//  * Only `t` and the columns the rig knows (required and optional) are
//    checked and kept; other columns are ignored whatever they contain. With
//    no rig (empty `known`), every column is checked and kept.
//  * A bad cell (empty, nan, inf, text) or a short / long row is an error
//    naming the line and column, unless `drop_bad_rows` is set: then the row
//    is dropped and counted in `dropped_rows`.
#pragma once

#include <cstddef>
#include <istream>
#include <map>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "tools/runfile/run_file_rig.hpp"

namespace rigctl {

class RunFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RunFileOptions {
  std::vector<std::string> required;  // missing one is an error naming it
  std::vector<std::string> optional;  // kept when present
  bool drop_bad_rows = false;
  std::size_t min_rows = 10;
};

struct RunFile {
  std::vector<std::pair<std::string, std::string>> metadata;  // in file order
  std::vector<std::string> header;                            // all columns, as in the file
  std::vector<double> t;
  std::map<std::string, std::vector<double>> columns;  // checked columns except t
  double dt = 0.0;                                     // sample period (median step) [s]
  bool resampled = false;
  std::size_t dropped_rows = 0;

  bool has(const std::string& name) const { return columns.count(name) != 0; }
  const std::vector<double>& col(const std::string& name) const;
  std::optional<std::string> meta(const std::string& key) const;
  // A metadata value as a number; an error naming the key when present but not numeric.
  std::optional<double> meta_number(const std::string& key) const;
  std::size_t size() const { return t.size(); }
};

// A rig kind by its name (`--rig`, `# rig:`); throws RunFileError naming
// the known kinds for another name: bad input like the file itself.
RunFileRig run_file_rig_from_string(const std::string& name);

// Columns the contract lists for a rig kind.
RunFileOptions run_file_columns(RunFileRig rig);

RunFile parse_run_file(std::istream& in, const std::string& name, const RunFileOptions& options);
RunFile read_run_file(const std::string& path, const RunFileOptions& options);

}  // namespace rigctl
