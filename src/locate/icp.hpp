// IV-B, Algorithm 2: ICP on Z-ridge points from several initial states, and (beyond the paper)
// a point-to-plane refinement on the whole observed region.
#pragma once

#include <vector>

#include "locate/locate_config.hpp"
#include "locate/locator_model.hpp"
#include "locate/zridge.hpp"

namespace pipeloc {

struct IcpBuffers {
  std::vector<Eigen::Vector3f> moved;        // model ridge samples at the current pose
  std::vector<Eigen::Vector3f> model_ridge;  // P_m
  std::vector<Eigen::Vector3f> src, dst;     // correspondences
  RidgeBuffers ridge;
};

// max_region_points: the most points an observed region passes to the Z-ridge.
void reserve_icp(IcpBuffers* buf, const LocatorModel& lm, int max_ridge_points, float ridge_cell_mm,
                 int max_region_points = 0);

struct RidgeFit {
  Pose pose = Pose::Identity();  // model -> bin
  float cost_mm = 1e30f;         // mean truncated ridge distance, both ways
  int iterations = 0;
  int model_ridge_points = 0;
  int matched = 0;    // model ridge points with an observed partner within D/2
  float gate_mm = 0;  // correspondence gate reached (to resume from)
};

// Rigid transform taking src onto dst in the least-squares sense (Kabsch), fixed-size maths.
Pose fit_rigid(const Eigen::Vector3f* src, const Eigen::Vector3f* dst, int n);

// One run of Algorithm 2's inner loop from `start`.
// `gate_mm` < 0 starts the correspondence gate at L/3 (a cold start). `cell_mm` is the ridge
// cell of the observed ridge given (<= 0: cfg.ridge_cell_mm); the model's ridge uses the same.
RidgeFit ridge_icp(const LocatorModel& lm, const Pose& start, const Eigen::Vector3f* observed_ridge,
                   int n_observed, const Eigen::Vector2f& axis, const LocateConfig& cfg, int max_iterations,
                   IcpBuffers* buf, float gate_mm = -1, float cell_mm = -1);

struct RefineResult {
  Pose pose = Pose::Identity();
  int inliers = 0;
  float rms_mm = 0;
};

// Point-to-plane ICP of observed points (bin frame) onto the model surface.
RefineResult refine_on_surface(const LocatorModel& lm, const Pose& start, const Eigen::Vector3f* observed,
                               int n, const LocateConfig& cfg);

}  // namespace pipeloc
