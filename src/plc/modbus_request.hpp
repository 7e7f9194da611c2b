// One Modbus TCP request (ADU = MBAP header + PDU), framed by the MBAP length field and checked
// against its function code before libmodbus's modbus_reply() sees it. Checked here so that
// modbus_reply() never takes its flushing exception path (it sleeps the response timeout and
// reads the socket dry, which would cost every client) and never reads past a short request.
// Modbus Messaging on TCP/IP Implementation Guide v1.0b, 3.1.3 (MBAP); Modbus Application
// Protocol v1.1b3, 6 (function codes) and 7 (exceptions).
#pragma once

#include <cstdint>

typedef struct _modbus modbus_t;
typedef struct _modbus_mapping_t modbus_mapping_t;

namespace pipeloc::mbtcp {

constexpr int kHeaderBytes = 7;   // transaction id, protocol id, length, unit id
constexpr int kMaxAduBytes = 260;  // MODBUS_TCP_MAX_ADU_LENGTH

// The whole ADU's size once the header's kHeaderBytes are in; -1 when the header cannot start a
// Modbus TCP request (protocol id not 0, length field outside 2..254).
int adu_bytes(const std::uint8_t* header);

// 0 when the request is well-formed for a function code the server answers, else the exception
// code to reply: 01 illegal function, 03 illegal data value (wrong length or quantity).
int request_exception(const std::uint8_t* adu, int length);

}  // namespace pipeloc::mbtcp

namespace pipeloc {

// What the server answers to one framed request: an exception for malformed requests and for
// writes outside CMD/REQ_ID, else libmodbus's reply from the map (which answers reads outside
// it with exception 02). Returns the bytes sent, -1 when the connection failed (errno set).
// Used by the server and the fuzzer.
int reply_to_request(modbus_t* ctx, modbus_mapping_t* mapping, int base, const std::uint8_t* adu,
                     int length);

}  // namespace pipeloc
