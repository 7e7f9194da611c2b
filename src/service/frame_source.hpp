// Where depth frames come from, behind one interface (config: source.kind): a live OpenNI2
// sensor, a replayed dataset, or the project's simulator. Sources are opened at start-up (they
// throw there, naming what is wrong); grab() runs in the cycle and returns a status instead.
#pragma once

#include <cstdint>
#include <memory>
#include <string>

#include "config/config_file.hpp"
#include "core/camera.hpp"
#include "core/clock.hpp"
#include "core/image.hpp"
#include "model/pipe_model.hpp"

namespace pipeloc {

struct Frame {
  Image<float> depth_mm;  // sized once from the source's intrinsics; 0 = no reading
  CameraInfo camera;
  Clock::time_point captured{};
  std::uint64_t sequence = 0;   // frames delivered by this source
  int scene_id = 0, im_id = 0;  // where it came from (replay: the dataset's ids; otherwise 0, sequence)
};

enum class GrabStatus { ok, sensor_unavailable, frame_invalid };
const char* grab_status_name(GrabStatus s);

struct SourceError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual const char* kind() const = 0;
  // Resolution and intrinsics of the frames it delivers; buffers are sized from these.
  virtual const Intrinsics& intrinsics() const = 0;
  // A frame captured after `after` (never an older, buffered one), waiting until `deadline` at
  // most. Allocates nothing; out->depth_mm must already have the source's size.
  virtual GrabStatus grab(Clock::time_point after, Clock::time_point deadline, Frame* out) = 0;
  // The robot took the pipe handed out at this pose (model -> camera of the last frame).
  virtual void picked(const Pose& /*model_to_cam*/) {}
  // The last LOCATE handed out no pose (DONE_NONE): a simulated cell may shake its bin before
  // the next frame.
  virtual void found_none() {}
  // One line for the start-up log.
  virtual std::string describe() const = 0;
};

// Opens the source chosen in cfg.source. Throws SourceError naming the file or device at fault.
std::unique_ptr<FrameSource> open_frame_source(const AppConfig& cfg, const PipeModel& model);

// A frame the localizer can work on: the right size, finite non-negative depths, and at least
// min_valid_share of its pixels with a reading. *why (when given) says which check failed, for
// the timing log (ERROR 2 alone does not tell a maintainer what was wrong).
constexpr double kMinValidDepthShare = 0.02;
GrabStatus check_frame(const Image<float>& depth_mm, const Intrinsics& expected,
                       double min_valid_share = kMinValidDepthShare, const char** why = nullptr);
// Pixels with a depth reading (finite, > 0).
std::size_t valid_depth_pixels(const Image<float>& depth_mm);

}  // namespace pipeloc
