#include "service/status_board.hpp"

#include <algorithm>
#include <cstring>

namespace pipeloc {
namespace {

int command_slot(std::uint16_t command) { return command >= 1 && command <= 3 ? command - 1 : 3; }

StatusRow row_of(const CycleRecord& r) {
  StatusRow row;
  row.trigger_unix_ms = r.trigger_unix_ms;
  row.command = r.command;
  row.req_id = r.req_id;
  row.status = r.status;
  row.error = r.error;
  row.count = r.count;
  row.candidates = r.candidates;
  row.accepted = r.accepted;
  row.cycle_ms = r.cycle_ms;
  row.frame_age_ms = r.frame_age_ms;
  row.budget_ms = r.budget_ms;
  row.score = r.score;
  row.budget_exhausted = r.budget_exhausted;
  row.frame_check = r.frame_check;
  row.frame_sequence = r.frame_sequence;
  row.cycle = r.cycle;
  return row;
}

}  // namespace

void StatusBoard::publish_command(const CycleRecord& record, int index, const StatusPose* poses,
                                  int pose_count) {
  StatusRow row = row_of(record);
  row.index = index;
  const bool locate = record.command == std::uint16_t(reg::Command::locate);
  std::lock_guard<std::mutex> lock(mutex_);
  StatusSnapshot& s = s_;
  ++s.commands_by_type[command_slot(record.command)];
  if (std::size_t(record.error) < std::size(s.errors_by_code)) ++s.errors_by_code[std::size_t(record.error)];
  if (record.status == reg::Status::done_ok) ++s.picks;
  s.picks_took_nothing += record.last_pick_took_nothing;
  s.recent[s.recent_next] = row;
  s.recent_next = (s.recent_next + 1) % StatusSnapshot::kRecent;
  s.recent_count = std::min(s.recent_count + 1, StatusSnapshot::kRecent);
  if (!locate) return;
  if (std::size_t(record.status) < std::size(s.locate_by_status))
    ++s.locate_by_status[std::size_t(record.status)];
  s.budget_exhausted += record.budget_exhausted;
  const double cycle_s = record.cycle_ms / 1000;
  int bucket = 0;
  while (bucket < StatusSnapshot::kBuckets && cycle_s > StatusSnapshot::kBucketLeS[bucket]) ++bucket;
  ++s.cycle_buckets[bucket];
  s.cycle_sum_s += cycle_s;
  ++s.cycle_count;
  s.history[s.history_next] = {record.trigger_unix_ms, float(record.cycle_ms), record.status};
  s.history_next = (s.history_next + 1) % StatusSnapshot::kHistory;
  s.history_count = std::min(s.history_count + 1, StatusSnapshot::kHistory);
  s.has_locate = true;
  s.last_locate = row;
  s.pose_count = std::clamp(pose_count, 0, StatusSnapshot::kPoses);
  std::copy(poses, poses + s.pose_count, s.poses);
}

void StatusBoard::publish_link(std::uint64_t heartbeats, bool healthy, const PlcClientInfo* clients,
                               int count) {
  std::lock_guard<std::mutex> lock(mutex_);
  s_.heartbeats = heartbeats;
  s_.healthy = healthy;
  s_.client_count = std::clamp(count, 0, StatusSnapshot::kClients);
  std::copy(clients, clients + s_.client_count, s_.clients);
}

void StatusBoard::publish_overlay(std::vector<std::uint8_t>* png, std::uint64_t cycle) {
  {
    std::lock_guard<std::mutex> lock(overlay_mutex_);
    overlay_png_.swap(*png);
    overlay_cycle_ = cycle;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  s_.overlay_cycle = cycle;
  s_.overlay_unix_ms = unix_ms_now();
}

void StatusBoard::snapshot(StatusSnapshot* out) const {
  std::lock_guard<std::mutex> lock(mutex_);
  *out = s_;
}

bool StatusBoard::overlay(std::vector<std::uint8_t>* png, std::uint64_t* cycle) const {
  std::lock_guard<std::mutex> lock(overlay_mutex_);
  if (overlay_png_.empty()) return false;
  *png = overlay_png_;
  *cycle = overlay_cycle_;
  return true;
}

int history_in_order(const StatusSnapshot& s, CycleSample* out) {
  const int first = s.history_count < StatusSnapshot::kHistory ? 0 : s.history_next;
  for (int i = 0; i < s.history_count; ++i) out[i] = s.history[(first + i) % StatusSnapshot::kHistory];
  return s.history_count;
}

double quantile_ms(const CycleSample* samples, int count, double q) {
  if (count <= 0) return 0;
  std::vector<float> v(static_cast<std::size_t>(count));
  for (int i = 0; i < count; ++i) v[std::size_t(i)] = samples[i].cycle_ms;
  std::sort(v.begin(), v.end());
  return v[std::size_t(q * (count - 1) + 0.5)];
}

}  // namespace pipeloc
