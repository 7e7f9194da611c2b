// IV-B's initial states: prepared once per model, then slid per candidate over its observed ridge.
#pragma once

#include <vector>

#include "locate/locate_config.hpp"
#include "locate/locator_model.hpp"

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

struct SlideBuffers {
  std::vector<Eigen::Vector3f> model_ridge;  // a start's ridge, placed
  TopDistance observed_top;                  // the observed ridge's
};
// max_ridge_points: the most points of a start's ridge; ridge_cell_mm: the finest ridge cell.
void reserve_slide(SlideBuffers* buf, const LocatorModel& lm, int max_ridge_points, float ridge_cell_mm);

// Beyond the paper: an observed region is often only part of its pipe (an end hidden, one leg
// of a U), so its measured centre need not be the model's. Start s, placed by axis_to_bin, is slid
// in the bin plane, along and across the observed axis over the model's own extent, to where its
// ridge best covers the observed one (mean top-view distance both ways, truncated at D).
// buf->observed_top must hold the observed ridge (TopDistance::build with cap D), and
// observed_in_axis the observed ridge points in the axis frame. along_mm: how far along the axis
// either way (the model's slide_along_mm, L/4, but where the observed ridge reaches the view's edge).
SlidStart slide_start(const LocatorModel& lm, const StartSet& starts, int s, const Pose& axis_to_bin,
                      const Eigen::Vector3f* observed_in_axis, int n_observed, const LocateConfig& cfg,
                      SlideBuffers* buf, float along_mm);

}  // namespace pipeloc
