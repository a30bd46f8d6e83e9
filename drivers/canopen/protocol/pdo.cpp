#include "drivers/canopen/protocol/pdo.hpp"

#include <cmath>

namespace rigctl::canopen {

int64_t pdo_type_min(PdoType t) {
  switch (t) {
    case PdoType::kI8: return INT8_MIN;
    case PdoType::kI16: return INT16_MIN;
    case PdoType::kI32: return INT32_MIN;
    default: return 0;
  }
}

int64_t pdo_type_max(PdoType t) {
  switch (t) {
    case PdoType::kU8: return UINT8_MAX;
    case PdoType::kI8: return INT8_MAX;
    case PdoType::kU16: return UINT16_MAX;
    case PdoType::kI16: return INT16_MAX;
    case PdoType::kU32: return UINT32_MAX;
    case PdoType::kI32: return INT32_MAX;
  }
  return 0;
}

bool PdoMapping::add(const PdoEntry& e) {
  const unsigned bits = pdo_type_bits(e.type);
  if (count_ == kMaxEntries || bits == 0 || bits_ + bits > 64) return false;
  if (!std::isfinite(e.scale) || e.scale == 0.0) return false;
  entries_[count_++] = e;
  bits_ += bits;
  return true;
}

namespace {

void put_raw(uint8_t* p, unsigned bytes, int64_t raw) {
  const auto u = static_cast<uint64_t>(raw);
  for (unsigned i = 0; i < bytes; ++i) p[i] = static_cast<uint8_t>(u >> (8 * i));
}

int64_t get_raw(const uint8_t* p, PdoType t) {
  const unsigned bytes = pdo_type_bits(t) / 8;
  uint64_t u = 0;
  for (unsigned i = 0; i < bytes; ++i) u |= static_cast<uint64_t>(p[i]) << (8 * i);
  switch (t) {
    case PdoType::kI8: return static_cast<int8_t>(u);
    case PdoType::kI16: return static_cast<int16_t>(u);
    case PdoType::kI32: return static_cast<int32_t>(u);
    default: return static_cast<int64_t>(u);
  }
}

void start_frame(const PdoMapping& m, uint32_t cob_id, CanFrame& out) {
  out = CanFrame{};
  out.can_id = cob_id & kCanSffMask;
  out.len = m.byte_length();
}

}  // namespace

PdoEncodeResult encode_pdo_raw(const PdoMapping& m, uint32_t cob_id, std::span<const int64_t> raw, CanFrame& out) {
  PdoEncodeResult r;
  if (raw.size() != m.size()) return r;
  start_frame(m, cob_id, out);
  unsigned pos = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const PdoEntry& e = m[i];
    int64_t v = raw[i];
    if (v < pdo_type_min(e.type)) {
      v = pdo_type_min(e.type);
      ++r.clamped;
    } else if (v > pdo_type_max(e.type)) {
      v = pdo_type_max(e.type);
      ++r.clamped;
    }
    const unsigned bytes = pdo_type_bits(e.type) / 8;
    put_raw(&out.data[pos], bytes, v);
    pos += bytes;
  }
  r.ok = true;
  return r;
}

PdoEncodeResult encode_pdo(const PdoMapping& m, uint32_t cob_id, std::span<const double> values, CanFrame& out) {
  PdoEncodeResult r;
  if (values.size() != m.size()) return r;
  std::array<int64_t, PdoMapping::kMaxEntries> raw{};
  uint8_t clamped = 0;
  for (std::size_t i = 0; i < m.size(); ++i) {
    const PdoEntry& e = m[i];
    const double q = values[i] / e.scale;
    const auto lo = static_cast<double>(pdo_type_min(e.type));
    const auto hi = static_cast<double>(pdo_type_max(e.type));
    if (std::isnan(q)) {
      raw[i] = 0;
      ++clamped;
    } else if (q <= lo - 0.5) {
      raw[i] = pdo_type_min(e.type);
      ++clamped;
    } else if (q >= hi + 0.5) {
      raw[i] = pdo_type_max(e.type);
      ++clamped;
    } else {
      raw[i] = std::llround(q);  // within [lo - 0.5, hi + 0.5): rounds into range
      if (raw[i] < pdo_type_min(e.type)) raw[i] = pdo_type_min(e.type);
      if (raw[i] > pdo_type_max(e.type)) raw[i] = pdo_type_max(e.type);
    }
  }
  r = encode_pdo_raw(m, cob_id, std::span<const int64_t>(raw.data(), m.size()), out);
  r.clamped = static_cast<uint8_t>(r.clamped + clamped);
  return r;
}

Malformed decode_pdo_raw(const PdoMapping& m, const CanFrame& frame, std::span<int64_t> out) {
  if (!frame.is_standard_data()) return Malformed::kNotDataFrame;
  if (frame.len != m.byte_length()) return Malformed::kBadPdoLength;
  unsigned pos = 0;
  for (std::size_t i = 0; i < m.size() && i < out.size(); ++i) {
    out[i] = get_raw(&frame.data[pos], m[i].type);
    pos += pdo_type_bits(m[i].type) / 8U;
  }
  return Malformed::kNone;
}

Malformed decode_pdo(const PdoMapping& m, const CanFrame& frame, std::span<double> out) {
  std::array<int64_t, PdoMapping::kMaxEntries> raw{};
  const Malformed r = decode_pdo_raw(m, frame, std::span<int64_t>(raw.data(), m.size()));
  if (r != Malformed::kNone) return r;
  for (std::size_t i = 0; i < m.size() && i < out.size(); ++i) out[i] = static_cast<double>(raw[i]) * m[i].scale;
  return Malformed::kNone;
}

}  // namespace rigctl::canopen
