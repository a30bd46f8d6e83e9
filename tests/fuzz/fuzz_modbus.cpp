// Fuzzes Modbus response decoding: drivers/modbus/modbus_codec.cpp (read planning,
// register blocks to raw values in every format and word order, and back) and
// drivers/modbus/calibration.cpp (raw to SI, linear and table), the path the DAQ's
// I/O thread takes from a read reply to Sample values.
//
// Input (front to back, see make_seeds.py): plan options (max_gap i8,
// max_registers u8), a point count (mod 17), per point 6 bytes (unit id u8,
// flags u8: bits 0-2 format, 3-4 word order, 5 holding register, 6 unit id +256,
// 7 address +65536; address u16 LE; calibration selector u8 (bit 0 table,
// bits 1-7 table size); a spare byte), a calibration (gain, offset f64 or the
// table's raw/si f64 pairs), then register data (u16 LE) filling the reply
// buffers, one per planned block, each exactly `count` registers (ASan sees
// any read past a reply).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "drivers/modbus/calibration.hpp"
#include "drivers/modbus/modbus_codec.hpp"
#include "tests/fuzz/fuzz_input.hpp"

using namespace rigctl;
using fuzz::check;

namespace {

std::optional<Calibration> make_calibration(fuzz::Reader& in, uint8_t selector) {
  try {
    if ((selector & 1) == 0) return Calibration(LinearCalibration(in.f64(), in.f64()));
    const std::size_t n = selector >> 1;  // 0..127 points
    std::vector<CalibrationPoint> points(n);
    for (auto& p : points) {
      p.raw = in.f64();
      p.si = in.f64();
    }
    return Calibration(TableCalibration(points));
  } catch (const std::invalid_argument&) {
    return std::nullopt;  // documented: construction validates and throws
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  fuzz::Reader in{data, size};
  ReadPlanOptions options;
  options.max_gap = static_cast<int8_t>(in.u8());
  options.max_registers = in.u8();
  const std::size_t n = in.u8() % 17;
  std::vector<ModbusPoint> points(n);
  std::vector<uint8_t> selectors(n);
  for (std::size_t i = 0; i < n; ++i) {
    ModbusPoint& p = points[i];
    p.unit_id = in.u8();
    const uint8_t flags = in.u8();
    p.format = static_cast<DataFormat>(flags & 0x7);  // 5..7: invalid formats
    p.order = static_cast<WordOrder>((flags >> 3) & 0x3);
    p.type = (flags & 0x20) ? RegisterType::kHoldingRegister : RegisterType::kInputRegister;
    if (flags & 0x40) p.unit_id += 256;
    p.address = in.u16();
    if (flags & 0x80) p.address += 65536 - 70000 * (p.address & 1);  // beyond 65535 or negative
    selectors[i] = in.u8();
    (void)in.u8();
  }
  std::vector<std::optional<Calibration>> calibrations;
  for (std::size_t i = 0; i < n; ++i) calibrations.push_back(make_calibration(in, selectors[i]));

  // Unplanned decoding of arbitrary registers, every format (valid or not) and order.
  {
    uint16_t regs[2] = {in.u16(), in.u16()};
    for (int f = 0; f < 8; ++f) {
      for (int o = 0; o < 4; ++o) {
        const auto format = static_cast<DataFormat>(f);
        const auto order = static_cast<WordOrder>(o);
        const double raw = decode_registers(regs, format, order);
        uint16_t out[2] = {0xDEAD, 0xBEEF};
        const EncodeStatus st = encode_registers(raw, format, order, out);
        if (f < 5) {
          check(register_count(format) == (f < 2 ? 1 : 2), "register count");
          if (!std::isnan(raw)) {
            check(st == EncodeStatus::kOk || (f == 4 && std::isinf(raw) && st == EncodeStatus::kSaturated),
                  "a decoded value re-encodes without saturation");
            if (st == EncodeStatus::kOk) {
              check(out[0] == regs[0] && (f < 2 ? out[1] == 0xBEEF : out[1] == regs[1]), "register round trip");
            }
          } else {
            check(f == 4 && st == EncodeStatus::kRejected, "only float32 decodes to NaN; NaN is rejected");
          }
        } else {
          check(std::isnan(raw) && st == EncodeStatus::kRejected, "invalid format");
        }
        check(combine_registers(regs, order) == combine_registers(regs, order), "combine");
        uint16_t split[2];
        split_registers(combine_registers(regs, order), order, split);
        check(split[0] == regs[0] && split[1] == regs[1], "split(combine(x)) == x");
      }
    }
  }

  ReadPlan plan;
  try {
    plan = plan_reads(points, options);
  } catch (const std::invalid_argument&) {
    return 0;  // documented for bad options or points
  }
  check(plan.where.size() == points.size(), "one location per point");
  std::vector<std::vector<uint16_t>> replies;
  for (const ReadBlock& b : plan.blocks) {
    check(b.count >= 1 && b.count <= options.max_registers, "block size");
    check(b.address >= 0 && b.address + b.count <= 65536, "block inside the register space");
    std::vector<uint16_t> reply(static_cast<std::size_t>(b.count));
    for (auto& r : reply) r = in.u16();
    replies.push_back(std::move(reply));
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    const ModbusPoint& p = points[i];
    const PointLocation at = plan.where[i];
    check(at.block >= 0 && static_cast<std::size_t>(at.block) < plan.blocks.size(), "point's block exists");
    const ReadBlock& b = plan.blocks[static_cast<std::size_t>(at.block)];
    check(b.unit_id == p.unit_id && b.type == p.type, "point in a block of its unit and table");
    check(at.offset >= 0 && at.offset + register_count(p.format) <= b.count, "point inside its block");
    check(b.address + at.offset == p.address, "offset matches the address");
    const uint16_t* regs = replies[static_cast<std::size_t>(at.block)].data() + at.offset;
    const double raw = decode_registers(regs, p.format, p.order);
    if (!calibrations[i]) continue;
    const Calibration& cal = *calibrations[i];
    const double si = cal.to_si(raw);
    check(!std::isnan(raw) || std::isnan(si), "NaN in, NaN out (to_si)");
    const double back = cal.to_raw(si);
    check(!std::isnan(si) || std::isnan(back), "NaN in, NaN out (to_raw)");
    if (const TableCalibration* t = cal.table()) {
      check(!t->in_table(std::nan("")), "in_table(NaN)");
      // Documented: breakpoints map exactly onto their partners (checked at
      // the ends, for tables whose spans are finite doubles).
      const double lo = t->to_si(t->raw_min()), hi = t->to_si(t->raw_max());
      if (std::isfinite(t->raw_max() - t->raw_min()) && std::isfinite(hi - lo)) {
        check(t->to_raw(lo) == t->raw_min() && t->to_raw(hi) == t->raw_max(), "table ends map exactly");
      }
    }
    uint16_t out[2] = {0, 0};
    (void)encode_registers(back, p.format, p.order, out);
  }
  return 0;
}
