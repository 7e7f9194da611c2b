// IV-B, Algorithm 2: ICP of the model's Z-ridge onto the observed one, from a given start.
#pragma once

#include <vector>

#include "locate/locate_config.hpp"
#include "locate/locator_model.hpp"
#include "locate/nearest_points.hpp"
#include "locate/zridge.hpp"

namespace pipeloc {

struct RidgeFit {
  Pose pose = Pose::Identity();  // model -> bin
  float cost_mm = 1e30f;         // mean truncated ridge distance, both ways
  int iterations = 0;
  int model_ridge_points = 0;
  int matched = 0;         // model ridge points with an observed partner within D/2
  float gate_mm = 0;       // correspondence gate reached (to resume from)
  float seen_through = 0;  // share of the model's ridge where the sensor saw deeper (set by the caller)
  // Ranks states: a ridge point the sensor saw through costs one more diameter, so a state lying
  // over empty space (a U flipped onto its other leg) loses to one the image allows.
  float rank_cost(float d) const { return cost_mm + seen_through * d; }
};

// The model's Z-ridge at `pose` (model -> bin) across `axis`, in cells of cell_mm: at most
// `capacity` points to out, bin frame; returns their count.
int posed_model_ridge(const LocatorModel& lm, const Pose& pose, const Eigen::Vector2f& axis, float cell_mm,
                      const LocateConfig& cfg, RidgeBuffers* rb, Eigen::Vector3f* out, int capacity);

// The observed ridge a run fits the model's to.
struct RidgeView {
  const Eigen::Vector3f* points = nullptr;  // bin frame
  int count = 0;
  Eigen::Vector2f axis = Eigen::Vector2f::UnitX();  // the observed principal direction (unit, bin XY)
  float cell_mm = 0;                                // its ridge cell; the model's ridge uses the same
};

// Where a run starts.
struct IcpStart {
  Pose pose = Pose::Identity();  // model -> bin
  float gate_mm = -1;            // correspondence gate to resume from; < 0: a cold start at L/3
  // The model's ridge at `pose` in cells of the view's cell_mm (model frame), when already known
  // (a start of the StartSet): the first iteration does not extract it again.
  const Eigen::Vector3f* model_ridge = nullptr;
  int model_ridge_count = 0;
};

// Algorithm 2's inner loop on one model with one config, in buffers sized once.
class RidgeIcp {
 public:
  // For observed ridges of up to max_ridge_points. Keeps lm and cfg by reference.
  void reserve(const LocatorModel& lm, const LocateConfig& cfg, int max_ridge_points);

  // One run from `start`, at most max_iterations, then evaluated (cost_mm, matched). An observed
  // ridge larger than max_ridge_points gives no fit (cost_mm stays 1e30).
  RidgeFit fit(const IcpStart& start, const RidgeView& observed, int max_iterations);
  // The same without the closing evaluation: pose, iterations and gate_mm only, for a run another
  // continues from at once.
  RidgeFit steps(const IcpStart& start, const RidgeView& observed, int max_iterations);

  // The model's ridge of the last fit() (RidgeFit::model_ridge_points of them), bin frame.
  const Eigen::Vector3f* model_ridge() const { return model_ridge_.data(); }

 private:
  int place_model_ridge(const Pose& pose, const Eigen::Vector2f& axis, float cell_mm);
  void pair_up(int nm, float radius_mm);
  RidgeFit iterate(const IcpStart& start, const RidgeView& observed, int max_iterations);
  void score(const RidgeView& observed, RidgeFit* fit);

  const LocatorModel* lm_ = nullptr;
  const LocateConfig* cfg_ = nullptr;
  std::vector<Eigen::Vector3f> model_ridge_;  // P_m
  std::vector<Eigen::Vector3f> src_, dst_;    // correspondences
  PointColumns observed_columns_;
  // Nearest partners both ways (PointColumns::nearest_both_ways_within).
  std::vector<int> model_to_, observed_to_;
  std::vector<float> model_d2_, observed_d2_;
  RidgeBuffers ridge_;
};

}  // namespace pipeloc
