// The register map of DESIGN.md (home for PLC programmers: firmware-host/REGISTERS.md once the
// server lands). Offsets are from a configurable base; 32-bit values take two registers.
#pragma once

#include <cstdint>
#include <optional>

#include "plc/encoding.hpp"
#include "plc/robot_pose.hpp"

namespace pipeloc::reg {

constexpr int kCmd = 0, kReqId = 1;  // written by the PLC
constexpr int kStatus = 10, kAckId = 11, kError = 12, kHeartbeat = 13, kCount = 14, kIndex = 15,
              kCycleMs = 16, kFrameAgeMs = 17, kCycles = 18;  // u32 at 18-19
constexpr int kPose = 20;                                     // X Y Z RX RY RZ, 2 registers each
constexpr int kScore = 32, kQuat = 34;                        // QW QX QY QZ
constexpr int kPoseEnd = 42;                                  // one past QZ
// Beyond DESIGN.md's map: what the last LOCATE saw but did not hand out, so that a PLC told
// DONE_NONE can tell a bin holding pipes it cannot pick (shake it) from one that shows none
// (refill it).
constexpr int kHeld = 42, kHeldWhy = 43, kRegions = 44;
constexpr int kSize = 45;

enum class Command : std::uint16_t { locate = 1, next = 2, clear_error = 3 };
enum class Status : std::uint16_t { ready = 0, busy = 1, done_ok = 2, done_none = 3, error = 4 };
enum class Error : std::uint16_t {
  none = 0,
  sensor_unavailable = 1,
  frame_invalid = 2,
  budget_exhausted = 3,
  config_model = 4,
  bad_command = 5,
  no_further_result = 6
};

struct Encoding {
  WordOrder order = WordOrder::abcd;
  bool scaled_int32 = false;  // 0.01 mm, 0.001 deg, score x 10000, quaternion x 10000
};

struct Result {
  Status status = Status::ready;
  Error error = Error::none;
  std::uint16_t count = 0, index = 0, cycle_ms = 0, frame_age_ms = 0;
  std::uint32_t cycles = 0;
  std::optional<RobotPose> pose;  // only read when status is done_ok
  float score = 0;
  // Of the last LOCATE that localized a frame: the poses it found but held back (not pickable),
  // the checks that held them (Withheld's bits, OR-ed), and the candidate regions (pipe-like tops)
  // it found. 0 where the LOCATE got no frame.
  std::uint16_t held = 0, held_why = 0, regions = 0;
};

// Writes ERROR .. REGIONS (12..44) of `map` (kSize registers from the base). STATUS and ACK_ID are
// left to the handshake, which writes them last. Unless the status is DONE_OK the pose, score
// and quaternion hold NaN (or the int32 sentinel), so a stale pose can never be read as new.
void write_result_block(const Result& result, const Encoding& enc, std::uint16_t* map);

// The handshake's writes, in DESIGN.md's order, on a map of kSize registers:
// start-up: everything zero, STATUS READY, pose NaN.
void write_initial(const Encoding& enc, std::uint16_t* map);
// A command was taken up: STATUS BUSY and the pose NaN (the old one is no longer current).
void write_busy(const Encoding& enc, std::uint16_t* map);
// The result: the block, then STATUS, then ACK_ID last.
void write_result(const Result& result, std::uint16_t ack_id, const Encoding& enc, std::uint16_t* map);

}  // namespace pipeloc::reg
