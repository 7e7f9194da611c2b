// 32-bit values in two 16-bit Modbus registers (DESIGN.md PLC interface). Written here rather
// than with libmodbus 3.1.6's modbus_set_float_*, which swap the bytes inside each register
// (fixed upstream in 3.1.11).
#pragma once

#include <cstdint>
#include <string>

namespace pipeloc {

// Byte order of the four bytes A B C D of a big-endian 32-bit value over two registers:
// ABCD = {AB, CD} (high word first, the default), CDAB = {CD, AB}, BADC = {BA, DC}, DCBA = {DC, BA}.
enum class WordOrder { abcd, cdab, badc, dcba };

// Throws std::invalid_argument naming the accepted spellings.
WordOrder parse_word_order(const std::string& text);
const char* word_order_name(WordOrder order);

void encode_u32(std::uint32_t value, WordOrder order, std::uint16_t out[2]);
std::uint32_t decode_u32(const std::uint16_t in[2], WordOrder order);

void encode_float(float value, WordOrder order, std::uint16_t out[2]);
float decode_float(const std::uint16_t in[2], WordOrder order);

// Scaled int32 encoding: value * scale rounded, saturated; NaN becomes the sentinel.
constexpr std::int32_t kScaledNone = INT32_MIN;
void encode_scaled(double value, double scale, WordOrder order, std::uint16_t out[2]);
double decode_scaled(const std::uint16_t in[2], double scale, WordOrder order);  // NaN for the sentinel

}  // namespace pipeloc
