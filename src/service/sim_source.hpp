// The embedded default source: the project's simulator. It keeps a pile in a bin, renders it
// once per change of the pile and draws fresh sensor noise for every frame. A pipe handed out
// and picked is taken out of the bin, so a run empties a bin as a real cell would; an empty
// bin is refilled with a new pile (source.sim.refill). With source.sim.shake_after_none, the bin
// is shaken after each DONE_NONE, as the pick after a DONE_OK (outside the cycle): the pipes left
// dropped into it again, a new pile of as many under the same camera (a real shaker moves them
// less: this is its best case).
#pragma once

#include <cstdio>
#include <random>
#include <vector>

#include "service/frame_source.hpp"
#include "sim/scene.hpp"

namespace pipeloc {

class SimSource : public FrameSource {
 public:
  SimSource(const PipeModel& model, const SimSourceConfig& cfg);
  ~SimSource() override;
  const char* kind() const override { return "sim"; }
  const Intrinsics& intrinsics() const override { return params_.intrinsics; }
  GrabStatus grab(Clock::time_point after, Clock::time_point deadline, Frame* out) override;
  void picked(const Pose& model_to_cam) override;
  void found_none() override;
  std::string describe() const override;

  // Ground truth for tests and the demo: the pipes still in the bin, model -> camera.
  std::vector<Pose> pipes_in_camera() const;
  int bins_filled() const { return bins_; }

 private:
  void fill_bin();
  void shake();
  void render();
  void write_truth(std::uint64_t frame);

  const PipeModel& model_;
  SimSourceConfig cfg_;
  SceneParams params_;
  std::mt19937 rng_;
  std::vector<Eigen::Vector3d> vertices_;  // for matching a picked pose to a pipe
  std::vector<Eigen::Vector3d> surface_;   // spread by area, for the share of a pipe in view
  std::vector<Pose> pick_symmetries_;      // ... as the scorer does: a straight tube's turns too
  std::vector<Pose> pile_;                 // model -> world
  Pose world_to_cam_ = Pose::Identity();
  SensorView view_;
  // With a truth file: the share of each pipe covered by the others, as the scorer counts it
  // (GtInfo::occ_by_pipes), for the pile as last rendered.
  std::vector<double> covered_;
  std::uint64_t sequence_ = 0;
  int bins_ = 0;
  int frames_without_pick_ = 0;
  int shakes_ = 0;  // of this bin
  std::FILE* truth_ = nullptr;
};

}  // namespace pipeloc
