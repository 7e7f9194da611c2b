#include "model/neighbors.hpp"

#include <cmath>
#include <flann/flann.hpp>
#include <limits>

namespace pipeloc {

struct KdTree3::Impl {
  std::unique_ptr<flann::Index<flann::L2_Simple<float>>> index;
};

KdTree3::KdTree3() : impl_(std::make_unique<Impl>()) {}
KdTree3::~KdTree3() = default;

void KdTree3::build(const Eigen::Vector3f* points, std::size_t count) {
  count_ = count;
  impl_->index.reset();
  if (count == 0) return;  // FLANN cannot index an empty matrix
  // Eigen::Vector3f is three packed floats, so the buffer is a count x 3 row-major matrix.
  flann::Matrix<float> data(const_cast<float*>(points[0].data()), count, 3);
  impl_->index =
      std::make_unique<flann::Index<flann::L2_Simple<float>>>(data, flann::KDTreeSingleIndexParams(10));
  impl_->index->buildIndex();
}

bool KdTree3::nearest(const Eigen::Vector3f& query, int* index, float* dist_sq, int checks) const {
  // Nothing found (an empty tree, a query FLANN cannot place, e.g. beyond float range): index -1
  // and an infinite distance, never an index a caller could read out of range with (tools/fuzz).
  *index = -1;
  *dist_sq = std::numeric_limits<float>::infinity();
  if (!impl_->index || !query.allFinite()) return false;
  flann::Matrix<float> q(const_cast<float*>(query.data()), 1, 3);
  flann::Matrix<int> idx(index, 1, 1);
  flann::Matrix<float> dst(dist_sq, 1, 1);
  flann::SearchParams params(checks <= 0 ? flann::FLANN_CHECKS_UNLIMITED : checks);
  if (impl_->index->knnSearch(q, idx, dst, 1, params) == 1 && *index >= 0 && std::size_t(*index) < count_)
    return true;
  *index = -1;
  *dist_sq = std::numeric_limits<float>::infinity();
  return false;
}

namespace {

// FLANN's radius search: at most max_results points closer than sqrt(radius_sq), closest first.
int within(const flann::Index<flann::L2_Simple<float>>& index, const Eigen::Vector3f& query, float radius_sq,
           int* indices, float* dists_sq, int max_results) {
  flann::Matrix<float> q(const_cast<float*>(query.data()), 1, 3);
  flann::Matrix<int> idx(indices, 1, std::size_t(max_results));
  flann::Matrix<float> dst(dists_sq, 1, std::size_t(max_results));
  flann::SearchParams params(flann::FLANN_CHECKS_UNLIMITED);
  params.max_neighbors = max_results;
  params.sorted = true;
  return index.radiusSearch(q, idx, dst, radius_sq, params);
}

}  // namespace

bool KdTree3::nearest_within(const Eigen::Vector3f& query, float radius_mm, int* index,
                             float* dist_sq) const {
  *index = -1;
  *dist_sq = std::numeric_limits<float>::infinity();
  if (!impl_->index || !query.allFinite() || !(radius_mm >= 0)) return false;
  int idx = -1;
  float d2 = 0;
  // FLANN keeps distances below the squared radius: the next float up keeps one at it too.
  const float r2 = std::nextafter(radius_mm * radius_mm, std::numeric_limits<float>::infinity());
  if (within(*impl_->index, query, r2, &idx, &d2, 1) != 1 || idx < 0 || std::size_t(idx) >= count_)
    return false;
  *index = idx;
  *dist_sq = d2;
  return true;
}

int KdTree3::radius(const Eigen::Vector3f& query, float radius_mm, int* indices, float* dists_sq,
                    int max_results) const {
  if (!impl_->index || max_results <= 0) return 0;
  return within(*impl_->index, query, radius_mm * radius_mm, indices, dists_sq, max_results);
}

}  // namespace pipeloc
