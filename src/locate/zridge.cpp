#include "locate/zridge.hpp"

#include <emmintrin.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pipeloc {

void reserve_ridge(RidgeBuffers* rb, float max_extent_mm, float cell_mm, int max_points) {
  // Four columns more than the points: the projection writes a whole group of four at a time.
  rb->max_points = std::max(0, max_points);
  for (auto* col : {&rb->u, &rb->v, &rb->z}) col->assign(std::size_t(rb->max_points) + 4, 0.0f);
  rb->index.assign(std::size_t(rb->max_points) + 4, 0);
  rb->cols = rb->rows = int(std::ceil(max_extent_mm / cell_mm)) + 2;
  rb->top_z.assign(std::size_t(rb->cols) * rb->rows, -std::numeric_limits<float>::infinity());
  rb->top_i.assign(std::size_t(rb->cols) * rb->rows, 0);
  rb->row_words = (rb->cols + 63) / 64;
  rb->occupied_bits.assign(std::size_t(rb->rows) * rb->row_words, 0);
  rb->occupied.assign(std::size_t(rb->cols), 0);
  rb->occupied_z.assign(std::size_t(rb->cols), 0.0f);
}

void OrientedColumns::assign(const Eigen::Vector3f* points, const Eigen::Vector3f* normals, int n,
                             int take_stride) {
  stride = std::max(1, take_stride);
  count = (n + stride - 1) / stride;
  for (auto* col : {&x, &y, &z, &nx, &ny, &nz}) col->assign(std::size_t(count), 0.0f);
  for (int k = 0; k < count; ++k) {
    const Eigen::Vector3f& p = points[k * stride];
    const Eigen::Vector3f& q = normals[k * stride];
    x[std::size_t(k)] = p.x(), y[std::size_t(k)] = p.y(), z[std::size_t(k)] = p.z();
    nx[std::size_t(k)] = q.x(), ny[std::size_t(k)] = q.y(), nz[std::size_t(k)] = q.z();
  }
}

namespace {

// Down-facing samples lie under the tube's top half and are never the highest of a ridge cell
// inside a run.
constexpr float kFacingDown = -0.2f;

struct Span {
  float u0 = 1e30f, u1 = -1e30f, v0 = 1e30f, v1 = -1e30f;
  int taken = 0;
};

// a0 * x + (a1 * y + a2 * z), in the order Eigen sums a row of a 3x3 product (and a dot product):
// the four-at-a-time path must give the same floats as the one-at-a-time one.
inline __m128 row_times(const float* a, __m128 x, __m128 y, __m128 z) {
  return _mm_add_ps(_mm_mul_ps(_mm_set1_ps(a[0]), x),
                    _mm_add_ps(_mm_mul_ps(_mm_set1_ps(a[1]), y), _mm_mul_ps(_mm_set1_ps(a[2]), z)));
}

// The columns moved by to_uvz (rows: along, across, height) and uvz_t; those whose normal does
// not face down (up: the bin's vertical in the columns' frame) are written, in order, to rb.
Span project_columns(const OrientedColumns& c, const Eigen::Matrix3f& to_uvz, const Eigen::Vector3f& uvz_t,
                     const Eigen::Vector3f& up, RidgeBuffers* rb) {
  float m[3][3], upv[3] = {up.x(), up.y(), up.z()};
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) m[i][j] = to_uvz(i, j);
  const __m128 tu = _mm_set1_ps(uvz_t.x()), tv = _mm_set1_ps(uvz_t.y()), tz = _mm_set1_ps(uvz_t.z());
  const __m128 down = _mm_set1_ps(kFacingDown);
  __m128 lo_u = _mm_set1_ps(1e30f), hi_u = _mm_set1_ps(-1e30f), lo_v = lo_u, hi_v = hi_u;
  float *out_u = rb->u.data(), *out_v = rb->v.data(), *out_z = rb->z.data();
  int* out_i = rb->index.data();
  int n = 0;
  alignas(16) float lane_u[4], lane_v[4], lane_z[4];
  for (int k = 0; k < c.count; k += 4) {
    const int lanes = std::min(4, c.count - k);
    __m128 x, y, z, nx, ny, nz;
    if (lanes == 4) {
      x = _mm_loadu_ps(&c.x[std::size_t(k)]), y = _mm_loadu_ps(&c.y[std::size_t(k)]);
      z = _mm_loadu_ps(&c.z[std::size_t(k)]), nx = _mm_loadu_ps(&c.nx[std::size_t(k)]);
      ny = _mm_loadu_ps(&c.ny[std::size_t(k)]), nz = _mm_loadu_ps(&c.nz[std::size_t(k)]);
    } else {  // the last few: missing lanes get a normal of zero and are masked off below
      alignas(16) float b[6][4] = {};
      for (int j = 0; j < lanes; ++j) {
        const std::size_t q = std::size_t(k + j);
        b[0][j] = c.x[q], b[1][j] = c.y[q], b[2][j] = c.z[q], b[3][j] = c.nx[q], b[4][j] = c.ny[q],
        b[5][j] = c.nz[q];
      }
      x = _mm_load_ps(b[0]), y = _mm_load_ps(b[1]), z = _mm_load_ps(b[2]);
      nx = _mm_load_ps(b[3]), ny = _mm_load_ps(b[4]), nz = _mm_load_ps(b[5]);
    }
    const int keep = _mm_movemask_ps(_mm_cmpgt_ps(row_times(upv, nx, ny, nz), down)) & ((1 << lanes) - 1);
    if (keep == 0) continue;
    const __m128 u = _mm_add_ps(row_times(m[0], x, y, z), tu);
    const __m128 v = _mm_add_ps(row_times(m[1], x, y, z), tv);
    const __m128 h = _mm_add_ps(row_times(m[2], x, y, z), tz);
    // Extremes of the kept lanes only: the others stand in as +-1e30.
    const __m128 kept = _mm_castsi128_ps(
        _mm_set_epi32(keep & 8 ? -1 : 0, keep & 4 ? -1 : 0, keep & 2 ? -1 : 0, keep & 1 ? -1 : 0));
    const auto pick = [&](__m128 a, __m128 other) {
      return _mm_or_ps(_mm_and_ps(kept, a), _mm_andnot_ps(kept, other));
    };
    lo_u = _mm_min_ps(lo_u, pick(u, _mm_set1_ps(1e30f))),
    hi_u = _mm_max_ps(hi_u, pick(u, _mm_set1_ps(-1e30f)));
    lo_v = _mm_min_ps(lo_v, pick(v, _mm_set1_ps(1e30f))),
    hi_v = _mm_max_ps(hi_v, pick(v, _mm_set1_ps(-1e30f)));
    _mm_store_ps(lane_u, u), _mm_store_ps(lane_v, v), _mm_store_ps(lane_z, h);
    // Every lane is written at the next free place; only a kept one moves it on.
    for (int j = 0; j < 4; ++j) {
      out_u[n] = lane_u[j], out_v[n] = lane_v[j], out_z[n] = lane_z[j], out_i[n] = k + j;
      n += (keep >> j) & 1;
    }
  }
  Span s;
  alignas(16) float e[4][4];
  _mm_store_ps(e[0], lo_u), _mm_store_ps(e[1], hi_u), _mm_store_ps(e[2], lo_v), _mm_store_ps(e[3], hi_v);
  for (int j = 0; j < 4; ++j)
    s.u0 = std::min(s.u0, e[0][j]), s.u1 = std::max(s.u1, e[1][j]), s.v0 = std::min(s.v0, e[2][j]),
    s.v1 = std::max(s.v1, e[3][j]);
  s.taken = n;
  return s;
}

}  // namespace

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
  const auto taken = [&](int k) { return !pts.normals || pts.normals[k].dot(up_in_input) > kFacingDown; };
  const int stride = std::max(1, pts.stride);
  const int max_taken = rb->max_points;
  Span span;
  const bool by_columns = pts.columns && pts.columns->count <= max_taken;
  if (by_columns) {
    span = project_columns(*pts.columns, to_uvz, uvz_t, up_in_input, rb);
  } else {
    for (int k = 0; k < pts.count; k += stride) {
      if (!taken(k)) continue;
      const Eigen::Vector3f q = to_uvz * pts.points[k] + uvz_t;
      span.u0 = std::min(span.u0, q.x()), span.u1 = std::max(span.u1, q.x());
      span.v0 = std::min(span.v0, q.y()), span.v1 = std::max(span.v1, q.y());
      if (span.taken < max_taken) {
        const std::size_t i = std::size_t(span.taken);
        rb->u[i] = q.x(), rb->v[i] = q.y(), rb->z[i] = q.z(), rb->index[i] = k;
      }
      ++span.taken;
    }
  }
  const int n_taken = span.taken;
  if (n_taken == 0) return 0;
  const float u0 = span.u0, v0 = span.v0;
  // Rows are lines across the axis (fixed u); columns run across (v).
  const int rows = std::min(rb->rows, int((span.u1 - u0) / cell) + 1);
  const int cols = std::min(rb->cols, int((span.v1 - v0) / cell) + 1);
  constexpr float kNone = -std::numeric_limits<float>::infinity();
  // Only the occupied cells are visited, by their bits, and emptied again before returning: a
  // tube fills a band of the grid, not the grid.
  const float inv_cell = 1.0f / cell;
  float* top_z = rb->top_z.data();
  int* top_i = rb->top_i.data();
  const int row_words = rb->row_words;
  std::uint64_t* bits = rb->occupied_bits.data();
  // Branch-free: whether a point tops its cell is as good as random.
  const auto bin_cell = [&](int r_, int c, float z, int k) {
    const std::size_t cell_index = std::size_t(r_) * cols + c;
    const float old_z = top_z[cell_index];
    const int higher = -int(z > old_z);  // all ones or zero
    top_z[cell_index] = std::max(old_z, z);
    top_i[cell_index] = (k & higher) | (top_i[cell_index] & ~higher);
    bits[std::size_t(r_) * row_words + std::size_t(c >> 6)] |= std::uint64_t(1) << (c & 63);
  };
  const auto bin = [&](float u, float v, float z, int k) {
    const int r_ = int((u - u0) * inv_cell);
    const int c = int((v - v0) * inv_cell);
    if (r_ < 0 || c < 0 || r_ >= rows || c >= cols) return;
    bin_cell(r_, c, z, k);
  };
  if (n_taken <= max_taken) {
    // Rows and columns four at a time (the same truncation as bin's); the cells one at a time.
    const __m128 u0_4 = _mm_set1_ps(u0), v0_4 = _mm_set1_ps(v0), inv4 = _mm_set1_ps(inv_cell);
    const __m128i rows4 = _mm_set1_epi32(rows), cols4 = _mm_set1_epi32(cols), minus1 = _mm_set1_epi32(-1);
    alignas(16) int lane_r[4], lane_c[4];
    int k = 0;
    for (; k + 4 <= n_taken; k += 4) {
      const __m128i r4 =
          _mm_cvttps_epi32(_mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(&rb->u[std::size_t(k)]), u0_4), inv4));
      const __m128i c4 =
          _mm_cvttps_epi32(_mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(&rb->v[std::size_t(k)]), v0_4), inv4));
      const __m128i inside =
          _mm_and_si128(_mm_and_si128(_mm_cmpgt_epi32(r4, minus1), _mm_cmplt_epi32(r4, rows4)),
                        _mm_and_si128(_mm_cmpgt_epi32(c4, minus1), _mm_cmplt_epi32(c4, cols4)));
      _mm_store_si128(reinterpret_cast<__m128i*>(lane_r), r4);
      _mm_store_si128(reinterpret_cast<__m128i*>(lane_c), c4);
      const int in = _mm_movemask_ps(_mm_castsi128_ps(inside));
      for (int j = 0; j < 4; ++j)
        if (in & (1 << j))
          bin_cell(lane_r[j], lane_c[j], rb->z[std::size_t(k + j)], rb->index[std::size_t(k + j)]);
    }
    for (; k < n_taken; ++k) {
      const std::size_t i = std::size_t(k);
      bin(rb->u[i], rb->v[i], rb->z[i], rb->index[i]);
    }
  } else {  // more points than the buffers were sized for: projected again, none dropped
    for (int k = 0; k < pts.count; k += stride)
      if (taken(k)) {
        const Eigen::Vector3f q = to_uvz * pts.points[k] + uvz_t;
        bin(q.x(), q.y(), q.z(), k);
      }
  }
  const auto emit = [&](std::size_t cell_index) {
    const int k = rb->top_i[cell_index];
    if (!by_columns) return Eigen::Vector3f(r * pts.points[k] + t);
    const OrientedColumns& c = *pts.columns;
    return Eigen::Vector3f(
        r * Eigen::Vector3f(c.x[std::size_t(k)], c.y[std::size_t(k)], c.z[std::size_t(k)]) + t);
  };
  int n = 0;
  const int min_run = std::max(1, int(min_run_mm / cell));
  int* occupied = rb->occupied.data();
  float* occupied_z = rb->occupied_z.data();
  const int words = (cols + 63) / 64;
  for (int r_ = 0; r_ < rows; ++r_) {
    const std::size_t row0 = std::size_t(r_) * cols;
    float* zr = &rb->top_z[row0];
    std::uint64_t* row_bits = bits + std::size_t(r_) * row_words;
    // The occupied cells of the row, in order, and their heights, listed while the row is emptied.
    int m = 0;
    for (int w = 0; w < words; ++w) {
      for (std::uint64_t b = row_bits[w]; b != 0; b &= b - 1) {
        const int c = w * 64 + __builtin_ctzll(b);
        const float z = zr[c];  // still none where only a point of no height (NaN) fell
        occupied[m] = c, occupied_z[m] = z, m += z != kNone;
        zr[c] = kNone;
      }
      row_bits[w] = 0;
    }
    if (whole_surface) {
      for (int a = 0; a < m && n < capacity; ++a) out[n++] = emit(row0 + occupied[a]);
      continue;
    }
    // Runs are found on the list, where a run's end is one test per occupied cell.
    for (int a = 0; a < m && n < capacity;) {
      // A run tolerates one empty cell (sampling gaps): occupied cells at most two apart.
      int best = a, b = a;
      while (b + 1 < m && occupied[b + 1] - occupied[b] <= 2) {
        ++b;
        best = occupied_z[b] > occupied_z[best] ? b : best;
      }
      // Peaks at the edge of a run are slopes, not ridges.
      if (occupied[b] - occupied[a] + 1 >= min_run && best != a && best != b)
        out[n++] = emit(row0 + occupied[best]);
      a = b + 1;
    }
  }
  return n;
}

}  // namespace pipeloc
