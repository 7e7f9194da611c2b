// IV-A: the Z-ridge. With the principal axis along X, the points nearest the camera along each
// line across the axis: per line and per run of occupied cells, the highest point.
#pragma once

#include <cstdint>
#include <vector>

#include "core/pose.hpp"

namespace pipeloc {

struct RidgeBuffers {
  int cols = 0, rows = 0;                    // capacity of the axis-aligned grid
  std::vector<float> top_z;                  // per cell: highest z; -inf (empty) between calls
  std::vector<int> top_i;                    // per cell: the index of that point
  int row_words = 0;                         // 64-bit words of occupied bits per row
  std::vector<std::uint64_t> occupied_bits;  // per row: a bit per occupied column; 0 between calls
  std::vector<int> occupied;                 // the occupied columns of the row being scanned
  std::vector<float> occupied_z;             // and their highest z
  int max_points = 0;                        // points taken that the columns below hold
  std::vector<float> u, v, z;                // per point taken: along and across the axis, and height
  std::vector<int> index;                    // per point taken: its index in the input
};

// Runs of ridge points narrower than this share of D are noise or a pipe's end, not its ridge.
constexpr float kRidgeMinRunOfD = 0.3f;

void reserve_ridge(RidgeBuffers* rb, float max_extent_mm, float cell_mm, int max_points = 0);

// points: bin frame. axis: unit in XY. Writes at most `capacity` ridge points to out and
// returns their count. Runs narrower than min_run_mm are ignored (noise, pipe ends).
// With `whole_surface`, every occupied cell's highest point instead: the visible surface sampled
// on the same grid (the paper's comparison, "--match surface").
int extract_zridge(const Eigen::Vector3f* points, int count, const Eigen::Vector2f& axis, float cell_mm,
                   float min_run_mm, RidgeBuffers* rb, Eigen::Vector3f* out, int capacity,
                   bool whole_surface = false);

// Points with their normals laid out by coordinate: every `stride`-th of a set, so that a pose
// moves them four at a time.
struct OrientedColumns {
  int stride = 1;  // of the set they were taken from
  int count = 0;
  std::vector<float> x, y, z, nx, ny, nz;
  void assign(const Eigen::Vector3f* points, const Eigen::Vector3f* normals, int n, int take_stride);
};

// The same ridge of points given in another frame (the model's), placed in the bin by to_bin:
// every `stride`-th point whose normal (same frame) does not face down at that pose is taken.
// Only the ridge points are moved into the bin, not every point. With `columns` (the same points,
// every stride-th, laid out by coordinate) the points are moved four at a time; the ridge is the same.
struct PosedPoints {
  const Eigen::Vector3f* points = nullptr;
  const Eigen::Vector3f* normals = nullptr;  // null: every point taken
  int count = 0;
  int stride = 1;
  const OrientedColumns* columns = nullptr;
  Pose to_bin = Pose::Identity();
};
int extract_zridge(const PosedPoints& pts, const Eigen::Vector2f& axis, float cell_mm, float min_run_mm,
                   RidgeBuffers* rb, Eigen::Vector3f* out, int capacity, bool whole_surface = false);

}  // namespace pipeloc
