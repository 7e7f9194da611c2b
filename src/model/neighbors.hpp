// Nearest neighbours in 3-D: the one place that talks to FLANN (kd-tree).
// Points are read from the caller's buffer, never copied; the buffer must outlive the tree.
#pragma once

#include <Eigen/Geometry>
#include <memory>
#include <vector>

namespace pipeloc {

class KdTree3 {
 public:
  KdTree3();
  ~KdTree3();
  KdTree3(const KdTree3&) = delete;
  KdTree3& operator=(const KdTree3&) = delete;

  // Index points[0..count). An empty cloud is valid: every query then finds nothing.
  void build(const Eigen::Vector3f* points, std::size_t count);
  std::size_t size() const { return count_; }

  // Nearest point to query; returns false (index -1, distance infinite) when there is none: an
  // empty tree or a query that is not finite.
  // `checks` bounds the leaves visited (FLANN's approximation knob; <= 0 means exact).
  bool nearest(const Eigen::Vector3f& query, int* index, float* dist_sq, int checks = -1) const;

  // Nearest point to query at most radius_mm away; false (index -1, distance infinite) when there
  // is none. Exact, and much cheaper than nearest() for a query far from every point: the search
  // prunes at the radius (the symmetry and slide searches land many samples off the surface).
  bool nearest_within(const Eigen::Vector3f& query, float radius_mm, int* index, float* dist_sq) const;

  // All points within radius_mm, written into caller-owned buffers of capacity `max_results`;
  // returns how many were written (closest first).
  int radius(const Eigen::Vector3f& query, float radius_mm, int* indices, float* dists_sq,
             int max_results) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::size_t count_ = 0;
};

}  // namespace pipeloc
