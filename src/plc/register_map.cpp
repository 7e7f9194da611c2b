#include "plc/register_map.hpp"

#include <cmath>

namespace pipeloc::reg {
namespace {

void put(double value, double scale, const Encoding& enc, std::uint16_t* at) {
  if (enc.scaled_int32)
    encode_scaled(value, scale, enc.order, at);
  else
    encode_float(float(value), enc.order, at);
}

}  // namespace

void write_result_block(const Result& r, const Encoding& enc, std::uint16_t* map) {
  map[kError] = std::uint16_t(r.error);
  map[kCount] = r.count;
  map[kIndex] = r.index;
  map[kCycleMs] = r.cycle_ms;
  map[kFrameAgeMs] = r.frame_age_ms;
  encode_u32(r.cycles, enc.order, &map[kCycles]);
  const bool valid = r.status == Status::done_ok && r.pose.has_value();
  const double nan = std::nan("");
  for (int i = 0; i < 3; ++i) {
    put(valid ? r.pose->xyz_mm[std::size_t(i)] : nan, 100.0, enc, &map[kPose + 2 * i]);
    put(valid ? r.pose->rxyz_deg[std::size_t(i)] : nan, 1000.0, enc, &map[kPose + 6 + 2 * i]);
  }
  put(valid ? r.score : nan, 10000.0, enc, &map[kScore]);
  for (int i = 0; i < 4; ++i)
    put(valid ? r.pose->wxyz[std::size_t(i)] : nan, 10000.0, enc, &map[kQuat + 2 * i]);
  map[kHeld] = r.held;
  map[kHeldWhy] = r.held_why;
  map[kRegions] = r.regions;
}

void write_initial(const Encoding& enc, std::uint16_t* map) {
  for (int i = 0; i < kSize; ++i) map[i] = 0;
  write_result_block(Result{}, enc, map);
  map[kStatus] = std::uint16_t(Status::ready);
}

void write_busy(const Encoding& enc, std::uint16_t* map) {
  const double nan = std::nan("");
  for (int i = 0; i < 6; ++i) put(nan, i < 3 ? 100.0 : 1000.0, enc, &map[kPose + 2 * i]);
  put(nan, 10000.0, enc, &map[kScore]);
  for (int i = 0; i < 4; ++i) put(nan, 10000.0, enc, &map[kQuat + 2 * i]);
  map[kStatus] = std::uint16_t(Status::busy);
}

void write_result(const Result& result, std::uint16_t ack_id, const Encoding& enc, std::uint16_t* map) {
  write_result_block(result, enc, map);
  map[kStatus] = std::uint16_t(result.status);
  map[kAckId] = ack_id;
}

}  // namespace pipeloc::reg
