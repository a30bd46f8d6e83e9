#include "drivers/modbus/modbus_codec.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>

namespace rigctl {

namespace {

constexpr uint16_t swap_bytes(uint16_t r) noexcept { return static_cast<uint16_t>((r >> 8) | (r << 8)); }

constexpr bool byte_swapped(WordOrder order) noexcept {
  return order == WordOrder::kHighFirstByteSwapped || order == WordOrder::kLowFirstByteSwapped;
}

constexpr bool low_word_first(WordOrder order) noexcept {
  return order == WordOrder::kLowFirst || order == WordOrder::kLowFirstByteSwapped;
}

uint16_t read16(const uint16_t* regs, WordOrder order) noexcept {
  return byte_swapped(order) ? swap_bytes(regs[0]) : regs[0];
}

void write16(uint16_t value, WordOrder order, uint16_t* regs) noexcept {
  regs[0] = byte_swapped(order) ? swap_bytes(value) : value;
}

// Rounds to nearest and clamps to [lo, hi] (integers exactly representable in
// a double). NaN must have been handled by the caller.
template <typename T>
std::pair<T, EncodeStatus> to_integer(double raw) noexcept {
  constexpr double lo = static_cast<double>(std::numeric_limits<T>::min());
  constexpr double hi = static_cast<double>(std::numeric_limits<T>::max());
  const double r = std::round(raw);  // +-inf stay +-inf and are clamped below
  if (r < lo) return {std::numeric_limits<T>::min(), EncodeStatus::kSaturated};
  if (r > hi) return {std::numeric_limits<T>::max(), EncodeStatus::kSaturated};
  return {static_cast<T>(r), EncodeStatus::kOk};
}

// One place for the names, so the parser, the error messages and the
// loader's choice lists cannot disagree.
constexpr std::array<std::string_view, 5> kFormatNames = {"int16", "uint16", "int32", "uint32", "float32"};
constexpr std::array<DataFormat, 5> kFormatValues = {DataFormat::kInt16, DataFormat::kUint16, DataFormat::kInt32,
                                                     DataFormat::kUint32, DataFormat::kFloat32};

constexpr std::array<std::string_view, 8> kOrderNames = {"high_first", "abcd", "low_first", "cdab",
                                                         "high_first_byte_swapped", "badc",
                                                         "low_first_byte_swapped", "dcba"};
constexpr std::array<WordOrder, 8> kOrderValues = {
    WordOrder::kHighFirst, WordOrder::kHighFirst, WordOrder::kLowFirst, WordOrder::kLowFirst,
    WordOrder::kHighFirstByteSwapped, WordOrder::kHighFirstByteSwapped,
    WordOrder::kLowFirstByteSwapped, WordOrder::kLowFirstByteSwapped};

constexpr std::array<std::string_view, 2> kTypeNames = {"input", "holding"};
constexpr std::array<RegisterType, 2> kTypeValues = {RegisterType::kInputRegister,
                                                     RegisterType::kHoldingRegister};

template <typename E, std::size_t N>
E parse(std::string_view what, std::string_view name, const std::array<std::string_view, N>& names,
        const std::array<E, N>& values) {
  for (std::size_t i = 0; i < N; ++i) {
    if (names[i] == name) return values[i];
  }
  std::string list;
  for (const auto n : names) {
    if (!list.empty()) list += ", ";
    list += n;
  }
  throw std::invalid_argument("unknown " + std::string(what) + " '" + std::string(name) +
                              "' (expected one of: " + list + ")");
}

}  // namespace

int register_count(DataFormat format) noexcept {
  switch (format) {
    case DataFormat::kInt16:
    case DataFormat::kUint16:
      return 1;
    case DataFormat::kInt32:
    case DataFormat::kUint32:
    case DataFormat::kFloat32:
      return 2;
  }
  return 2;  // not a valid enumerator: the larger size, so a buffer check errs on the safe side
}

uint32_t combine_registers(const uint16_t* regs, WordOrder order) noexcept {
  uint16_t first = regs[0], second = regs[1];
  if (byte_swapped(order)) {
    first = swap_bytes(first);
    second = swap_bytes(second);
  }
  const uint16_t high = low_word_first(order) ? second : first;
  const uint16_t low = low_word_first(order) ? first : second;
  return (static_cast<uint32_t>(high) << 16) | low;
}

void split_registers(uint32_t value, WordOrder order, uint16_t* regs) noexcept {
  const auto high = static_cast<uint16_t>(value >> 16);
  const auto low = static_cast<uint16_t>(value & 0xFFFFu);
  uint16_t first = low_word_first(order) ? low : high;
  uint16_t second = low_word_first(order) ? high : low;
  if (byte_swapped(order)) {
    first = swap_bytes(first);
    second = swap_bytes(second);
  }
  regs[0] = first;
  regs[1] = second;
}

double decode_registers(const uint16_t* regs, DataFormat format, WordOrder order) noexcept {
  switch (format) {
    case DataFormat::kInt16:
      return static_cast<double>(static_cast<int16_t>(read16(regs, order)));
    case DataFormat::kUint16:
      return static_cast<double>(read16(regs, order));
    case DataFormat::kInt32:
      return static_cast<double>(static_cast<int32_t>(combine_registers(regs, order)));
    case DataFormat::kUint32:
      return static_cast<double>(combine_registers(regs, order));
    case DataFormat::kFloat32:
      return static_cast<double>(std::bit_cast<float>(combine_registers(regs, order)));
  }
  return std::numeric_limits<double>::quiet_NaN();
}

EncodeStatus encode_registers(double raw, DataFormat format, WordOrder order, uint16_t* regs) noexcept {
  if (std::isnan(raw)) return EncodeStatus::kRejected;
  switch (format) {
    case DataFormat::kInt16: {
      const auto [v, status] = to_integer<int16_t>(raw);
      write16(static_cast<uint16_t>(v), order, regs);
      return status;
    }
    case DataFormat::kUint16: {
      const auto [v, status] = to_integer<uint16_t>(raw);
      write16(v, order, regs);
      return status;
    }
    case DataFormat::kInt32: {
      const auto [v, status] = to_integer<int32_t>(raw);
      split_registers(static_cast<uint32_t>(v), order, regs);
      return status;
    }
    case DataFormat::kUint32: {
      const auto [v, status] = to_integer<uint32_t>(raw);
      split_registers(v, order, regs);
      return status;
    }
    case DataFormat::kFloat32: {
      // Converting a double beyond the float range is undefined behaviour;
      // clamp first. Values between FLT_MAX and the next (missing) float
      // step also end at FLT_MAX, as round-to-nearest would mostly do.
      constexpr double kMax = std::numeric_limits<float>::max();
      EncodeStatus status = EncodeStatus::kOk;
      if (raw > kMax) {
        raw = kMax;
        status = EncodeStatus::kSaturated;
      } else if (raw < -kMax) {
        raw = -kMax;
        status = EncodeStatus::kSaturated;
      }
      split_registers(std::bit_cast<uint32_t>(static_cast<float>(raw)), order, regs);
      return status;
    }
  }
  return EncodeStatus::kRejected;  // not a valid enumerator: write nothing
}

DataFormat data_format_from_string(std::string_view name) {
  return parse("data format", name, kFormatNames, kFormatValues);
}

WordOrder word_order_from_string(std::string_view name) {
  return parse("word order", name, kOrderNames, kOrderValues);
}

RegisterType register_type_from_string(std::string_view name) {
  return parse("register type", name, kTypeNames, kTypeValues);
}

std::span<const std::string_view> data_format_names() noexcept { return kFormatNames; }
std::span<const std::string_view> word_order_names() noexcept { return kOrderNames; }
std::span<const std::string_view> register_type_names() noexcept { return kTypeNames; }

std::string_view to_string(DataFormat format) noexcept {
  switch (format) {
    case DataFormat::kInt16: return "int16";
    case DataFormat::kUint16: return "uint16";
    case DataFormat::kInt32: return "int32";
    case DataFormat::kUint32: return "uint32";
    case DataFormat::kFloat32: return "float32";
  }
  return "?";
}

std::string_view to_string(WordOrder order) noexcept {
  switch (order) {
    case WordOrder::kHighFirst: return "high_first";
    case WordOrder::kLowFirst: return "low_first";
    case WordOrder::kHighFirstByteSwapped: return "high_first_byte_swapped";
    case WordOrder::kLowFirstByteSwapped: return "low_first_byte_swapped";
  }
  return "?";
}

std::string_view to_string(RegisterType type) noexcept {
  switch (type) {
    case RegisterType::kInputRegister: return "input";
    case RegisterType::kHoldingRegister: return "holding";
  }
  return "?";
}

ReadPlan plan_reads(std::span<const ModbusPoint> points, const ReadPlanOptions& options) {
  if (options.max_gap < 0) {
    throw std::invalid_argument("read plan: max_gap must be >= 0, got " + std::to_string(options.max_gap));
  }
  if (options.max_registers < 2 || options.max_registers > kMaxReadRegisters) {
    throw std::invalid_argument("read plan: max_registers must be in 2.." + std::to_string(kMaxReadRegisters) +
                                ", got " + std::to_string(options.max_registers));
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    const ModbusPoint& p = points[i];
    const std::string where = "point " + std::to_string(i) + ": ";
    if (p.unit_id < 0 || p.unit_id > 255) {
      throw std::invalid_argument(where + "unit id must be in 0..255, got " + std::to_string(p.unit_id));
    }
    if (p.type != RegisterType::kInputRegister && p.type != RegisterType::kHoldingRegister) {
      throw std::invalid_argument(where + "invalid register type");
    }
    switch (p.format) {
      case DataFormat::kInt16:
      case DataFormat::kUint16:
      case DataFormat::kInt32:
      case DataFormat::kUint32:
      case DataFormat::kFloat32:
        break;
      default:
        throw std::invalid_argument(where + "invalid data format");
    }
    const int last = p.address + register_count(p.format) - 1;
    if (p.address < 0 || last > 65535) {
      throw std::invalid_argument(where + "address " + std::to_string(p.address) + " (" +
                                  std::string(to_string(p.format)) + ") outside 0..65535");
    }
  }

  // Visit the points by (unit, type, address, end); stable so equal points
  // keep their input order and the plan is deterministic.
  std::vector<std::size_t> order(points.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  auto key = [&](std::size_t i) {
    const ModbusPoint& p = points[i];
    return std::tuple(p.unit_id, static_cast<int>(p.type), p.address, register_count(p.format));
  };
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return key(a) < key(b); });

  ReadPlan plan;
  plan.where.resize(points.size());
  int end = 0;  // one past the current block's last register
  for (const std::size_t i : order) {
    const ModbusPoint& p = points[i];
    const int p_end = p.address + register_count(p.format);
    bool fits = false;
    if (!plan.blocks.empty()) {
      const ReadBlock& b = plan.blocks.back();
      fits = b.unit_id == p.unit_id && b.type == p.type && p.address - end <= options.max_gap &&
             std::max(end, p_end) - b.address <= options.max_registers;
    }
    if (!fits) {
      plan.blocks.push_back(ReadBlock{p.unit_id, p.type, p.address, 0});
      end = p.address;
    }
    ReadBlock& b = plan.blocks.back();
    end = std::max(end, p_end);
    b.count = end - b.address;
    plan.where[i] = PointLocation{static_cast<int>(plan.blocks.size()) - 1, p.address - b.address};
  }
  return plan;
}

}  // namespace rigctl
