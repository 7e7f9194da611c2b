// What one cycle of the service did, for the PLC registers and the timing log.
#pragma once

#include <array>
#include <cstdint>
#include <optional>

#include "locate/locator.hpp"
#include "plc/register_map.hpp"
#include "plc/robot_pose.hpp"
#include "service/frame_source.hpp"

namespace pipeloc {

// Adds 1 to counts[k] for each of its bits k set (Withheld's or Ambiguity's).
template <std::size_t N>
void count_bits(unsigned bits, std::array<int, N>* counts) {
  for (std::size_t k = 0; k < N; ++k) (*counts)[k] += int((bits >> k) & 1u);
}

struct CycleRecord {
  std::uint64_t cycle = 0;  // LOCATE cycles so far (this one included)
  std::uint16_t command = 0, req_id = 0;
  double trigger_unix_ms = 0;  // wall clock at the trigger
  double queued_ms = 0;        // trigger to the start of the cycle (waiting behind another command)
  double grab_ms = 0;          // trigger to frame in hand
  double frame_age_ms = 0;     // frame capture to result
  StageTimes stages;           // of the localizer (again_ms: its second searches, after the result)
  double cycle_ms = 0;         // trigger to result
  double budget_ms = 0;
  GrabStatus grab = GrabStatus::ok;
  const char* frame_check = "";  // which check a frame_invalid frame failed (static text)
  int candidates = 0, tried = 0, accepted = 0;  // regions, regions worked, estimates
  int count = 0;                                // poses handed out (pickable, ranked)
  int unresolved = 0;  // estimates pickable but for the tube's relief against the noise
  // Estimates not pickable, by the checks they fail (Withheld's bits; one may fail several).
  std::array<int, kWithheldKinds> withheld{};
  // ... of those ambiguous, why (Ambiguity's bits; one may have several reasons).
  std::array<int, kAmbiguityKinds> ambiguous_why{};
  float score = 0;                              // of the pose presented
  // The pose presented (DONE_OK only): its rank, and what the PLC reads in the registers.
  int index = -1;
  std::optional<RobotPose> pose;
  // The pose presented before this LOCATE took nothing: where it lay, the bin reads as before.
  bool last_pick_took_nothing = false;
  bool budget_exhausted = false;
  bool cut_by_shutdown = false;  // stopped by SIGTERM/SIGINT/SIGHUP, not by the budget
  std::uint64_t frame_sequence = 0;
  reg::Status status = reg::Status::ready;
  reg::Error error = reg::Error::none;
};

const char* status_name(reg::Status s);
const char* error_name(reg::Error e);

}  // namespace pipeloc
