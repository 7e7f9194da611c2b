#include "locate/nearest_points.hpp"

#include <emmintrin.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

namespace pipeloc {
namespace {

constexpr float kFar = 1e30f;  // "no partner" distance
// The slab scanned reaches this much beyond the radius, so that a partner within it is never
// outside the slab by the rounding of a coordinate.
constexpr float kSlabMargin = 1.01f;
// Slabs wider than this share of the set's extent hold most of it: the bookkeeping of slabs
// costs more than it spares, and all pairs are scanned (compact sets such as a coil's ridge, the
// wide gates of the first iterations).
constexpr float kSlabOfExtent = 0.5f;
// Fewer pairs than this are scanned sooner than the set is sorted.
constexpr int kMinPairsForSlabs = 128 * 128;

// Squared distances from q to points j..j+3 of the columns, summed as the one-at-a-time tail sums
// them ((p - q)^2 equals (q - p)^2 exactly, so either side's search gets the same floats).
inline __m128 distances4(const float* xs, const float* ys, const float* zs, int j, __m128 qx, __m128 qy,
                         __m128 qz) {
  const __m128 dx = _mm_sub_ps(_mm_loadu_ps(xs + j), qx), dy = _mm_sub_ps(_mm_loadu_ps(ys + j), qy),
               dz = _mm_sub_ps(_mm_loadu_ps(zs + j), qz);
  return _mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz));
}

// The one-at-a-time tail's squared distance from q to point j, summed as distances4() sums it.
inline float distance2(const float* xs, const float* ys, const float* zs, int j, const Eigen::Vector3f& q) {
  const float dx = xs[j] - q.x(), dy = ys[j] - q.y(), dz = zs[j] - q.z();
  return dx * dx + dy * dy + dz * dz;
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

// Per lane, the least distance so far and the least index at it: the points come in an order other
// than their indices', so an equal distance takes the lower index.
inline void keep_lowest_least(__m128 d, __m128i index4, __m128* low4, __m128i* at4) {
  const __m128i take =
      _mm_or_si128(_mm_castps_si128(_mm_cmplt_ps(d, *low4)),
                   _mm_and_si128(_mm_castps_si128(_mm_cmpeq_ps(d, *low4)), _mm_cmplt_epi32(index4, *at4)));
  *low4 = _mm_min_ps(d, *low4);
  *at4 = _mm_or_si128(_mm_and_si128(take, index4), _mm_andnot_si128(take, *at4));
}

// The other side's partners, held in memory for points j..j+3: query i (queries come in order)
// replaces one only when strictly closer, so ties keep the first.
inline void keep_first_least_held(__m128 d, __m128i i4, float* held_d2, int* held_to) {
  __m128 held = _mm_loadu_ps(held_d2);
  __m128i to = _mm_loadu_si128(reinterpret_cast<const __m128i*>(held_to));
  keep_first_least(d, i4, &held, &to);
  _mm_storeu_ps(held_d2, held);
  _mm_storeu_si128(reinterpret_cast<__m128i*>(held_to), to);
}

// Partners farther than sqrt(r2) are none: -1 at kFar.
inline void forget_beyond(float r2, float* d2, int* to, int count) {
  for (int k = 0; k < count; ++k)
    if (!(d2[k] <= r2)) d2[k] = kFar, to[k] = -1;
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
    const float d = distance2(xs, ys, zs, i, q);
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
      keep_first_least_held(d, i4, b_d2 + j, b_to + j);  // b's side
    }
    int best;
    float low = first_least_of_lanes(low4, at4, &best);
    for (; j < n; ++j) {
      const float d = distance2(xs, ys, zs, j, q);
      if (d < low) low = d, best = j;
      if (d < b_d2[j]) b_d2[j] = d, b_to[j] = i;
    }
    a_d2[i] = low;
    a_to[i] = low < 1e30f ? best : -1;
  }
  // (b_to[j] stays -1 unless some a[i] came strictly under 1e30: no clean-up needed)
}

// For each a[i], the slab of the sorted points whose coordinate along the longest side lies within
// the radius of a[i]'s (every partner within the radius lies in it), scanned four at a time as
// nearest_both_ways() scans all: the same distances, the same partners up to the radius.
void PointColumns::nearest_both_ways_within(const Eigen::Vector3f* a, int na, float radius, int* a_to,
                                            float* a_d2, int* b_to, float* b_d2) {
  const float r2 = radius * radius, slab = radius * kSlabMargin;
  // Slabs that hold most of the set, or few pairs in all: scan all pairs.
  if (!(2 * slab < kSlabOfExtent * extent_along_) || na * n < kMinPairsForSlabs) {
    nearest_both_ways(a, na, a_to, a_d2, b_to, b_d2);
    forget_beyond(r2, a_d2, a_to, na);
    forget_beyond(r2, b_d2, b_to, n);
    return;
  }
  if (!sorted_) sort_along();
  const float *xs = sorted_x_.data(), *ys = sorted_y_.data(), *zs = sorted_z_.data();
  const float* along = along_ == 0 ? xs : along_ == 1 ? ys : zs;
  const int* index = sorted_index_.data();
  float* held_d2 = sorted_b_d2_.data();
  int* held_to = sorted_b_to_.data();
  std::fill_n(held_d2, n, kFar);
  std::fill_n(held_to, n, -1);
  for (int i = 0; i < na; ++i) {
    const Eigen::Vector3f& q = a[i];
    const float key = q[along_];
    const int begin = int(std::lower_bound(along, along + n, key - slab) - along);
    const int end = int(std::upper_bound(along + begin, along + n, key + slab) - along);
    const __m128 qx = _mm_set1_ps(q.x()), qy = _mm_set1_ps(q.y()), qz = _mm_set1_ps(q.z());
    const __m128i i4 = _mm_set1_epi32(i);
    __m128 low4 = _mm_set1_ps(kFar);
    __m128i at4 = _mm_set1_epi32(-1);
    int j = begin;
    for (; j + 4 <= end; j += 4) {
      const __m128 d = distances4(xs, ys, zs, j, qx, qy, qz);
      keep_lowest_least(d, _mm_loadu_si128(reinterpret_cast<const __m128i*>(index + j)), &low4, &at4);
      keep_first_least_held(d, i4, held_d2 + j, held_to + j);
    }
    int best;
    float low = first_least_of_lanes(low4, at4, &best);
    for (; j < end; ++j) {
      const float d = distance2(xs, ys, zs, j, q);
      if (d < low || (d == low && index[j] < best)) low = d, best = index[j];
      if (d < held_d2[j]) held_d2[j] = d, held_to[j] = i;
    }
    a_d2[i] = low;
    a_to[i] = best;
  }
  for (int k = 0; k < n; ++k) b_d2[index[k]] = held_d2[k], b_to[index[k]] = held_to[k];
  forget_beyond(r2, a_d2, a_to, na);
  forget_beyond(r2, b_d2, b_to, n);
}

void PointColumns::reserve(int capacity) {
  for (auto* column : {&x, &y, &z, &sorted_x_, &sorted_y_, &sorted_z_, &sorted_b_d2_})
    column->assign(std::size_t(capacity), 0.0f);
  sorted_index_.assign(std::size_t(capacity), 0);
  sorted_key_.assign(std::size_t(capacity), 0);
  sorted_b_to_.assign(std::size_t(capacity), -1);
  n = 0;
}

bool PointColumns::assign(const Eigen::Vector3f* p, int count) {
  if (count > int(x.size())) return false;
  Eigen::Vector3f low = Eigen::Vector3f::Constant(kFar), high = -low;
  for (int i = 0; i < count; ++i) {
    x[std::size_t(i)] = p[i].x(), y[std::size_t(i)] = p[i].y(), z[std::size_t(i)] = p[i].z();
    low = low.cwiseMin(p[i]), high = high.cwiseMax(p[i]);
  }
  n = count;
  const Eigen::Vector3f extent = high - low;
  along_ = extent.x() >= extent.y() && extent.x() >= extent.z() ? 0 : extent.y() >= extent.z() ? 1 : 2;
  extent_along_ = n > 0 ? extent[along_] : 0.0f;
  sorted_ = false;
  return true;
}

// The points sorted along the longest side, once per set: each one's coordinate there as an
// unsigned int in the same order as the floats (not-a-number as infinity: last), its index below
// it, so a plain sort of integers gives the order and ties to the lower index.
void PointColumns::sort_along() {
  const float* along = along_ == 0 ? x.data() : along_ == 1 ? y.data() : z.data();
  std::uint64_t* key = sorted_key_.data();
  for (int j = 0; j < n; ++j) {
    const float v = std::isnan(along[j]) ? HUGE_VALF : along[j];
    std::uint32_t bits;
    std::memcpy(&bits, &v, sizeof bits);
    bits = bits & 0x80000000u ? ~bits : bits | 0x80000000u;
    key[j] = (std::uint64_t(bits) << 32) | std::uint32_t(j);
  }
  std::sort(key, key + n);
  for (int k = 0; k < n; ++k) {
    const int j = int(key[k] & 0xffffffffu);
    sorted_index_[std::size_t(k)] = j;
    sorted_x_[std::size_t(k)] = x[std::size_t(j)];
    sorted_y_[std::size_t(k)] = y[std::size_t(j)];
    sorted_z_[std::size_t(k)] = z[std::size_t(j)];
  }
  sorted_ = true;
}

}  // namespace pipeloc
