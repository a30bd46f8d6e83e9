// What the one-channel and the multi-drive identification share about their
// runs: the hold after the excitation and where the run's CSV goes.
#pragma once

#include <filesystem>
#include <string>

namespace rigctl {

// Held at the operating point(s) after the excitation, so that the run's
// controlled stop never cuts into it.
inline constexpr double kIdentifyTailS = 0.5;

// OUT.json's run file: OUT-run.csv beside it.
inline std::string identify_default_csv_path(const std::string& out_path) {
  std::filesystem::path p(out_path);
  p.replace_extension();
  return p.string() + "-run.csv";
}

}  // namespace rigctl
