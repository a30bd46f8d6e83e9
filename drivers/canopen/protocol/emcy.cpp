#include "drivers/canopen/protocol/emcy.hpp"

#include "drivers/canopen/protocol/cob_id.hpp"

namespace rigctl::canopen {

Malformed decode_emcy(const CanFrame& frame, Emcy& out) {
  CobInfo info;
  if (const Malformed m = check_frame_for(frame, Function::kEmcy, info); m != Malformed::kNone) return m;
  out.node = info.node;
  out.error_code = get_u16le(&frame.data[0]);
  out.error_register = frame.data[2];
  for (std::size_t i = 0; i < 5; ++i) out.manufacturer[i] = frame.data[3 + i];
  return Malformed::kNone;
}

CanFrame encode_emcy(const Emcy& e) {
  CanFrame f;
  f.can_id = kCobEmcyBase + (e.node & 0x7F);
  f.len = 8;
  put_u16le(&f.data[0], e.error_code);
  f.data[2] = e.error_register;
  for (std::size_t i = 0; i < 5; ++i) f.data[3 + i] = e.manufacturer[i];
  return f;
}

const char* emcy_code_text(uint16_t code) {
  switch (code) {
    case 0x0000: return "error reset or no error";
    case 0x1000: return "generic error";
    case 0x2000: return "current";
    case 0x2100: return "current, device input side";
    case 0x2200: return "current inside the device";
    case 0x2300: return "current, device output side";
    case 0x3000: return "voltage";
    case 0x3100: return "mains voltage";
    case 0x3200: return "voltage inside the device";
    case 0x3300: return "output voltage";
    case 0x4000: return "temperature";
    case 0x4100: return "ambient temperature";
    case 0x4200: return "device temperature";
    case 0x5000: return "device hardware";
    case 0x6000: return "device software";
    case 0x6100: return "internal software";
    case 0x6200: return "user software";
    case 0x6300: return "data set";
    case 0x7000: return "additional modules";
    case 0x8000: return "monitoring";
    case 0x8100: return "communication";
    case 0x8110: return "CAN overrun (objects lost)";
    case 0x8120: return "CAN in error passive mode";
    case 0x8130: return "life guard error or heartbeat error";
    case 0x8140: return "recovered from bus off";
    case 0x8150: return "CAN-ID collision";
    case 0x8200: return "protocol error";
    case 0x8210: return "PDO not processed due to length error";
    case 0x8220: return "PDO length exceeded";
    case 0x8230: return "DAM MPDO not processed, destination object not available";
    case 0x8240: return "unexpected SYNC data length";
    case 0x8250: return "RPDO timeout";
    case 0x9000: return "external error";
    case 0xF000: return "additional functions";
    case 0xFF00: return "device specific";
    default: break;
  }
  switch (code >> 12) {
    case 0x0: return "error reset or no error";
    case 0x1: return "generic error";
    case 0x2: return "current";
    case 0x3: return "voltage";
    case 0x4: return "temperature";
    case 0x5: return "device hardware";
    case 0x6: return "device software";
    case 0x7: return "additional modules";
    case 0x8:
      if ((code & 0xFF00) == 0x8100) return "communication";
      if ((code & 0xFF00) == 0x8200) return "protocol error";
      return "monitoring";
    case 0x9: return "external error";
    case 0xF:
      if ((code & 0xFF00) == 0xF000) return "additional functions";
      if ((code & 0xFF00) == 0xFF00) return "device specific";
      return "reserved";
    default: return "reserved";
  }
}

}  // namespace rigctl::canopen
