#include "service/timing_log.hpp"

#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

#include "core/clock.hpp"
#include "service/cycle.hpp"

namespace pipeloc {
namespace {

double quantile_sorted(const std::vector<double>& v, double q) {
  return v.empty() ? 0.0 : v[std::size_t(q * double(v.size() - 1) + 0.5)];
}

}  // namespace

const char* status_name(reg::Status s) {
  switch (s) {
    case reg::Status::ready:
      return "READY";
    case reg::Status::busy:
      return "BUSY";
    case reg::Status::done_ok:
      return "DONE_OK";
    case reg::Status::done_none:
      return "DONE_NONE";
    case reg::Status::error:
      return "ERROR";
  }
  return "?";
}

const char* error_name(reg::Error e) {
  switch (e) {
    case reg::Error::none:
      return "none";
    case reg::Error::sensor_unavailable:
      return "sensor_unavailable";
    case reg::Error::frame_invalid:
      return "frame_invalid";
    case reg::Error::budget_exhausted:
      return "budget_exhausted";
    case reg::Error::config_model:
      return "config_model";
    case reg::Error::bad_command:
      return "bad_command";
    case reg::Error::no_further_result:
      return "no_further_result";
  }
  return "?";
}

TimingLog::TimingLog(const LogConfig& cfg, int summary_every) : cfg_(cfg), summary_every_(summary_every) {
  std::error_code ec;
  std::filesystem::create_directories(cfg.dir, ec);
  path_ = (std::filesystem::path(cfg.dir) / "timing.jsonl").string();
  file_ = std::fopen(path_.c_str(), "a");
  if (!file_)
    throw std::runtime_error("log.dir '" + cfg.dir + "': cannot write " + path_ + ": " +
                             std::strerror(errno));
  bytes_ = std::ftell(file_);
  window_.reserve(std::size_t(summary_every));
  sorted_.reserve(std::size_t(summary_every));
}

TimingLog::~TimingLog() {
  if (file_) std::fclose(file_);
}

// The file is gone (its folder deleted, the file removed or rotated away by hand) or was never
// reopened: open it again, creating the folder. Only on that path does anything allocate.
bool TimingLog::reopen_if_gone() {
  struct stat st {};
  if (file_ && ::fstat(fileno(file_), &st) == 0 && st.st_nlink > 0) return true;
  if (file_) std::fclose(file_);
  std::error_code ec;
  std::filesystem::create_directories(cfg_.dir, ec);
  file_ = std::fopen(path_.c_str(), "a");
  if (!file_) return false;
  bytes_ = std::ftell(file_);
  ++reopened_;
  spdlog::warn("timing log: {} had gone (folder deleted?); reopened", path_);
  return true;
}

void TimingLog::put(const char* line, int length) {
  if (length <= 0) return;
  length = std::min(length, int(sizeof(line_)) - 1);
  if (!reopen_if_gone()) {  // the log is lost for now, the cycle is not; said once per outage
    if (!failing_) spdlog::error("timing log: cannot open {}: {}", path_, std::strerror(errno));
    failing_ = true, ++write_errors_;
    return;
  }
  const bool ok = std::fwrite(line, 1, std::size_t(length), file_) == std::size_t(length) && std::fflush(file_) == 0;
  if (!ok) {
    if (!failing_) spdlog::error("timing log: cannot write {}: {} (disk full?)", path_, std::strerror(errno));
    failing_ = true, ++write_errors_;
    std::clearerr(file_);
    return;
  }
  if (failing_) spdlog::info("timing log: writing {} again after {} lost lines", path_, write_errors_);
  failing_ = false;
  bytes_ += length;
  if (bytes_ > long(cfg_.max_file_kb) * 1024) rotate();
}

void TimingLog::rotate() {
  std::fclose(file_);
  char from[4096], to[4096];
  for (int i = cfg_.keep_files; i >= 1; --i) {
    if (i == 1)
      std::snprintf(from, sizeof from, "%s", path_.c_str());
    else
      std::snprintf(from, sizeof from, "%s.%d", path_.c_str(), i - 1);
    std::snprintf(to, sizeof to, "%s.%d", path_.c_str(), i);
    std::rename(from, to);  // the oldest is overwritten
  }
  file_ = std::fopen(path_.c_str(), "w");
  bytes_ = 0;
}

void TimingLog::event(const char* name, const char* rest) {
  const int n = std::snprintf(line_, sizeof line_, "{\"event\":\"%s\",\"unix_ms\":%.0f%s%s}\n", name,
                              unix_ms_now(), *rest ? "," : "", rest);
  put(line_, n);
}

TimingLog::Summary TimingLog::summary() const {
  Summary s;
  sorted_.assign(window_.begin(), window_.end());
  std::sort(sorted_.begin(), sorted_.end());
  s.cycles = int(sorted_.size());
  s.p50 = quantile_sorted(sorted_, 0.50);
  s.p95 = quantile_sorted(sorted_, 0.95);
  s.p99 = quantile_sorted(sorted_, 0.99);
  s.max = sorted_.empty() ? 0.0 : sorted_.back();
  return s;
}

namespace {
// "name":n,... for every bit of Withheld ("ambiguous":n,...) or of Ambiguity ("rival":n,...), in its
// order, into a fixed buffer (no allocation per cycle).
struct CountsText {
  char text[256] = "";
  template <std::size_t N>
  CountsText(const std::array<int, N>& counts, const char* (*name)(int)) {
    int at = 0;
    for (int k = 0; k < int(N) && at < int(sizeof text); ++k)
      at += std::snprintf(text + at, sizeof text - std::size_t(at), "%s\"%s\":%d", k ? "," : "", name(k),
                          counts[std::size_t(k)]);
  }
};
// The pose presented, as the PLC reads it: {"x_mm":..,...,"rz_deg":..}, or null.
struct PoseText {
  char text[192] = "null";
  explicit PoseText(const CycleRecord& r) {
    if (!r.pose) return;
    const RobotPose& p = *r.pose;
    std::snprintf(
        text, sizeof text,
        "{\"x_mm\":%.2f,\"y_mm\":%.2f,\"z_mm\":%.2f,\"rx_deg\":%.3f,\"ry_deg\":%.3f,\"rz_deg\":%.3f}",
        p.xyz_mm[0], p.xyz_mm[1], p.xyz_mm[2], p.rxyz_deg[0], p.rxyz_deg[1], p.rxyz_deg[2]);
  }
};
}  // namespace

void TimingLog::write(const CycleRecord& r) {
  const StageTimes& t = r.stages;
  const int n = std::snprintf(
      line_, sizeof line_,
      "{\"event\":\"cycle\",\"cycle\":%llu,\"cmd\":%u,\"req_id\":%u,\"trigger_unix_ms\":%.1f,\"frame\":%llu,"
      "\"queued_ms\":%.2f,\"grab\":\"%s\",\"frame_check\":\"%s\",\"grab_ms\":%.2f,\"frame_age_ms\":%.2f,"
      "\"zbuffer_ms\":%.2f,\"normals_ms\":%.2f,"
      "\"regions_ms\":%.2f,\"axis_ms\":%.2f,\"ridge_icp_ms\":%.2f,\"refine_ms\":%.2f,\"verify_ms\":%.2f,"
      "\"locate_ms\":%.2f,\"again_ms\":%.2f,\"cycle_ms\":%.2f,\"budget_ms\":%.1f,\"budget_use\":%.3f,"
      "\"budget_exhausted\":%s,"
      "\"candidates\":%d,\"tried\":%d,\"accepted\":%d,\"count\":%d,\"unresolved\":%d,\"score\":%.4f,"
      "\"index\":%d,\"pose\":%s,\"last_pick_took_nothing\":%s,\"status\":\"%s\",\"error\":\"%s\","
      "\"withheld\":{%s},\"ambiguous_why\":{%s}}\n",
      (unsigned long long)r.cycle, unsigned(r.command), unsigned(r.req_id), r.trigger_unix_ms,
      (unsigned long long)r.frame_sequence, r.queued_ms, grab_status_name(r.grab), r.frame_check, r.grab_ms,
      r.frame_age_ms, t.zbuffer_ms, t.normals_ms, t.regions_ms, t.axis_ms, t.ridge_icp_ms, t.refine_ms,
      t.verify_ms, t.total_ms - t.again_ms, t.again_ms, r.cycle_ms, r.budget_ms,
      r.budget_ms > 0 ? r.cycle_ms / r.budget_ms : 0.0, r.budget_exhausted ? "true" : "false", r.candidates,
      r.tried, r.accepted, r.count, r.unresolved, double(r.score), r.index, PoseText(r).text,
      r.last_pick_took_nothing ? "true" : "false", status_name(r.status),
      r.cut_by_shutdown ? "shutdown" : error_name(r.error), CountsText(r.withheld, withheld_name).text,
      CountsText(r.ambiguous_why, ambiguity_name).text);
  put(line_, n);
  if (r.command != std::uint16_t(reg::Command::locate)) return;
  window_.push_back(r.cycle_ms);
  if (int(window_.size()) < summary_every_) return;
  const Summary s = summary();
  char rest[256];
  std::snprintf(rest, sizeof rest,
                "\"cycles\":%d,\"up_to_cycle\":%llu,\"cycle_ms_p50\":%.2f,\"cycle_ms_p95\":%.2f,"
                "\"cycle_ms_p99\":%.2f,\"cycle_ms_max\":%.2f",
                s.cycles, (unsigned long long)r.cycle, s.p50, s.p95, s.p99, s.max);
  event("summary", rest);
  window_.clear();
}

}  // namespace pipeloc
