// IV-A: the Z-ridge. With the principal axis along X, the points nearest the camera along each
// line across the axis: per line and per run of occupied cells, the highest point.
#pragma once

#include <vector>

#include "core/pose.hpp"

namespace pipeloc {

struct RidgeBuffers {
  int cols = 0, rows = 0;            // capacity of the axis-aligned grid
  std::vector<float> top_z;          // per cell: highest z; -inf (empty) between calls
  std::vector<int> top_i;            // per cell: the index of that point
  std::vector<int> row_lo, row_hi;   // per row: first and last occupied column of this call
  std::vector<Eigen::Vector3f> uvz;  // per point taken: along and across the axis, and height
  std::vector<int> index;            // per point taken: its index in the input
};

void reserve_ridge(RidgeBuffers* rb, float max_extent_mm, float cell_mm, int max_points = 0);

// points: bin frame. axis: unit in XY. Writes at most `capacity` ridge points to out and
// returns their count. Runs narrower than min_run_mm are ignored (noise, pipe ends).
// With `whole_surface`, every occupied cell's highest point instead: the visible surface sampled
// on the same grid (the paper's comparison, "--match surface").
int extract_zridge(const Eigen::Vector3f* points, int count, const Eigen::Vector2f& axis, float cell_mm,
                   float min_run_mm, RidgeBuffers* rb, Eigen::Vector3f* out, int capacity,
                   bool whole_surface = false);

// The same ridge of points given in another frame (the model's), placed in the bin by to_bin:
// every `stride`-th point whose normal (same frame) does not face down at that pose is taken.
// Only the ridge points are moved into the bin, not every point.
struct PosedPoints {
  const Eigen::Vector3f* points = nullptr;
  const Eigen::Vector3f* normals = nullptr;  // null: every point taken
  int count = 0;
  int stride = 1;
  Pose to_bin = Pose::Identity();
};
int extract_zridge(const PosedPoints& pts, const Eigen::Vector2f& axis, float cell_mm, float min_run_mm,
                   RidgeBuffers* rb, Eigen::Vector3f* out, int capacity, bool whole_surface = false);

}  // namespace pipeloc
