// Fuzzes the run-file (CSV) reader of docs/run-files.md,
// tools/runfile/run_file.cpp. The first input byte picks the options (rig kind's
// columns or keep-all, drop_bad_rows, min_rows); the rest is the file.
// RunFileError is the reader's documented answer; anything else is a bug.
// Checks the reader's promises on what it returns: t strictly increasing,
// every kept column as long as t, dt > 0.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>

#include "tools/runfile/run_file.hpp"

namespace {

void check(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "run file invariant broken: %s\n", what);
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  static const char* const kRigs[] = {"", "quarter_car", "pneumatic_rotary", "half_car", "linear_axis", "damper", "", "x"};
  const uint8_t mode = data[0];
  rigctl::RunFileOptions options;
  try {
    const char* rig = kRigs[mode & 7];
    if (rig[0] != '\0') options = rigctl::run_file_columns(rigctl::run_file_rig_from_string(rig));
  } catch (const rigctl::RunFileError&) {
    return 0;  // the unknown kind "x": the documented error
  }
  options.drop_bad_rows = (mode & 8) != 0;
  options.min_rows = (mode >> 4) & 0x0F;  // 0..15
  std::istringstream in(std::string(reinterpret_cast<const char*>(data + 1), size - 1));
  try {
    const rigctl::RunFile rf = rigctl::parse_run_file(in, "fuzz.csv", options);
    check(rf.t.size() >= 2, "at least two rows");
    check(std::isfinite(rf.dt) && rf.dt > 0.0, "dt finite and > 0");
    for (const double x : rf.t) check(std::isfinite(x), "t finite");
    for (std::size_t i = 1; i < rf.t.size(); ++i) check(rf.t[i] > rf.t[i - 1], "t strictly increasing");
    for (const auto& [name, col] : rf.columns) check(col.size() == rf.t.size(), "column as long as t");
    for (const auto& r : options.required) check(rf.has(r), "required column kept");
    for (const auto& [k, v] : rf.metadata) {
      try {
        (void)rf.meta_number(k);
      } catch (const rigctl::RunFileError&) {
      }
    }
    if (std::getenv("FUZZ_VERBOSE")) std::fprintf(stderr, "accepted: %zu rows, dt %g\n", rf.size(), rf.dt);
  } catch (const rigctl::RunFileError& e) {
    if (std::getenv("FUZZ_VERBOSE")) std::fprintf(stderr, "%s\n", e.what());
  }
  return 0;
}
