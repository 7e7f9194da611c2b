// What the cell learns from a pick that took nothing: a pose handed out, after whose pick the depth
// where the sensor saw the pose reads as before, is not handed out again while it reads so
// (service.withhold_unchanged_picks). The robot went there and the bin did not change: the pose is
// wrong, or the gripper cannot take that pipe there; handing it out again would send the robot to
// the same place. Fixed size: no allocation in the cycle.
#pragma once

#include <array>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "locate/locator.hpp"

namespace pipeloc {

class TriedPicks {
 public:
  // Pixels a pose's footprint is compared on, of at most kExamined surface samples.
  static constexpr int kFootprintPx = 256;
  static constexpr std::size_t kExamined = 2048;
  // A footprint reads as before where at least this share of its pixels does.
  static constexpr double kUnchangedShare = 0.5;
  // A footprint with fewer readings tells nothing (a pose wholly out of the view).
  static constexpr int kMinFootprintPx = 16;

  // The pose presented last (model -> camera) on the frame it was found in: the one the robot
  // goes to before the next LOCATE. Its footprint: the pixels where the frame shows the pose's
  // surface on top (facing the camera, read where it lies), with the depth read there. The
  // model's vertices were used before: a straight tube's lie only at its end rings, whose pixels
  // half read past the tube, so a pick that took its pipe read as unchanged (3 of 12 picks of a
  // zoo bin).
  void handed_out(const Pose& model_to_cam, const Image<float>& depth_mm, const Intrinsics& k,
                  const LocatorModel& lm);
  // A new frame: the pose handed out last becomes a tried one where its footprint reads as before
  // (within D/2 on at least kUnchangedShare of its pixels: a pipe taken away changes the depth
  // there by at least its diameter); a tried pose whose footprint changed is forgotten (the pipe
  // moved or is gone). The oldest is forgotten when Locator::kMaxTried are remembered. True when
  // the pose handed out last became a tried one: its pick took nothing.
  bool next_frame(const Image<float>& depth_mm, float tube_d_mm);
  void clear() { has_last_ = false, count_ = 0; }

  const Pose* poses() const { return poses_.data(); }
  int size() const { return count_; }

 private:
  struct Footprint {
    int n = 0;
    std::array<int, kFootprintPx> pixel{};
    std::array<float, kFootprintPx> depth_mm{};
  };
  static bool unchanged(const Footprint& f, const Image<float>& depth_mm, float tube_d_mm);

  Pose last_ = Pose::Identity();
  Footprint last_footprint_;
  bool has_last_ = false;
  std::array<Pose, Locator::kMaxTried> poses_;
  std::array<Footprint, Locator::kMaxTried> footprints_;
  int count_ = 0;
};

}  // namespace pipeloc
