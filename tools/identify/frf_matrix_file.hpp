// The matrix FRF file (JSON, docs/frf-files.md section 2.2): what
// `rigctl identify` writes for a rig with several drives (the two-poster's
// posts) and `rigctl iterate` reads for its MIMO inverse. One matrix of
// closed-loop responses from every drive (the channels' demands) to every
// response (the channels' feedbacks and valve commands first, then those
// asked for), with each response's multiple coherence and each
// response-drive pair's partial coherence per line. The single-channel
// file (frf_file.hpp) is unchanged; the two are told apart by `format`.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tools/identify/frf_data.hpp"
#include "tools/identify/mimo_frf.hpp"

namespace rigctl {

inline constexpr const char* kFrfMatrixFormat = "rigctl-frf-matrix";
inline constexpr int kFrfMatrixVersion = 1;

struct FrfMatrixExcitation {
  std::string kind = "orthogonal_multisine";
  double band_min_hz = 0.0, band_max_hz = 0.0;
  std::vector<double> amplitude;  // per drive: the peak [drive unit]
  std::size_t realisations = 0;   // phase rotations (>= drives): the drives are uncorrelated over them
  double period_s = 0.0;          // one multisine period: the line spacing is 1 / period_s
  std::size_t settle_periods = 1; // played before each analysed period
  uint64_t seed = 0;
  double start_s = 0.0, end_s = 0.0;  // run-file times of the excitation
};

struct FrfMatrixData {
  std::string rig, config, run_log;
  double sample_rate_hz = 0.0;
  std::vector<FrfChannel> drives;        // the channels' demands, e.g. x_ref_1, x_ref_2
  std::vector<double> operating_point;   // per drive: the demand held [drive unit]
  std::vector<FrfChannel> responses;     // feedbacks, commands, then the extra ones
  std::vector<double> response_mean;     // per response over the analysed records
  FrfMatrixExcitation excitation;
  MimoFrf frf;                           // drives -> responses

  std::size_t drive_index(const std::string& name) const;     // throws naming the drives
  std::size_t response_index(const std::string& name) const;  // throws naming the responses
  // The rows of `names` only (the iteration's target channels).
  MimoFrf rows(const std::vector<std::string>& names) const;
};

std::string frf_matrix_to_json(const FrfMatrixData& m);
void write_frf_matrix_file(const FrfMatrixData& m, const std::string& path);

// Throws FrfFileError naming the file and the missing or bad key.
FrfMatrixData parse_frf_matrix_json(const std::string& text, const std::string& name);
FrfMatrixData read_frf_matrix_file(const std::string& path);

// The file's `format` without reading the rest: "rigctl-frf" (one channel)
// or "rigctl-frf-matrix". Throws FrfFileError when it is neither.
std::string frf_file_format(const std::string& path);

}  // namespace rigctl
