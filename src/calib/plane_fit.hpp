// A plane fitted robustly to a point cloud: RANSAC on random triples, then a least-squares refit
// (the eigenvector of least spread) on the inliers, repeated while the inlier set changes.
#pragma once

#include <Eigen/Core>
#include <random>
#include <vector>

namespace pipeloc {

struct PlaneFitParams {
  double inlier_mm = 8;              // RANSAC: a point this close to the plane supports it
  int iterations = 400;              // random triples tried
  double max_normal_deg = 90;        // planes whose normal is farther than this from `facing` are skipped
  Eigen::Vector3d facing{0, 0, -1};  // e.g. towards the camera: -z in the camera frame
  int refits = 5;                    // least-squares refits on the inliers
  unsigned seed = 1;
};

struct PlaneFit {
  Eigen::Vector3d normal{0, 0, 1};  // unit, with normal . facing > 0
  double offset_mm = 0;             // plane: normal . p + offset_mm = 0
  int inliers = 0;
  double inlier_share = 0;  // of all points given
  double rms_mm = 0;        // of the inliers' distances, after the refit
  double distance(const Eigen::Vector3d& p) const { return normal.dot(p) + offset_mm; }
};

// points: in any frame (mm). Returns inliers = 0 when no plane was found.
PlaneFit fit_plane_ransac(const std::vector<Eigen::Vector3d>& points, const PlaneFitParams& params);

}  // namespace pipeloc
