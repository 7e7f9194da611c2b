#include "plc/modbus_request.hpp"

#include <modbus/modbus.h>

#include "plc/register_map.hpp"

namespace pipeloc::mbtcp {
namespace {

int u16(const std::uint8_t* p) { return (p[0] << 8) | p[1]; }

// Function codes (Modbus Application Protocol v1.1b3, 6.1-6.17).
enum : int {
  kReadCoils = 0x01, kReadDiscrete = 0x02, kReadHolding = 0x03, kReadInput = 0x04,
  kWriteCoil = 0x05, kWriteSingle = 0x06, kWriteCoils = 0x0F, kWriteMultiple = 0x10,
  kReportServerId = 0x11, kMaskWrite = 0x16, kReadWriteMultiple = 0x17,
};
constexpr int kIllegalFunction = 1, kIllegalValue = 3;

bool in(int v, int lo, int hi) { return v >= lo && v <= hi; }

}  // namespace

int adu_bytes(const std::uint8_t* header) {
  const int length = u16(header + 4);  // unit id + PDU
  if (u16(header + 2) != 0 || !in(length, 2, kMaxAduBytes - kHeaderBytes + 1)) return -1;
  return kHeaderBytes - 1 + length;
}

int request_exception(const std::uint8_t* adu, int length) {
  const std::uint8_t* pdu = adu + kHeaderBytes;
  const int n = length - kHeaderBytes;  // PDU bytes after the function code's
  switch (pdu[0]) {
    case kReadCoils:
    case kReadDiscrete:
      return n == 5 && in(u16(pdu + 3), 1, 2000) ? 0 : kIllegalValue;
    case kReadHolding:
    case kReadInput:
      return n == 5 && in(u16(pdu + 3), 1, 125) ? 0 : kIllegalValue;
    case kWriteCoil:
    case kWriteSingle:
      return n == 5 ? 0 : kIllegalValue;
    case kWriteCoils:
      return n >= 6 && in(u16(pdu + 3), 1, 1968) && pdu[5] == (u16(pdu + 3) + 7) / 8 && n == 6 + pdu[5]
                 ? 0
                 : kIllegalValue;
    case kWriteMultiple:
      return n >= 6 && in(u16(pdu + 3), 1, 123) && pdu[5] == 2 * u16(pdu + 3) && n == 6 + pdu[5]
                 ? 0
                 : kIllegalValue;
    case kReportServerId:
      return n == 1 ? 0 : kIllegalValue;
    case kMaskWrite:
      return n == 7 ? 0 : kIllegalValue;
    case kReadWriteMultiple:
      return n >= 10 && in(u16(pdu + 3), 1, 125) && in(u16(pdu + 7), 1, 121) &&
                     pdu[9] == 2 * u16(pdu + 7) && n == 10 + pdu[9]
                 ? 0
                 : kIllegalValue;
    default:
      return kIllegalFunction;
  }
}

// The registers [first, first + count) a well-formed request writes, if it writes any.
bool written_range(const std::uint8_t* adu, int* first, int* count) {
  const std::uint8_t* pdu = adu + kHeaderBytes;
  switch (pdu[0]) {
    case kWriteSingle:
    case kMaskWrite:
      *first = u16(pdu + 1), *count = 1;
      return true;
    case kWriteMultiple:
      *first = u16(pdu + 1), *count = u16(pdu + 3);
      return true;
    case kReadWriteMultiple:
      *first = u16(pdu + 5), *count = u16(pdu + 7);
      return true;
    default:
      return false;
  }
}

}  // namespace pipeloc::mbtcp

namespace pipeloc {

int reply_to_request(modbus_t* ctx, modbus_mapping_t* mapping, int base, const std::uint8_t* adu,
                     int length) {
  if (length < mbtcp::kHeaderBytes + 1) return 0;  // unit id only: nothing to answer
  if (const int e = mbtcp::request_exception(adu, length)) return modbus_reply_exception(ctx, adu, unsigned(e));
  int first = 0, count = 0;
  if (mbtcp::written_range(adu, &first, &count) && (first < base || first + count > base + reg::kReqId + 1))
    // Only CMD and REQ_ID belong to the PLC; the rest is the service's.
    return modbus_reply_exception(ctx, adu, MODBUS_EXCEPTION_ILLEGAL_DATA_ADDRESS);
  return modbus_reply(ctx, adu, length, mapping);
}

}  // namespace pipeloc
