#include "locate/nearest_points.hpp"

#include <emmintrin.h>

#include <algorithm>

namespace pipeloc {
namespace {

// Squared distances from q to points j..j+3 of the columns, summed as the one-at-a-time tail sums
// them ((p - q)^2 equals (q - p)^2 exactly, so either side's search gets the same floats).
inline __m128 distances4(const float* xs, const float* ys, const float* zs, int j, __m128 qx, __m128 qy,
                         __m128 qz) {
  const __m128 dx = _mm_sub_ps(_mm_loadu_ps(xs + j), qx), dy = _mm_sub_ps(_mm_loadu_ps(ys + j), qy),
               dz = _mm_sub_ps(_mm_loadu_ps(zs + j), qz);
  return _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
}

// Per lane, the least distance so far and the first index at it: a later one replaces it only
// when strictly closer.
inline void keep_first_least(__m128 d, __m128i index4, __m128* low4, __m128i* at4) {
  const __m128i closer = _mm_castps_si128(_mm_cmplt_ps(d, *low4));
  *low4 = _mm_min_ps(d, *low4);
  *at4 = _mm_or_si128(_mm_and_si128(closer, index4), _mm_andnot_si128(closer, *at4));
}

// The least of the lanes' distances, and of the points at it the first (-1 if none).
inline float first_least_of_lanes(__m128 low4, __m128i at4, int* best) {
  alignas(16) float lanes[4];
  alignas(16) int lane_at[4];
  _mm_store_ps(lanes, low4);
  _mm_store_si128(reinterpret_cast<__m128i*>(lane_at), at4);
  float low = 1e30f;
  *best = -1;
  for (int l = 0; l < 4; ++l)
    if (lanes[l] < low || (lanes[l] == low && lane_at[l] >= 0 && lane_at[l] < *best))
      low = lanes[l], *best = lane_at[l];
  return low;
}

}  // namespace

// nearest() on columns, four points at a time: each lane keeps its least distance and the first
// point at it; the lanes then give the least, and of the points at it the first. Same sums in the
// same order, same answer.
int PointColumns::nearest(const Eigen::Vector3f& q, float* d2) const {
  const float *xs = x.data(), *ys = y.data(), *zs = z.data();
  const __m128 qx = _mm_set1_ps(q.x()), qy = _mm_set1_ps(q.y()), qz = _mm_set1_ps(q.z());
  __m128 low4 = _mm_set1_ps(1e30f);
  __m128i at4 = _mm_set1_epi32(-1), index4 = _mm_setr_epi32(0, 1, 2, 3);
  const __m128i four = _mm_set1_epi32(4);
  int i = 0;
  for (; i + 4 <= n; i += 4, index4 = _mm_add_epi32(index4, four))
    keep_first_least(distances4(xs, ys, zs, i, qx, qy, qz), index4, &low4, &at4);
  int best;
  float low = first_least_of_lanes(low4, at4, &best);
  for (; i < n; ++i) {  // the last few lie after every lane's
    const float dx = xs[i] - q.x(), dy = ys[i] - q.y(), dz = zs[i] - q.z();
    const float d = dx * dx + dy * dy + dz * dz;
    if (d < low) low = d, best = i;
  }
  *d2 = low;
  return low < 1e30f ? best : -1;
}

void PointColumns::nearest_both_ways(const Eigen::Vector3f* a, int na, int* a_to, float* a_d2, int* b_to,
                                     float* b_d2) const {
  const float *xs = x.data(), *ys = y.data(), *zs = z.data();
  std::fill_n(b_d2, n, 1e30f);
  std::fill_n(b_to, n, -1);
  const __m128i four = _mm_set1_epi32(4);
  for (int i = 0; i < na; ++i) {
    const Eigen::Vector3f& q = a[i];
    const __m128 qx = _mm_set1_ps(q.x()), qy = _mm_set1_ps(q.y()), qz = _mm_set1_ps(q.z());
    const __m128i i4 = _mm_set1_epi32(i);
    __m128 low4 = _mm_set1_ps(1e30f);
    __m128i at4 = _mm_set1_epi32(-1), index4 = _mm_setr_epi32(0, 1, 2, 3);
    int j = 0;
    for (; j + 4 <= n; j += 4, index4 = _mm_add_epi32(index4, four)) {
      const __m128 d = distances4(xs, ys, zs, j, qx, qy, qz);
      keep_first_least(d, index4, &low4, &at4);
      // b's side: a strictly closer a[i] replaces the one held, so ties keep the first
      __m128 held = _mm_loadu_ps(b_d2 + j);
      __m128i held_to = _mm_loadu_si128(reinterpret_cast<const __m128i*>(b_to + j));
      keep_first_least(d, i4, &held, &held_to);
      _mm_storeu_ps(b_d2 + j, held);
      _mm_storeu_si128(reinterpret_cast<__m128i*>(b_to + j), held_to);
    }
    int best;
    float low = first_least_of_lanes(low4, at4, &best);
    for (; j < n; ++j) {
      const float dx = xs[j] - q.x(), dy = ys[j] - q.y(), dz = zs[j] - q.z();
      const float d = dx * dx + dy * dy + dz * dz;
      if (d < low) low = d, best = j;
      if (d < b_d2[j]) b_d2[j] = d, b_to[j] = i;
    }
    a_d2[i] = low;
    a_to[i] = low < 1e30f ? best : -1;
  }
  // (b_to[j] stays -1 unless some a[i] came strictly under 1e30: no clean-up needed)
}

void PointColumns::reserve(int capacity) {
  x.assign(std::size_t(capacity), 0.0f);
  y.assign(std::size_t(capacity), 0.0f);
  z.assign(std::size_t(capacity), 0.0f);
  n = 0;
}

bool PointColumns::assign(const Eigen::Vector3f* p, int count) {
  if (count > int(x.size())) return false;
  for (int i = 0; i < count; ++i)
    x[std::size_t(i)] = p[i].x(), y[std::size_t(i)] = p[i].y(), z[std::size_t(i)] = p[i].z();
  n = count;
  return true;
}

}  // namespace pipeloc
