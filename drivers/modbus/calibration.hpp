// Transducer calibration: raw register value (counts, or the float a DAQ
// module reports in its own units) to SI and back. Inputs use to_si(); the
// servovalve output and the simulated DAQ use to_raw().
//
// Construction validates and may throw std::invalid_argument (start-up code).
// to_si()/to_raw() run on the 2.5 ms tick path: they never allocate, lock or
// throw. NaN in gives NaN out, so an invalid reading stays visibly invalid.
#pragma once

#include <cstddef>
#include <span>
#include <utility>
#include <variant>
#include <vector>

namespace rigctl {

// si = gain * raw + offset; raw = (si - offset) / gain.
class LinearCalibration {
 public:
  LinearCalibration() = default;  // identity: gain 1, offset 0
  // Throws std::invalid_argument unless gain is finite and non-zero and offset finite.
  LinearCalibration(double gain, double offset);

  // The line through (raw0, si0) and (raw1, si1), e.g. ADC counts at both ends
  // of a transducer's span. Throws unless raw0 != raw1 and si0 != si1.
  static LinearCalibration from_points(double raw0, double si0, double raw1, double si1);

  double gain() const noexcept { return gain_; }
  double offset() const noexcept { return offset_; }

  double to_si(double raw) const noexcept { return gain_ * raw + offset_; }
  double to_raw(double si) const noexcept { return (si - offset_) / gain_; }

 private:
  double gain_ = 1.0;
  double offset_ = 0.0;
};

struct CalibrationPoint {
  double raw = 0.0;
  double si = 0.0;
};

// Piecewise-linear table for a nonlinear transducer.
//
// The raw column must be strictly increasing and the SI column strictly
// monotonic (increasing or decreasing), so the map is a bijection and the
// inverse is again a table lookup, on the SI column.
//
// Beyond the ends the first and last segments are extrapolated linearly; the
// value is NOT clamped. A clamped reading would freeze at the table's end
// while the rod keeps moving: the controller would see no motion and the
// limit checks on that channel could never trip. Extrapolation keeps the
// reading continuous, monotonic and moving with the transducer, keeps
// to_raw(to_si(x)) == x everywhere, and leaves "out of range" to the limit
// checks (the driver can also test in_table(raw) to mark the sample).
class TableCalibration {
 public:
  // Throws std::invalid_argument for fewer than 2 points, a non-finite value,
  // a raw value not greater than the previous one, or an SI value that breaks
  // strict monotonicity; the message names the offending point's index.
  explicit TableCalibration(std::span<const CalibrationPoint> points);
  TableCalibration(std::span<const double> raw, std::span<const double> si);

  double to_si(double raw) const noexcept;
  double to_raw(double si) const noexcept;

  std::size_t size() const noexcept { return raw_.size(); }
  double raw_min() const noexcept { return raw_.front(); }
  double raw_max() const noexcept { return raw_.back(); }
  bool si_increasing() const noexcept { return si_increasing_; }
  // True when raw lies within the table (no extrapolation); false for NaN.
  bool in_table(double raw) const noexcept { return raw >= raw_.front() && raw <= raw_.back(); }

 private:
  void validate();  // throws; sets si_increasing_

  std::vector<double> raw_;  // strictly increasing
  std::vector<double> si_;   // strictly increasing or strictly decreasing
  bool si_increasing_ = true;
};

// One channel's calibration, whichever kind. A value type: copy it freely at
// start-up; after construction to_si()/to_raw() never allocate.
class Calibration {
 public:
  Calibration() = default;  // identity (linear, gain 1, offset 0)
  Calibration(LinearCalibration linear) : kind_(linear) {}  // NOLINT: implicit on purpose
  Calibration(TableCalibration table) : kind_(std::move(table)) {}  // NOLINT

  double to_si(double raw) const noexcept;
  double to_raw(double si) const noexcept;

  // The alternative held, or nullptr.
  const LinearCalibration* linear() const noexcept { return std::get_if<LinearCalibration>(&kind_); }
  const TableCalibration* table() const noexcept { return std::get_if<TableCalibration>(&kind_); }

 private:
  std::variant<LinearCalibration, TableCalibration> kind_;
};

}  // namespace rigctl
