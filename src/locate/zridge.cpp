#include "locate/zridge.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pipeloc {

void reserve_ridge(RidgeBuffers* rb, float max_extent_mm, float cell_mm, int max_points) {
  rb->uvz.assign(std::size_t(max_points), Eigen::Vector3f::Zero());
  rb->index.assign(std::size_t(max_points), 0);
  rb->cols = rb->rows = int(std::ceil(max_extent_mm / cell_mm)) + 2;
  rb->top_z.assign(std::size_t(rb->cols) * rb->rows, -std::numeric_limits<float>::infinity());
  rb->top_i.assign(std::size_t(rb->cols) * rb->rows, 0);
  rb->row_lo.assign(std::size_t(rb->rows), 0);
  rb->row_hi.assign(std::size_t(rb->rows), 0);
}

int extract_zridge(const Eigen::Vector3f* points, int count, const Eigen::Vector2f& axis, float cell,
                   float min_run_mm, RidgeBuffers* rb, Eigen::Vector3f* out, int capacity,
                   bool whole_surface) {
  PosedPoints pts;
  pts.points = points;
  pts.count = count;
  return extract_zridge(pts, axis, cell, min_run_mm, rb, out, capacity, whole_surface);
}

int extract_zridge(const PosedPoints& pts, const Eigen::Vector2f& axis, float cell, float min_run_mm,
                   RidgeBuffers* rb, Eigen::Vector3f* out, int capacity, bool whole_surface) {
  const Eigen::Matrix3f r = pts.to_bin.linear().cast<float>();
  const Eigen::Vector3f t = pts.to_bin.translation().cast<float>();
  // Rows of `to_uvz` give, from a point of the input frame, its position along the axis, across it,
  // and its height in the bin.
  const Eigen::Vector3f along3(axis.x(), axis.y(), 0), across3(-axis.y(), axis.x(), 0);
  Eigen::Matrix3f to_uvz;
  to_uvz.row(0) = along3.transpose() * r;
  to_uvz.row(1) = across3.transpose() * r;
  to_uvz.row(2) = r.row(2);
  const Eigen::Vector3f uvz_t(along3.dot(t), across3.dot(t), t.z());
  const Eigen::Vector3f up_in_input = r.row(2).transpose();
  // Down-facing samples lie under the tube's top half and are never the highest of a ridge cell
  // inside a run.
  constexpr float kFacingDown = -0.2f;
  const auto taken = [&](int k) { return !pts.normals || pts.normals[k].dot(up_in_input) > kFacingDown; };
  const int stride = std::max(1, pts.stride);
  const int max_taken = int(rb->uvz.size());
  float u0 = 1e30f, u1 = -1e30f, v0 = 1e30f, v1 = -1e30f;
  int n_taken = 0;
  for (int k = 0; k < pts.count; k += stride) {
    if (!taken(k)) continue;
    const Eigen::Vector3f q = to_uvz * pts.points[k] + uvz_t;
    u0 = std::min(u0, q.x()), u1 = std::max(u1, q.x()), v0 = std::min(v0, q.y()), v1 = std::max(v1, q.y());
    if (n_taken < max_taken) rb->uvz[std::size_t(n_taken)] = q, rb->index[std::size_t(n_taken)] = k;
    ++n_taken;
  }
  if (n_taken == 0) return 0;
  // Rows are lines across the axis (fixed u); columns run across (v).
  const int rows = std::min(rb->rows, int((u1 - u0) / cell) + 1);
  const int cols = std::min(rb->cols, int((v1 - v0) / cell) + 1);
  constexpr float kNone = -std::numeric_limits<float>::infinity();
  // Only the occupied span of each row is visited, and emptied again before returning: a tube
  // fills a band of the grid, not the grid.
  std::fill_n(rb->row_lo.begin(), rows, cols);
  std::fill_n(rb->row_hi.begin(), rows, -1);
  const float inv_cell = 1.0f / cell;
  const auto bin = [&](const Eigen::Vector3f& q, int k) {
    const int r_ = int((q.x() - u0) * inv_cell);
    const int c = int((q.y() - v0) * inv_cell);
    if (r_ < 0 || c < 0 || r_ >= rows || c >= cols) return;
    const std::size_t cell_index = std::size_t(r_) * cols + c;
    if (q.z() > rb->top_z[cell_index]) rb->top_z[cell_index] = q.z(), rb->top_i[cell_index] = k;
    rb->row_lo[std::size_t(r_)] = std::min(rb->row_lo[std::size_t(r_)], c);
    rb->row_hi[std::size_t(r_)] = std::max(rb->row_hi[std::size_t(r_)], c);
  };
  if (n_taken <= max_taken) {
    for (int k = 0; k < n_taken; ++k) bin(rb->uvz[std::size_t(k)], rb->index[std::size_t(k)]);
  } else {  // more points than the buffers were sized for: projected again, none dropped
    for (int k = 0; k < pts.count; k += stride)
      if (taken(k)) bin(to_uvz * pts.points[k] + uvz_t, k);
  }
  const auto emit = [&](std::size_t cell_index) {
    return Eigen::Vector3f(r * pts.points[rb->top_i[cell_index]] + t);
  };
  int n = 0;
  const int min_run = std::max(1, int(min_run_mm / cell));
  for (int r_ = 0; r_ < rows; ++r_) {
    const std::size_t row0 = std::size_t(r_) * cols;
    float* zr = &rb->top_z[row0];
    const int lo = rb->row_lo[std::size_t(r_)], hi = rb->row_hi[std::size_t(r_)];
    if (whole_surface)
      for (int c = lo; c <= hi && n < capacity; ++c)
        if (zr[c] != kNone) out[n++] = emit(row0 + c);
    int c = whole_surface ? hi + 1 : lo;
    while (c <= hi && n < capacity) {
      if (zr[c] == kNone) {
        ++c;
        continue;
      }
      // A run tolerates one empty cell (sampling gaps).
      int best = c, end = c;
      while (end + 1 <= hi && (zr[end + 1] != kNone || (end + 2 <= hi && zr[end + 2] != kNone))) {
        ++end;
        if (zr[end] != kNone && zr[end] > zr[best]) best = end;
      }
      // Peaks at the edge of a run are slopes, not ridges.
      if (end - c + 1 >= min_run && best != c && best != end) out[n++] = emit(row0 + best);
      c = end + 1;
    }
    if (lo <= hi) std::fill(zr + lo, zr + hi + 1, kNone);
  }
  return n;
}

}  // namespace pipeloc
