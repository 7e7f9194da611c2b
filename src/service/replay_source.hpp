// Frames from disk, in order, looping: a BOP dataset (every test/SSSSSS/depth/*.png with its
// scene_camera.json) or a folder of 16-bit depth PNGs with one camera file. Every frame is read
// and checked at start-up, so a bad file stops the service there, naming the file.
#pragma once

#include <vector>

#include "service/frame_source.hpp"

namespace pipeloc {

class ReplaySource : public FrameSource {
 public:
  explicit ReplaySource(const ReplaySourceConfig& cfg);
  const char* kind() const override { return "replay"; }
  const Intrinsics& intrinsics() const override { return intrinsics_; }
  GrabStatus grab(Clock::time_point after, Clock::time_point deadline, Frame* out) override;
  std::string describe() const override;
  std::size_t frames() const { return frames_.size(); }

 private:
  struct Stored {
    Image<float> depth_mm;
    CameraInfo camera;
    int scene_id = 0, im_id = 0;
  };
  // One frame; its size is checked against its camera (image camera_id of camera_file).
  void add(const std::string& png, const std::string& camera_file, int camera_id, const CameraInfo& camera,
           int scene_id, int im_id);

  ReplaySourceConfig cfg_;
  std::vector<Stored> frames_;
  Intrinsics intrinsics_;
  std::size_t next_ = 0;
  std::uint64_t sequence_ = 0;
};

}  // namespace pipeloc
