#include "plc/encoding.hpp"

#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace pipeloc {

WordOrder parse_word_order(const std::string& t) {
  if (t == "ABCD") return WordOrder::abcd;
  if (t == "CDAB") return WordOrder::cdab;
  if (t == "BADC") return WordOrder::badc;
  if (t == "DCBA") return WordOrder::dcba;
  throw std::invalid_argument("word order '" + t + "': expected ABCD, CDAB, BADC or DCBA");
}

const char* word_order_name(WordOrder o) {
  switch (o) {
    case WordOrder::abcd:
      return "ABCD";
    case WordOrder::cdab:
      return "CDAB";
    case WordOrder::badc:
      return "BADC";
    case WordOrder::dcba:
      return "DCBA";
  }
  return "?";
}

namespace {
std::uint16_t swap_bytes(std::uint16_t v) { return std::uint16_t((v << 8) | (v >> 8)); }
}  // namespace

void encode_u32(std::uint32_t v, WordOrder order, std::uint16_t out[2]) {
  const std::uint16_t hi = std::uint16_t(v >> 16), lo = std::uint16_t(v & 0xffff);
  switch (order) {
    case WordOrder::abcd:
      out[0] = hi, out[1] = lo;
      break;
    case WordOrder::cdab:
      out[0] = lo, out[1] = hi;
      break;
    case WordOrder::badc:
      out[0] = swap_bytes(hi), out[1] = swap_bytes(lo);
      break;
    case WordOrder::dcba:
      out[0] = swap_bytes(lo), out[1] = swap_bytes(hi);
      break;
  }
}

std::uint32_t decode_u32(const std::uint16_t in[2], WordOrder order) {
  std::uint16_t hi = 0, lo = 0;
  switch (order) {
    case WordOrder::abcd:
      hi = in[0], lo = in[1];
      break;
    case WordOrder::cdab:
      lo = in[0], hi = in[1];
      break;
    case WordOrder::badc:
      hi = swap_bytes(in[0]), lo = swap_bytes(in[1]);
      break;
    case WordOrder::dcba:
      lo = swap_bytes(in[0]), hi = swap_bytes(in[1]);
      break;
  }
  return (std::uint32_t(hi) << 16) | lo;
}

void encode_float(float value, WordOrder order, std::uint16_t out[2]) {
  std::uint32_t bits;
  std::memcpy(&bits, &value, 4);
  encode_u32(bits, order, out);
}

float decode_float(const std::uint16_t in[2], WordOrder order) {
  const std::uint32_t bits = decode_u32(in, order);
  float value;
  std::memcpy(&value, &bits, 4);
  return value;
}

void encode_scaled(double value, double scale, WordOrder order, std::uint16_t out[2]) {
  std::int32_t v = kScaledNone;
  if (std::isfinite(value)) {
    // The sentinel is kept for "no value": saturate one above it.
    const double s = std::round(value * scale);
    v = s >= double(std::numeric_limits<std::int32_t>::max()) ? std::numeric_limits<std::int32_t>::max()
        : s <= double(kScaledNone + 1)                        ? kScaledNone + 1
                                                              : std::int32_t(s);
  }
  encode_u32(std::uint32_t(v), order, out);
}

double decode_scaled(const std::uint16_t in[2], double scale, WordOrder order) {
  const std::int32_t v = std::int32_t(decode_u32(in, order));
  return v == kScaledNone ? std::nan("") : double(v) / scale;
}

}  // namespace pipeloc
