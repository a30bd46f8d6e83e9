// Register-level encoding of the Modbus DAQ's analogue channels: how a signal
// sits in one or two 16-bit registers, how to turn those registers into a raw
// number (counts, or the float the module already scaled) and back, and how a
// set of channels is read in as few requests as the protocol allows.
//
// Pure code, no I/O. decode_registers() and encode_registers() run on the
// 2.5 ms tick path: they never allocate, lock or throw. The parse helpers and
// plan_reads() are start-up code and throw std::invalid_argument.
//
// Registers here are the host-order uint16_t values libmodbus hands over
// (modbus_read_registers / modbus_read_input_registers), i.e. each register's
// two wire bytes already combined big-endian, as the Modbus spec defines.
#pragma once

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

namespace rigctl {

// Which table a channel lives in. Analogue inputs are normally input registers
// (read with FC 4); outputs are holding registers (written with FC 6/16, read
// back with FC 3). Some DAQ modules expose their inputs as holding registers.
enum class RegisterType { kInputRegister, kHoldingRegister };

enum class DataFormat {
  kInt16,    // one register, two's complement
  kUint16,   // one register
  kInt32,    // two registers, two's complement
  kUint32,   // two registers
  kFloat32,  // two registers, IEEE 754 binary32
};

// Where the four bytes A B C D of a 32-bit value (A most significant) sit in
// the two registers. Names follow libmodbus (modbus_get_float_abcd, ...).
//
// The two byte-swapped orders are not exotic: modules whose firmware copies a
// little-endian CPU word into the register map without swapping produce DCBA
// (or BADC for 16-bit-word-swapping firmwares), and several I/O-module and
// meter families document them as a "byte swap" option next to "word swap".
// They are supported so any such module can be configured without a patch.
//
// For 16-bit formats the word order is irrelevant, but the byte-swapped orders
// swap the two bytes of the register (a module that swaps bytes swaps them in
// every register), so a 16-bit value under BADC or DCBA is read as "BA".
enum class WordOrder {
  kHighFirst,             // ABCD: high word first, big-endian words; the Modbus convention
  kLowFirst,              // CDAB: low word first ("word swap"), big-endian words
  kHighFirstByteSwapped,  // BADC: high word first, bytes swapped inside each word
  kLowFirstByteSwapped,   // DCBA: fully little-endian
};

// Number of 16-bit registers the format occupies: 1 or 2.
int register_count(DataFormat format) noexcept;

// Combines two registers into the 32-bit pattern ABCD according to `order`,
// and the reverse. Exposed for the simulated DAQ (e.g. to inject a NaN float
// pattern) and for tests.
uint32_t combine_registers(const uint16_t* regs, WordOrder order) noexcept;
void split_registers(uint32_t value, WordOrder order, uint16_t* regs) noexcept;

// The raw value held in register_count(format) registers starting at regs[0]:
// integer counts exactly as a double, or the float32 widened to double.
// A float32 NaN or infinity is returned as such: the caller marks the input
// invalid (Sample::status) rather than the codec inventing a number.
double decode_registers(const uint16_t* regs, DataFormat format, WordOrder order) noexcept;

enum class EncodeStatus {
  kOk,         // written; integers rounded to nearest (ties away from zero)
  kSaturated,  // written, but the value was beyond the format's range and was clamped to its end
  kRejected,   // NOT written: the value was NaN; registers left untouched
};

// Writes `raw` into register_count(format) registers starting at regs[0].
//
// * Integers are rounded to nearest (std::round: ties away from zero, the
//   same whatever the FPU rounding mode) and saturated to the format's range,
//   never wrapped: 40000 as int16 is 32767, -1 as uint16 is 0, +-inf are the
//   ends of the range.
// * float32: values beyond +-FLT_MAX (including +-inf) become +-FLT_MAX, so a
//   non-finite number never reaches a device; others round to nearest float.
// * NaN is rejected for every format, with nothing written. There is no safe
//   register value the codec could choose: 0 counts is full negative current
//   on a unipolar (uint16) amplifier input, and a valve's null is generally
//   not 0 counts. The caller must write its own safe value (the calibrated
//   null) and treat the NaN as a fault; [[nodiscard]] makes it look.
[[nodiscard]] EncodeStatus encode_registers(double raw, DataFormat format, WordOrder order,
                                            uint16_t* regs) noexcept;

// Config-string parsing. Names are lower case and exact; an unknown name
// throws std::invalid_argument whose message lists the accepted names.
//   data format:   int16 uint16 int32 uint32 float32
//   word order:    high_first | abcd, low_first | cdab,
//                  high_first_byte_swapped | badc, low_first_byte_swapped | dcba
//   register type: input, holding
DataFormat data_format_from_string(std::string_view name);
WordOrder word_order_from_string(std::string_view name);
RegisterType register_type_from_string(std::string_view name);

// Every accepted name, for the config loader's "expected one of" lists.
std::span<const std::string_view> data_format_names() noexcept;
std::span<const std::string_view> word_order_names() noexcept;
std::span<const std::string_view> register_type_names() noexcept;

// Canonical names (the first spelling above), for logs and messages.
std::string_view to_string(DataFormat format) noexcept;
std::string_view to_string(WordOrder order) noexcept;
std::string_view to_string(RegisterType type) noexcept;

// ---------------------------------------------------------------------------
// Batched reads

// Where one channel lives on the bus. `address` is the 0-based protocol
// address (what libmodbus takes), not a 30001/40001-style reference number.
struct ModbusPoint {
  int unit_id = 1;  // 0..255 (RTU slaves are 1..247; TCP gateways may use 0 or 255)
  RegisterType type = RegisterType::kInputRegister;
  int address = 0;  // 0..65535, and the point's last register must be <= 65535
  DataFormat format = DataFormat::kInt16;
  WordOrder order = WordOrder::kHighFirst;
};

// The largest read of FC 3 / FC 4 (Modbus application protocol v1.1b3, 6.3/6.4).
inline constexpr int kMaxReadRegisters = 125;

struct ReadPlanOptions {
  // Unused registers between two channels that may be read along with them
  // rather than opening a new request. A register costs 2 bytes of response
  // (~0.17 ms at 115200 baud RTU, nothing noticeable on TCP) while a request
  // costs a full round trip, so small gaps are worth reading. Set 0 for a
  // module that answers "illegal data address" for registers it lacks.
  int max_gap = 4;
  // Registers per request, 2..kMaxReadRegisters (2 so a 32-bit point fits).
  int max_registers = kMaxReadRegisters;
};

// One read request: `count` registers from `address` of one unit and table.
struct ReadBlock {
  int unit_id = 0;
  RegisterType type = RegisterType::kInputRegister;
  int address = 0;
  int count = 0;
};

// Where a point's registers land: block `block`, starting `offset` registers
// into that block's buffer.
struct PointLocation {
  int block = 0;
  int offset = 0;
};

struct ReadPlan {
  std::vector<ReadBlock> blocks;     // sorted by unit id, then type (input, holding), then address
  std::vector<PointLocation> where;  // one per input point, in the input order
};

// Groups the points into contiguous read blocks, greedily in address order
// (which gives the fewest blocks under these rules), one (unit id, register
// type) per block, at most options.max_registers each,
// bridging gaps of up to options.max_gap registers. A point is never split
// across blocks. Points may overlap or repeat (e.g. one register read both as
// int16 and uint16); they then share registers. Deterministic. Throws
// std::invalid_argument for bad options or a point out of range, naming the
// point's index.
ReadPlan plan_reads(std::span<const ModbusPoint> points, const ReadPlanOptions& options = {});

}  // namespace rigctl
