// Nearest points in a small set, four at a time: the pairing step of the ridge ICP (2.2.1).
#pragma once

#include <Eigen/Core>
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
};

}  // namespace pipeloc
