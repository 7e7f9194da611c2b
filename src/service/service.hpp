// The service's cycle, in the lifecycle of a ros2_control hardware interface: the constructor
// validates and sizes everything (init + configure: model, locator buffers, frame source,
// timing log) and throws if anything is wrong; run() is the real-time part: one PLC command in,
// the register contents out, no allocation after the first LOCATE and no exceptions.
#pragma once

#include <atomic>
#include <memory>
#include <vector>

#include "config/config_file.hpp"
#include "io/png.hpp"
#include "locate/locator.hpp"
#include "plc/register_map.hpp"
#include "service/cycle.hpp"
#include "service/frame_source.hpp"
#include "service/status_board.hpp"
#include "service/timing_log.hpp"
#include "service/tried_picks.hpp"

namespace pipeloc {

// The pipe model of a config: model.stl, or model.preset. Throws naming the key.
PipeModel load_config_model(const AppConfig& cfg);
// robot_from_camera and the grasp offset of a config (identity when not given).
Pose config_robot_from_camera(const PlcConfig& plc);
Pose config_grasp(const ModelConfig& model, EulerConvention euler);

class Service {
 public:
  Service(const AppConfig& cfg, const PipeModel& model, std::unique_ptr<FrameSource> source);

  // Runs the PLC command `command` (CMD register) submitted at `trigger`:
  // LOCATE captures a frame taken after the trigger and localizes within service.budget_ms;
  // NEXT presents the next pose of the last LOCATE; CLEAR_ERROR returns to READY, keeping the
  // poses of the last LOCATE for NEXT.
  const reg::Result& run(std::uint16_t command, std::uint16_t req_id, Clock::time_point trigger);
  // The status page's board (owned by the caller, outliving the Service); nullptr: none.
  void set_status_board(StatusBoard* board) { board_ = board; }
  // After the result is published: a LOCATE's second searches (retry_surface_cell_of_d), within
  // its budget and until *interrupt is set (a command waits); their poses are reported (overlay,
  // log), never handed out, so the PLC does not wait for them. Adds their time to the record.
  void search_again(const std::atomic<bool>* interrupt = nullptr);
  // Copies the last command's record and poses to the board (fixed size, no allocation); after
  // the result is published, beside the timing log line.
  void publish_status();
  // After the result is published (outside the cycle): every log.overlay_every LOCATEs the
  // integrator's picture of the frame is written, every status.overlay_every LOCATEs it goes to
  // the status board, a LOCATE that handed out no pose keeps its frame (log.no_pick_frames), a
  // pick that took nothing keeps the frame it was found in (log.took_nothing_frames), and the
  // simulated bin loses the pipe handed out (after a DONE_NONE, is shaken if so configured).
  // Shutting down, the records are still written (the last LOCATE before a stop is often the one
  // that stood still) but the bin stays as it is.
  void after_publish(bool shutting_down = false);
  // Stops a running cycle at its next check (shutdown).
  void cancel_cycles(const std::atomic<bool>* flag) {
    cancel_ = flag;
    locator_.set_cancel_flag(flag);
  }

  double budget_ms() const { return cfg_.service.budget_ms; }
  const CycleRecord& record() const { return record_; }
  const reg::Result& result() const { return result_; }
  const Frame& frame() const { return frame_; }
  const LocateOutput& output() const { return locator_.output(); }
  const Locator& locator() const { return locator_; }
  FrameSource& source() { return *source_; }
  TimingLog& log() { return log_; }
  // The pose (model -> camera) presented now, when the status is DONE_OK.
  const Pose* presented() const;

 private:
  struct Ranked {
    Pose model_to_cam = Pose::Identity();
    RobotPose robot;
    float score = 0;
  };
  void locate(Clock::time_point trigger);
  void present(int index);
  void write_overlays();
  void keep_no_pick_frame(const Image<Rgb>& overlay);
  void hold_pick();
  void keep_took_nothing_frame();
  void note_unresolved(const LocateOutput& out);
  void warn_unresolved();

  const AppConfig& cfg_;
  std::unique_ptr<FrameSource> source_;
  Locator locator_;
  Frame frame_;
  TimingLog log_;
  Pose robot_from_camera_, grasp_;
  std::vector<Ranked> ranked_;  // pickable poses of the last LOCATE, in the order handed out
  int index_ = -1;
  int handed_out_ = -1;  // the pose of ranked_ presented last: the one the robot goes to
  TriedPicks tried_;     // poses whose picks left the bin unchanged (withhold_unchanged_picks)
  // The pose presented last and the frame it was found in, while the robot picks it; kept in
  // log.dir/took-nothing where the next LOCATE finds the bin there as it was.
  struct HeldPick {
    Frame frame;
    Ranked pose;
    std::uint32_t cycle = 0;
    int index = -1;
    bool held = false;
    bool took_nothing = false;  // found so by the LOCATE running now: kept after its result
  };
  HeldPick held_pick_;
  bool pick_pending_ = false;
  std::uint32_t cycles_ = 0;
  // The last LOCATE handed out nothing, but found a pose the sensor does not resolve
  // (pick_min_relief_sigmas): logged after the PLC has its result.
  struct Unresolved {
    float relief_sigmas = -1;  // of the best such pose; -1: none
    float depth_mm = 0;        // its distance from the camera
    float noise_mm = 0;        // the frame's noise
    bool noise_measured = false;
  };
  Unresolved unresolved_;
  std::uint32_t unresolved_cycles_ = 0;  // such LOCATEs since the last pick
  const std::atomic<bool>* cancel_ = nullptr;
  StatusBoard* board_ = nullptr;
  reg::Result result_;
  CycleRecord record_;
};

}  // namespace pipeloc
