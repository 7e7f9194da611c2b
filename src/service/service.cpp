#include "service/service.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <vector>

#include "core/clock.hpp"
#include "io/bop.hpp"
#include "io/json_file.hpp"
#include "io/png.hpp"
#include "locate/thresholds.hpp"
#include "model/make_pipe.hpp"
#include "report/locate_overlay.hpp"
#include "sim/sensor.hpp"

namespace pipeloc {
namespace {

std::uint16_t clamp_u16(double v) { return std::uint16_t(std::clamp(std::lround(v), 0L, 65535L)); }

}  // namespace

PipeModel load_config_model(const AppConfig& cfg) {
  if (!cfg.model.stl.empty()) return load_pipe_model(cfg.model.stl);
  if (!cfg.model.preset.empty())
    return derive_pipe_model(make_pipe(pipe_preset(cfg.model.preset)), "preset " + cfg.model.preset);
  throw ConfigError("config '" + cfg.path +
                    "': model: expected model.stl (the pipe's STL, mm) or model.preset");
}

Pose config_robot_from_camera(const PlcConfig& plc) {
  return plc.robot_from_camera.size() == 16 ? pose_from_matrix_rowmajor(plc.robot_from_camera.data())
                                            : Pose::Identity();
}

Pose config_grasp(const ModelConfig& m, EulerConvention euler) {
  Pose g = Pose::Identity();
  g.linear() = rotation_from_euler_deg(m.grasp_rxyz_deg, euler);
  g.translation() = Eigen::Vector3d(m.grasp_xyz_mm[0], m.grasp_xyz_mm[1], m.grasp_xyz_mm[2]);
  return g;
}

Service::Service(const AppConfig& cfg, const PipeModel& model, std::unique_ptr<FrameSource> source)
    : cfg_(cfg),
      source_(std::move(source)),
      locator_(model, cfg.locate, source_->intrinsics()),
      log_(cfg.log, cfg.service.summary_every),
      robot_from_camera_(config_robot_from_camera(cfg.plc)),
      grasp_(config_grasp(cfg.model, cfg.plc.euler)) {
  const Intrinsics& k = source_->intrinsics();
  frame_.depth_mm.resize(k.width, k.height, 0.0f);
  frame_.camera.intrinsics = k;
  if (cfg.log.took_nothing_frames > 0) held_pick_.frame = frame_;
  ranked_.reserve(std::size_t(cfg.locate.result_cap()));
}

const Pose* Service::presented() const {
  if (result_.status != reg::Status::done_ok || index_ < 0) return nullptr;
  return &ranked_[std::size_t(index_)].model_to_cam;
}

void Service::present(int index) {
  index_ = index;
  handed_out_ = index;
  const Ranked& r = ranked_[std::size_t(index)];
  result_.status = reg::Status::done_ok;
  result_.error = reg::Error::none;
  result_.index = std::uint16_t(index);
  result_.pose = r.robot;
  result_.score = r.score;
  pick_pending_ = true;
}

const reg::Result& Service::run(std::uint16_t command, std::uint16_t req_id, Clock::time_point trigger) {
  const double unix_ms = unix_ms_now() - ms_since(trigger);
  record_ = CycleRecord{};
  record_.command = command;
  record_.req_id = req_id;
  record_.trigger_unix_ms = unix_ms;
  record_.budget_ms = cfg_.service.budget_ms;
  result_.pose.reset();
  result_.score = 0;
  switch (command) {
    case std::uint16_t(reg::Command::locate):
      locate(trigger);
      break;
    case std::uint16_t(reg::Command::next):
      if (index_ >= 0 && index_ + 1 < int(ranked_.size())) {
        present(index_ + 1);
      } else {
        index_ = int(ranked_.size());  // past the end: NEXT keeps answering "no further result"
        result_.status = reg::Status::error;
        result_.error = reg::Error::no_further_result;
      }
      break;
    case std::uint16_t(reg::Command::clear_error):
      // Only the error goes: the poses of the last LOCATE stay, and NEXT presents the next one
      // (a PLC clears a fault of its own, e.g. a failed grip, and goes on with the same frame).
      result_.status = reg::Status::ready;
      result_.error = reg::Error::none;
      break;
    default:
      result_.status = reg::Status::error;
      result_.error = reg::Error::bad_command;
      break;
  }
  result_.cycles = cycles_;
  record_.cycle = cycles_;
  record_.status = result_.status;
  record_.error = result_.error;
  record_.count = int(ranked_.size());
  record_.score = result_.status == reg::Status::done_ok ? result_.score : 0.0f;
  if (result_.status == reg::Status::done_ok) record_.index = result_.index, record_.pose = result_.pose;
  record_.cycle_ms = ms_between(trigger, Clock::now());
  if (command != std::uint16_t(reg::Command::locate)) record_.frame_age_ms = 0;
  return result_;
}

void Service::locate(Clock::time_point trigger) {
  ++cycles_;
  // The pose presented last, on the frame it was found in: the robot has been there since.
  const bool judge_picks = cfg_.service.withhold_unchanged_picks || cfg_.log.took_nothing_frames > 0;
  if (judge_picks && handed_out_ >= 0)
    tried_.handed_out(ranked_[std::size_t(handed_out_)].model_to_cam, frame_.depth_mm,
                      frame_.camera.intrinsics, locator_.locator_model());
  handed_out_ = -1;
  ranked_.clear();
  index_ = -1;
  // The budget counts from when the cycle starts: a LOCATE queued behind another command (REQ_ID
  // changed while BUSY) gets all of it. The frame is still one taken after the PLC's trigger.
  const Clock::time_point started = Clock::now();
  record_.queued_ms = ms_between(trigger, started);
  const Clock::time_point deadline = started + ms_duration(cfg_.service.budget_ms);

  GrabStatus grab = source_->grab(trigger, deadline, &frame_);
  record_.frame_check = grab == GrabStatus::frame_invalid ? "rejected by the source" : "";
  // A frame from before the trigger is never localized: it could show a pipe already picked.
  if (grab == GrabStatus::ok && frame_.captured <= trigger)
    grab = GrabStatus::frame_invalid, record_.frame_check = "taken before the trigger";
  if (grab == GrabStatus::ok)
    grab = check_frame(frame_.depth_mm, source_->intrinsics(), kMinValidDepthShare, &record_.frame_check);
  const Clock::time_point grabbed = Clock::now();
  record_.grab = grab;
  record_.grab_ms = ms_between(trigger, grabbed);
  record_.frame_sequence = frame_.sequence;
  result_.held = result_.held_why = result_.regions = 0;
  if (grab != GrabStatus::ok) {
    result_.status = reg::Status::error;
    result_.error =
        grab == GrabStatus::sensor_unavailable ? reg::Error::sensor_unavailable : reg::Error::frame_invalid;
  } else {
    // Where the robot went and the bin reads as before, that pose is not handed out again.
    record_.last_pick_took_nothing = tried_.next_frame(frame_.depth_mm, locator_.locator_model().tube_d_mm);
    held_pick_.took_nothing = record_.last_pick_took_nothing && held_pick_.held;
    locator_.set_tried(tried_.poses(), cfg_.service.withhold_unchanged_picks ? tried_.size() : 0);
    // The localizer stops taking up candidates a little before the deadline, so that what is
    // in flight and the publishing still fit the budget.
    const auto margin = ms_duration(std::min(5.0, 0.1 * cfg_.service.budget_ms));
    const LocateOutput& out = locator_.locate_to_pick(frame_.depth_mm, frame_.camera, deadline - margin);
    // The PLC's poses in the order they are handed out: the first is the pick.
    out.for_each_handed_out([&](int i) {
      if (int(ranked_.size()) >= cfg_.locate.result_cap()) return false;
      const PipeEstimate& e = out.estimates[std::size_t(i)];
      Ranked r;
      r.model_to_cam = e.model_to_cam;
      r.robot = to_robot(e.model_to_cam, robot_from_camera_, grasp_, cfg_.plc.euler);
      r.score = e.score;
      ranked_.push_back(r);
      return true;
    });
    record_.stages = out.times;
    record_.candidates = int(out.traces.size());
    for (const CandidateTrace& t : out.traces) record_.tried += t.outcome != CandidateOutcome::budget;
    record_.accepted = int(out.estimates.size());
    // What it saw and did not hand out, for the PLC: a DONE_NONE with poses held back or regions
    // found is a bin with pipes the cell cannot pick as they lie; one with neither shows none.
    for (const PipeEstimate& e : out.estimates) {
      count_bits(e.withheld, &record_.withheld);
      count_bits(e.ambiguous_why, &record_.ambiguous_why);
      if (e.withheld != 0 && result_.held < 0xFFFF) ++result_.held;
      result_.held_why = std::uint16_t(result_.held_why | e.withheld);
    }
    result_.regions = clamp_u16(double(record_.candidates));
    record_.cut_by_shutdown = out.budget_exhausted && cancel_ && cancel_->load();
    record_.budget_exhausted = out.budget_exhausted && !record_.cut_by_shutdown;
    note_unresolved(out);
    if (!ranked_.empty()) {
      present(0);
    } else if (out.budget_exhausted) {
      result_.status = reg::Status::error;
      result_.error = reg::Error::budget_exhausted;
    } else {
      result_.status = reg::Status::done_none;
      result_.error = reg::Error::none;
    }
  }
  const Clock::time_point done = Clock::now();
  result_.count = std::uint16_t(ranked_.size());
  if (ranked_.empty()) result_.index = 0;
  result_.cycle_ms = clamp_u16(ms_between(trigger, done));
  record_.frame_age_ms = grab == GrabStatus::ok ? ms_between(frame_.captured, done) : 0.0;
  result_.frame_age_ms = clamp_u16(record_.frame_age_ms);
}

void Service::search_again(const std::atomic<bool>* interrupt) {
  if (record_.command != std::uint16_t(reg::Command::locate) || record_.grab != GrabStatus::ok) return;
  const LocateOutput& out = locator_.search_again(interrupt);
  record_.stages = out.times;
  record_.accepted = int(out.estimates.size());
}

void Service::publish_status() {
  if (!board_) return;
  StatusPose poses[StatusSnapshot::kPoses];
  int n = 0;
  if (record_.command == std::uint16_t(reg::Command::locate))
    for (; n < StatusSnapshot::kPoses && n < int(ranked_.size()); ++n) {
      const Ranked& r = ranked_[std::size_t(n)];
      poses[n].robot = r.robot;
      poses[n].score = r.score;
      const Eigen::Vector3d t = r.model_to_cam.translation();
      poses[n].cam_xyz_mm = {t.x(), t.y(), t.z()};
    }
  board_->publish_command(record_, result_.index, poses, n);
}

// A cell that stands still because its sensor does not resolve the pipe (pick_min_relief_sigmas)
// says so, with what would change it: the first such LOCATE after a pick, then every 100th.
void Service::note_unresolved(const LocateOutput& out) {
  unresolved_ = Unresolved{};
  for (const PipeEstimate& e : out.estimates) {
    record_.unresolved += e.unresolved;
    if (e.unresolved && e.relief_sigmas > unresolved_.relief_sigmas) {
      unresolved_.relief_sigmas = e.relief_sigmas;
      unresolved_.depth_mm = float(e.model_to_cam.translation().norm());
    }
  }
  if (!ranked_.empty()) unresolved_cycles_ = 0;
  if (!ranked_.empty() || out.budget_exhausted) unresolved_.relief_sigmas = -1;  // nothing to warn of
  unresolved_.noise_mm = float(locator_.config().frame_noise_mm);
  unresolved_.noise_measured = out.noise.samples >= kMinNoiseSamples;
}

void Service::warn_unresolved() {
  if (unresolved_.relief_sigmas < 0) return;
  const Unresolved u = unresolved_;
  unresolved_ = Unresolved{};  // once per LOCATE (a NEXT after it publishes too)
  if (unresolved_cycles_++ % 100 != 0) return;
  const LocateConfig::ReliefBound bound =
      locator_.config().min_relief(locator_.locator_model().slides_as_straight_tube());
  spdlog::warn(
      "LOCATE {}: DONE_NONE, though a pipe was found {:.0f} mm from the camera: the sensor does not resolve "
      "its {:.1f} mm tube there (relief {:.1f} sigmas of the depth noise, {:.1f} mm {}; [locate] "
      "{} {:.1f}): mount the camera nearer or use a sensor with less noise ({} such "
      "LOCATEs since the last pick)",
      cycles_, u.depth_mm, locator_.locator_model().tube_d_mm, u.relief_sigmas, u.noise_mm,
      u.noise_measured ? "measured" : "assumed: too few readings to measure", bound.key, bound.sigmas,
      unresolved_cycles_);
}

// The integrator's picture of the last LOCATE: drawn once when the log, the status page or the
// no-pick record wants it.
void Service::write_overlays() {
  if (record_.command != std::uint16_t(reg::Command::locate) || record_.grab != GrabStatus::ok) return;
  auto due = [this](int every) { return every > 0 && cycles_ % std::uint32_t(every) == 0; };
  const bool to_file = due(cfg_.log.overlay_every);
  const bool to_board = board_ && cfg_.status.enabled && due(cfg_.status.overlay_every);
  const bool no_pick = cfg_.log.no_pick_frames > 0 && ranked_.empty() && !record_.cut_by_shutdown;
  if (!to_file && !to_board && !no_pick) return;
  try {
    const Image<Rgb> overlay = draw_locate_overlay(locator_, frame_.depth_mm, frame_.camera);
    if (no_pick) keep_no_pick_frame(overlay);
    if (to_file) {
      // Written aside and renamed, so a viewer never catches half a file.
      const std::string path = (std::filesystem::path(cfg_.log.dir) / "overlay-latest.png").string();
      write_rgb_png(path + ".tmp", overlay);
      std::filesystem::rename(path + ".tmp", path);
    }
    if (to_board) {
      std::vector<std::uint8_t> png = encode_rgb_png(overlay);
      board_->publish_overlay(&png, record_.cycle);
    }
  } catch (const std::exception& e) {
    spdlog::warn("overlay: {}", e.what());
  }
}

namespace {

// The maintainer's kept frames (no-pick/, took-nothing/): a frame's files are named by its folder,
// the UTC time and the LOCATE cycle, so they sort oldest first, and share the part after the base.
// Writes the depth and the camera (located again with `pipeloc locate --depth F-depth.png --camera
// F-camera.json`); returns the base for the other parts.
std::string keep_frame(const std::filesystem::path& dir, std::uint32_t cycle, const Frame& frame) {
  std::filesystem::create_directories(dir);
  char name[24];
  std::snprintf(name, sizeof name, "-cycle%08u", cycle);
  const std::string base = (dir / (utc_text(unix_ms_now(), "%Y%m%d-%H%M%S") + name)).string();
  write_depth_png(base + "-depth.png", to_raw_depth(frame.depth_mm, frame.camera.depth_scale));
  write_json(base + "-camera.json", Json{{"0", camera_to_json(frame.camera)}});
  return base;
}

// Removes the oldest frames' parts beyond the newest `keep`.
void keep_newest(const std::filesystem::path& dir, int keep, std::initializer_list<const char*> parts) {
  namespace fs = std::filesystem;
  const std::string suffix = "-depth.png";
  std::vector<std::string> kept;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (name.size() > suffix.size() && name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
      kept.push_back(name.substr(0, name.size() - suffix.size()));
  }
  std::sort(kept.begin(), kept.end());
  for (std::size_t k = 0; k + std::size_t(keep) < kept.size(); ++k)
    for (const char* part : parts) {
      std::error_code ec;  // a file already gone is no error
      fs::remove(dir / (kept[k] + part), ec);
    }
}

}  // namespace

// The maintainer's record of why the cell stood still: the last log.no_pick_frames LOCATEs that
// handed out no pose keep their depth frame, camera and overlay in log.dir/no-pick/.
void Service::keep_no_pick_frame(const Image<Rgb>& overlay) {
  try {
    const std::filesystem::path dir = std::filesystem::path(cfg_.log.dir) / "no-pick";
    const std::string base = keep_frame(dir, cycles_, frame_);
    write_rgb_png(base + "-overlay.png", overlay);
    keep_newest(dir, cfg_.log.no_pick_frames, {"-depth.png", "-camera.json", "-overlay.png"});
  } catch (const std::exception& e) {
    spdlog::warn("no-pick frame: {}", e.what());
  }
}

// The pose presented and the frame it was found in, while the robot picks it (a NEXT on the same
// frame replaces the pose only). A copy into buffers sized at start-up, after the result is out.
void Service::hold_pick() {
  if (cfg_.log.took_nothing_frames <= 0 || index_ < 0) return;
  if (!held_pick_.held || held_pick_.cycle != cycles_) held_pick_.frame = frame_;
  held_pick_.pose = ranked_[std::size_t(index_)];
  held_pick_.cycle = cycles_;
  held_pick_.index = index_;
  held_pick_.held = true;
}

// The maintainer's record of a pick that took nothing (the robot went there and the bin reads as
// before: a wrong pose, or a gripper that cannot hold the pipe there): the frame the pose was found
// in, the pose as handed out (`-pick.json`: cycle, INDEX, score, model -> camera, the registers'
// pose) and a picture of it, in log.dir/took-nothing/; the last log.took_nothing_frames are kept.
void Service::keep_took_nothing_frame() {
  held_pick_.took_nothing = false;
  held_pick_.held = false;
  const HeldPick& h = held_pick_;
  const std::filesystem::path dir = std::filesystem::path(cfg_.log.dir) / "took-nothing";
  spdlog::warn(
      "LOCATE {}: the pick of LOCATE {} (INDEX {}) took nothing: the bin reads as before where its pose "
      "lies; its frame is kept in {}",
      cycles_, h.cycle, h.index, dir.string());
  try {
    const std::string base = keep_frame(dir, h.cycle, h.frame);
    Json matrix = Json::array();
    const Eigen::Matrix4d m = h.pose.model_to_cam.matrix();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) matrix.push_back(m(r, c));
    const RobotPose& p = h.pose.robot;
    write_json(base + "-pick.json", Json{{"cycle", h.cycle},
                                         {"found_unchanged_by_cycle", cycles_},
                                         {"index", h.index},
                                         {"score", h.pose.score},
                                         {"model_to_cam_rowmajor_mm", matrix},
                                         {"robot",
                                          {{"x_mm", p.xyz_mm[0]},
                                           {"y_mm", p.xyz_mm[1]},
                                           {"z_mm", p.xyz_mm[2]},
                                           {"rx_deg", p.rxyz_deg[0]},
                                           {"ry_deg", p.rxyz_deg[1]},
                                           {"rz_deg", p.rxyz_deg[2]}}}});
    char caption[96];
    std::snprintf(caption, sizeof caption, "LOCATE %u INDEX %d: THE PICK TOOK NOTHING", h.cycle, h.index);
    write_rgb_png(base + "-overlay.png",
                  draw_pose_overlay(h.frame.depth_mm, h.frame.camera, locator_.locator_model(),
                                    h.pose.model_to_cam, caption));
    keep_newest(dir, cfg_.log.took_nothing_frames,
                {"-depth.png", "-camera.json", "-pick.json", "-overlay.png"});
  } catch (const std::exception& e) {
    spdlog::warn("took-nothing frame: {}", e.what());
  }
}

void Service::after_publish(bool shutting_down) {
  warn_unresolved();
  write_overlays();
  if (held_pick_.took_nothing) keep_took_nothing_frame();
  if (shutting_down) return;
  if (result_.status == reg::Status::done_none) source_->found_none();  // only a LOCATE answers it
  if (!pick_pending_) return;
  pick_pending_ = false;
  hold_pick();
  if (const Pose* p = presented()) source_->picked(*p);
}

}  // namespace pipeloc
