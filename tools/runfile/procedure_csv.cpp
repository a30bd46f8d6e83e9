#include "tools/runfile/procedure_csv.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>

#include "rigctl/procedure_t.hpp"

namespace rigctl {

namespace {

constexpr const char* kHeader =
    "t,tick,step,step_name,step_kind,phase,step_cycles,total_cycles,programmed_cycles,ramp_in_cycles,row,row_cycles,"
    "pass,time_left,wanted,comp_gain,comp_phase,comp_mean,comp_peak,comp_valley,amplitude_error,phase_error,"
    "peak_error,valley_error,peak,valley,pv_change,damage,stop_at_block_end\n";

void put_row(std::FILE* f, const procedure_t& p) {
  // Step names come from the procedure file: quoted, a quote doubled (RFC 4180).
  std::string name = "\"";
  for (char c : p.step_name) name += c == '"' ? std::string("\"\"") : std::string(1, c);
  name += "\"";
  std::fprintf(f, "%.9g,%lld,%d,%s,%s,%s,%lld,%lld,%lld,%lld,%d,%lld,%lld,%.6g", p.t, static_cast<long long>(p.tick),
               p.step, name.c_str(), p.step_kind.c_str(), p.phase.c_str(), static_cast<long long>(p.step_cycles),
               static_cast<long long>(p.total_cycles), static_cast<long long>(p.programmed_cycles),
               static_cast<long long>(p.ramp_in_cycles), p.row, static_cast<long long>(p.row_cycles),
               static_cast<long long>(p.pass), p.time_left);
  for (double v : {p.wanted, p.comp_gain, p.comp_phase, p.comp_mean, p.comp_peak, p.comp_valley, p.amplitude_error,
                   p.phase_error, p.peak_error, p.valley_error, p.peak, p.valley, p.pv_change, p.damage}) {
    std::fprintf(f, ",%.9g", v + 0.0);
  }
  std::fprintf(f, ",%d\n", p.stop_at_block_end ? 1 : 0);
}

}  // namespace

std::string procedure_csv_path(const std::string& run_csv_path) {
  const std::string ext = ".csv";
  const bool has_ext = run_csv_path.size() > ext.size() && run_csv_path.compare(run_csv_path.size() - ext.size(), ext.size(), ext) == 0;
  return (has_ext ? run_csv_path.substr(0, run_csv_path.size() - ext.size()) : run_csv_path) + ".procedure.csv";
}

int64_t procedure_log_to_csv(const std::string& lcm_log_path, const std::string& csv_path, const std::string& channel_prefix) {
  const std::string channel = channel_prefix + "PROCEDURE";
  lcm::LogFile log(lcm_log_path, "r");
  if (!log.good()) throw std::runtime_error("procedure csv: cannot open '" + lcm_log_path + "' as LCM log");
  const std::string tmp = csv_path + ".tmp";
  std::FILE* f = nullptr;
  int64_t rows = 0;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel != channel) continue;
    procedure_t p;
    if (p.decode(ev->data, 0, ev->datalen) < 0) continue;
    if (f == nullptr) {
      f = std::fopen(tmp.c_str(), "w");
      if (f == nullptr) throw std::runtime_error("procedure csv: cannot create '" + tmp + "': " + std::strerror(errno));
      std::fputs(kHeader, f);
    }
    put_row(f, p);
    ++rows;
  }
  if (f == nullptr) return 0;
  const bool failed = std::ferror(f) != 0;
  if (std::fclose(f) != 0 || failed) {
    std::remove(tmp.c_str());
    throw std::runtime_error("procedure csv: writing '" + tmp + "' failed (disk full?)");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, csv_path, ec);
  if (ec) throw std::runtime_error("procedure csv: cannot rename '" + tmp + "' to '" + csv_path + "': " + ec.message());
  return rows;
}

}  // namespace rigctl
