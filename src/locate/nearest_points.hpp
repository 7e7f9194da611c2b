// Nearest points in a small set, four at a time: the pairing step of the ridge ICP (2.2.1).
// Within a radius, only the slab of the set within it along its longest side is scanned.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

namespace pipeloc {

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
  // nearest_both_ways() where only partners within `radius` count: a partner within it is the
  // same one at the same squared distance (ties to the first as there); where none lies within
  // it, -1 and 1e30. Each a[i] scans only the points within the radius of it along the set's
  // longest side (sorted along it once per set), four at a time. Where those slabs would hold
  // most of the set, or the pairs are few, all pairs are scanned as nearest_both_ways() does.
  void nearest_both_ways_within(const Eigen::Vector3f* a, int na, float radius, int* a_to, float* a_d2,
                                int* b_to, float* b_d2);

 private:
  // The points sorted along the set's longest side `along_` (0, 1, 2: x, y, z): coordinates,
  // each one's index in x, y, z, the sort's keys, and per sorted point its partner's squared
  // distance and index.
  void sort_along();
  std::vector<float> sorted_x_, sorted_y_, sorted_z_, sorted_b_d2_;
  std::vector<int> sorted_index_, sorted_b_to_;
  std::vector<std::uint64_t> sorted_key_;
  int along_ = 0;
  bool sorted_ = false;     // the sorted columns are this set's (sorted on first need)
  float extent_along_ = 0;  // the set's extent along it
};

}  // namespace pipeloc
