// What the status page (src/status) shows of the running service. The threads that own the data
// publish into it, the page's thread copies it out: the cycle thread a fixed-size record of each
// command (no allocation, no I/O, the lock held only for a copy of a few KiB), the PLC front end
// its clients and heartbeat, and after_publish() the overlay PNG, drawn outside the cycle's time.
#pragma once

#include <cstdint>
#include <mutex>
#include <vector>

#include "plc/plc_link.hpp"
#include "plc/robot_pose.hpp"
#include "service/cycle.hpp"

namespace pipeloc {

// One command's outcome, as the page lists it.
struct StatusRow {
  double trigger_unix_ms = 0;
  std::uint16_t command = 0, req_id = 0;
  reg::Status status = reg::Status::ready;
  reg::Error error = reg::Error::none;
  int count = 0, index = 0;          // poses handed out by the last LOCATE, rank presented
  int candidates = 0, accepted = 0;  // regions, estimates (LOCATE)
  double cycle_ms = 0, frame_age_ms = 0, budget_ms = 0;
  float score = 0;
  bool budget_exhausted = false;
  const char* frame_check = "";  // static text
  std::uint64_t frame_sequence = 0, cycle = 0;
};

// A pose of the last LOCATE as the PLC gets it (robot frame), and where it is in the camera's.
struct StatusPose {
  RobotPose robot;
  std::array<double, 3> cam_xyz_mm{};
  float score = 0;
};

struct CycleSample {
  double trigger_unix_ms = 0;
  float cycle_ms = 0;
  reg::Status status = reg::Status::ready;
};

struct StatusSnapshot {
  static constexpr int kHistory = 600;  // LOCATE cycle times kept for the page's plots
  static constexpr int kRecent = 15;    // results listed
  static constexpr int kPoses = 16;     // poses of the last LOCATE listed
  static constexpr int kClients = 64;   // = the largest plc.max_clients
  // Upper bounds (s) of /metrics' cycle-time histogram buckets; +Inf is implied.
  static constexpr int kBuckets = 16;
  static constexpr double kBucketLeS[kBuckets] = {0.01,  0.02, 0.03, 0.04, 0.05, 0.06, 0.08, 0.1,
                                                  0.125, 0.15, 0.2,  0.25, 0.3,  0.5,  1,    2.5};

  // Counters since start (all commands unless named).
  std::uint64_t commands_by_type[4] = {};          // locate, next, clear_error, other
  std::uint64_t locate_by_status[5] = {};          // LOCATE results by reg::Status
  std::uint64_t errors_by_code[7] = {};            // every command's ERROR register, by reg::Error
  std::uint64_t picks = 0;                         // DONE_OK results: poses handed to the PLC (LOCATE, NEXT)
  std::uint64_t picks_took_nothing = 0;            // picks after which the bin read as before there
  std::uint64_t budget_exhausted = 0;              // LOCATEs the budget cut short
  std::uint64_t cycle_buckets[kBuckets + 1] = {};  // LOCATE cycle times, not cumulative; last: +Inf
  double cycle_sum_s = 0;
  std::uint64_t cycle_count = 0;
  // Rings, oldest first from index next (when full).
  CycleSample history[kHistory];
  int history_count = 0, history_next = 0;
  StatusRow recent[kRecent];
  int recent_count = 0, recent_next = 0;
  // The last LOCATE.
  bool has_locate = false;
  StatusRow last_locate;
  StatusPose poses[kPoses];
  int pose_count = 0;  // listed (at most kPoses of last_locate.count)
  // The PLC link, from the front end.
  std::uint64_t heartbeats = 0;
  bool healthy = true;
  int client_count = 0;
  PlcClientInfo clients[kClients];
  // The overlay the page shows.
  std::uint64_t overlay_cycle = 0;  // 0: none yet
  double overlay_unix_ms = 0;
};

class StatusBoard {
 public:
  // Cycle thread, after each command: its record and, for a LOCATE, its ranked poses.
  void publish_command(const CycleRecord& record, int index, const StatusPose* poses, int pose_count);
  // PLC front end, every heartbeat period.
  void publish_link(std::uint64_t heartbeats, bool healthy, const PlcClientInfo* clients, int count);
  // After a LOCATE's result is out: its overlay as PNG bytes (taken over by swap).
  void publish_overlay(std::vector<std::uint8_t>* png, std::uint64_t cycle);

  // The page's thread.
  void snapshot(StatusSnapshot* out) const;
  // False when no overlay was published yet.
  bool overlay(std::vector<std::uint8_t>* png, std::uint64_t* cycle) const;

 private:
  mutable std::mutex mutex_, overlay_mutex_;
  StatusSnapshot s_;
  std::vector<std::uint8_t> overlay_png_;
  std::uint64_t overlay_cycle_ = 0;
};

// Samples of the ring in time order, and the share-`q` quantile of their cycle times (0 if none).
int history_in_order(const StatusSnapshot& s, CycleSample* out);
double quantile_ms(const CycleSample* samples, int count, double q);

}  // namespace pipeloc
