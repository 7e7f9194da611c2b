#include "locate/zridge.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pipeloc {

void reserve_ridge(RidgeBuffers* rb, float max_extent_mm, float cell_mm, int max_points) {
  rb->uv.assign(std::size_t(max_points), Eigen::Vector2f::Zero());
  rb->cols = rb->rows = int(std::ceil(max_extent_mm / cell_mm)) + 2;
  rb->top_z.assign(std::size_t(rb->cols) * rb->rows, -std::numeric_limits<float>::infinity());
  rb->row_lo.assign(std::size_t(rb->rows), 0);
  rb->row_hi.assign(std::size_t(rb->rows), 0);
  rb->top_p.assign(std::size_t(rb->cols) * rb->rows, Eigen::Vector3f::Zero());
}

int extract_zridge(const Eigen::Vector3f* pts, int count, const Eigen::Vector2f& axis, float cell,
                   float min_run_mm, RidgeBuffers* rb, Eigen::Vector3f* out, int capacity,
                   bool whole_surface) {
  if (count == 0) return 0;
  const Eigen::Vector2f across(-axis.y(), axis.x());
  float u0 = 1e30f, u1 = -1e30f, v0 = 1e30f, v1 = -1e30f;
  const bool keep_uv = count <= int(rb->uv.size());  // else computed twice
  for (int k = 0; k < count; ++k) {
    const float u = pts[k].head<2>().dot(axis), v = pts[k].head<2>().dot(across);
    if (keep_uv) rb->uv[std::size_t(k)] = Eigen::Vector2f(u, v);
    u0 = std::min(u0, u), u1 = std::max(u1, u), v0 = std::min(v0, v), v1 = std::max(v1, v);
  }
  // Rows are lines across the axis (fixed u); columns run across (v).
  const int rows = std::min(rb->rows, int((u1 - u0) / cell) + 1);
  const int cols = std::min(rb->cols, int((v1 - v0) / cell) + 1);
  constexpr float kNone = -std::numeric_limits<float>::infinity();
  // Only the occupied span of each row is visited, and emptied again before returning: a tube
  // fills a band of the grid, not the grid.
  std::fill_n(rb->row_lo.begin(), rows, cols);
  std::fill_n(rb->row_hi.begin(), rows, -1);
  const float inv_cell = 1.0f / cell;
  for (int k = 0; k < count; ++k) {
    const Eigen::Vector2f uv =
        keep_uv ? rb->uv[std::size_t(k)]
                : Eigen::Vector2f(pts[k].head<2>().dot(axis), pts[k].head<2>().dot(across));
    const int r = int((uv.x() - u0) * inv_cell);
    const int c = int((uv.y() - v0) * inv_cell);
    if (r < 0 || c < 0 || r >= rows || c >= cols) continue;
    float& z = rb->top_z[std::size_t(r) * cols + c];
    if (pts[k].z() > z) z = pts[k].z(), rb->top_p[std::size_t(r) * cols + c] = pts[k];
    rb->row_lo[std::size_t(r)] = std::min(rb->row_lo[std::size_t(r)], c);
    rb->row_hi[std::size_t(r)] = std::max(rb->row_hi[std::size_t(r)], c);
  }
  int n = 0;
  const int min_run = std::max(1, int(min_run_mm / cell));
  for (int r = 0; r < rows; ++r) {
    float* zr = &rb->top_z[std::size_t(r) * cols];
    const int lo = rb->row_lo[std::size_t(r)], hi = rb->row_hi[std::size_t(r)];
    if (whole_surface)
      for (int c = lo; c <= hi && n < capacity; ++c)
        if (zr[c] != kNone) out[n++] = rb->top_p[std::size_t(r) * cols + c];
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
      if (end - c + 1 >= min_run && best != c && best != end)
        out[n++] = rb->top_p[std::size_t(r) * cols + best];
      c = end + 1;
    }
    if (lo <= hi) std::fill(zr + lo, zr + hi + 1, kNone);
  }
  return n;
}

}  // namespace pipeloc
