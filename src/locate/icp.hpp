// IV-B, Algorithm 2: ICP on Z-ridge points from several initial states, and (beyond the paper)
// a point-to-plane refinement on the whole observed region.
#pragma once

#include <vector>

#include "locate/locate_config.hpp"
#include "locate/locator_model.hpp"
#include "locate/zridge.hpp"

namespace pipeloc {

// Top view distance to a point set: each cell holds the horizontal distance from its centre to
// the nearest point, up to a cap. Looked up many times per start when sliding it.
struct TopDistance {
  float origin_x = 0, origin_y = 0, cell = 1, cap = 1;
  int width = 0, height = 0, capacity_side = 0;
  std::vector<float> d;
  void reserve(int side) { capacity_side = side, d.assign(std::size_t(side) * side, 0.0f); }
  void build(const Eigen::Vector3f* pts, int n, float cell_mm, float cap_mm);
  float at(float x, float y) const {
    const int i = int((x - origin_x) / cell), j = int((y - origin_y) / cell);
    if (x < origin_x || y < origin_y || i >= width || j >= height) return cap;
    return d[std::size_t(j) * width + i];
  }
};

// A point set laid out by coordinate, for nearest-point scans four points at a time.
struct PointColumns {
  std::vector<float> x, y, z;
  int n = 0;
  void reserve(int capacity);
  // false (and nothing assigned) if count exceeds the capacity reserved
  bool assign(const Eigen::Vector3f* points, int count);
  // The first of the points closest to q (-1 if none), its squared distance in d2.
  int nearest(const Eigen::Vector3f& q, float* d2) const;
  // nearest() both ways between a[0..na) and these points, from one pass over the pairs: for each
  // a[i] its nearest here (a_to[i], a_d2[i]), and for each point here the first of a closest to
  // it (b_to[j], b_d2[j]; -1 if a is empty). The same answers as nearest() each way.
  void nearest_both_ways(const Eigen::Vector3f* a, int na, int* a_to, float* a_d2, int* b_to,
                         float* b_d2) const;
};

struct IcpBuffers {
  std::vector<Eigen::Vector3f> model_ridge;  // P_m
  std::vector<Eigen::Vector3f> src, dst;     // correspondences
  PointColumns observed_columns;
  std::vector<int> model_to, observed_to;  // nearest partners both ways (PointColumns::nearest_both_ways)
  std::vector<float> model_d2, observed_d2;
  RidgeBuffers ridge;
  TopDistance observed_top;  // for slide_start
};

// max_region_points: the most points an observed region passes to the Z-ridge.
void reserve_icp(IcpBuffers* buf, const LocatorModel& lm, int max_ridge_points, float ridge_cell_mm,
                 int max_region_points = 0);

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

// Rigid transform taking src onto dst in the least-squares sense (Kabsch), fixed-size maths.
Pose fit_rigid(const Eigen::Vector3f* src, const Eigen::Vector3f* dst, int n);

struct SlidStart {
  Pose pose = Pose::Identity();  // model -> bin
  float cost_mm = 1e30f;         // mean truncated top-view ridge distance, both ways, at the best offset
  int start = -1;                // index in the StartSet
};

// IV-B's initial states, prepared once per model. Start s lies in the frame of the observed axis
// (X along the measured principal direction, the measured centre at the origin): turned about the
// axis (canonical start k), reversed or not, and (beyond the paper) turned about the vertical by
// a yaw offset, since the principal direction of a partly hidden curved pipe can be far from the
// model's. Each keeps its coarse Z-ridge (model frame) and the top-view distance to it, so that a
// candidate slides its starts without extracting a model ridge per start.
struct StartSet {
  float cell_mm = 0;                         // ridge cell of the ridges (the probes' cell)
  std::vector<Pose> pose;                    // model -> axis frame
  std::vector<int> ridge_begin;              // start s: ridge_model[ridge_begin[s] .. ridge_begin[s + 1])
  std::vector<Eigen::Vector3f> ridge_model;  // ridge points, model frame
  std::vector<TopDistance> top;              // distance to the ridge, axis frame
  int size() const { return int(pose.size()); }
  int ridge_count(int s) const { return ridge_begin[std::size_t(s) + 1] - ridge_begin[std::size_t(s)]; }
  const Eigen::Vector3f* ridge(int s) const { return &ridge_model[std::size_t(ridge_begin[std::size_t(s)])]; }
};
StartSet prepare_starts(const LocatorModel& lm, const LocateConfig& cfg);

// Beyond the paper: an observed region is often only part of its pipe (an end hidden, one leg
// of a U), so its measured centre need not be the model's. Start s, placed by axis_to_bin, is slid
// in the bin plane, along and across the observed axis over the model's own extent, to where its
// ridge best covers the observed one (mean top-view distance both ways, truncated at D).
// buf->observed_top must hold the observed ridge (TopDistance::build with cap D), and
// observed_in_axis the observed ridge points in the axis frame.
SlidStart slide_start(const LocatorModel& lm, const StartSet& starts, int s, const Pose& axis_to_bin,
                      const Eigen::Vector3f* observed_in_axis, int n_observed, const LocateConfig& cfg,
                      IcpBuffers* buf);

// One run of Algorithm 2's inner loop from `start`. The observed ridge holds at most the
// max_ridge_points of reserve_icp (more: no fit, cost_mm stays 1e30).
// `gate_mm` < 0 starts the correspondence gate at L/3 (a cold start). `cell_mm` is the ridge
// cell of the observed ridge given (<= 0: cfg.ridge_cell_mm); the model's ridge uses the same.
// `start_ridge` (model frame), when given, is the model's ridge at `start` along `axis` in cells of
// cell_mm, already known (a start of the StartSet): the first iteration does not extract it again.
RidgeFit ridge_icp(const LocatorModel& lm, const Pose& start, const Eigen::Vector3f* observed_ridge,
                   int n_observed, const Eigen::Vector2f& axis, const LocateConfig& cfg, int max_iterations,
                   IcpBuffers* buf, float gate_mm = -1, float cell_mm = -1,
                   const Eigen::Vector3f* start_ridge = nullptr, int start_ridge_count = 0);

// ridge_icp without its closing evaluation: pose, iterations and gate_mm only (the cost and
// match counts stay unset), for a run another continues from at once.
RidgeFit ridge_icp_steps(const LocatorModel& lm, const Pose& start, const Eigen::Vector3f* observed_ridge,
                         int n_observed, const Eigen::Vector2f& axis, const LocateConfig& cfg,
                         int max_iterations, IcpBuffers* buf, float gate_mm = -1, float cell_mm = -1,
                         const Eigen::Vector3f* start_ridge = nullptr, int start_ridge_count = 0);

struct RefineResult {
  Pose pose = Pose::Identity();
  int inliers = 0;
  float rms_mm = 0;
};

// Point-to-plane ICP of observed points (bin frame) onto the model surface.
RefineResult refine_on_surface(const LocatorModel& lm, const Pose& start, const Eigen::Vector3f* observed,
                               int n, const LocateConfig& cfg);

}  // namespace pipeloc
