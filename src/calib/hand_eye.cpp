#include "calib/hand_eye.hpp"

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace pipeloc {
namespace {

Pose umeyama_fit(const std::vector<Eigen::Vector3d>& cam, const std::vector<Eigen::Vector3d>& robot,
                 const std::vector<bool>& skip) {
  int n = 0;
  for (bool s : skip) n += !s;
  Eigen::Matrix3Xd src(3, n), dst(3, n);
  for (std::size_t i = 0, j = 0; i < cam.size(); ++i)
    if (!skip[i]) src.col(Eigen::Index(j)) = cam[i], dst.col(Eigen::Index(j)) = robot[i], ++j;
  Pose p;
  p.matrix() = Eigen::umeyama(src, dst, false);
  return p;
}

// Spread of the stations across their second direction (mm, RMS): ~0 when they lie on a line.
double second_spread_mm(const std::vector<Eigen::Vector3d>& pts) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : pts) mean += p;
  mean /= double(pts.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : pts) cov += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov / double(pts.size()));
  return std::sqrt(std::max(0.0, eig.eigenvalues()(1)));
}

}  // namespace

HandEyeResult solve_hand_eye(const std::vector<Eigen::Vector3d>& cam,
                             const std::vector<Eigen::Vector3d>& robot, double outlier_factor,
                             double outlier_floor_mm) {
  HandEyeResult r;
  const std::size_t n = cam.size();
  if (n != robot.size() || n < 4) {
    r.error = "need at least 4 stations, got " + std::to_string(std::min(n, robot.size()));
    return r;
  }
  if (second_spread_mm(cam) < 10) {
    r.error =
        "the sphere positions lie nearly on one line (spread across it under 10 mm): move the robot "
        "to stations that span a plane or a volume";
    return r;
  }
  r.outlier.assign(n, false);
  auto residuals = [&] {
    r.residual_mm.resize(n);
    for (std::size_t i = 0; i < n; ++i) r.residual_mm[i] = (r.robot_from_camera * cam[i] - robot[i]).norm();
  };
  r.robot_from_camera = umeyama_fit(cam, robot, r.outlier);
  residuals();
  std::vector<double> sorted = r.residual_mm;
  std::nth_element(sorted.begin(), sorted.begin() + long(n / 2), sorted.end());
  const double median = sorted[n / 2];
  int outliers = 0;
  for (std::size_t i = 0; i < n; ++i) {
    r.outlier[i] = r.residual_mm[i] > std::max(outlier_factor * median, outlier_floor_mm);
    outliers += r.outlier[i];
  }
  // Solved again without them, when 4 stations are left; otherwise only flagged.
  const bool drop = outliers > 0 && int(n) - outliers >= 4;
  if (drop) {
    r.robot_from_camera = umeyama_fit(cam, robot, r.outlier);
    residuals();
  }
  double sq = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (!drop || !r.outlier[i]) sq += r.residual_mm[i] * r.residual_mm[i], ++r.used;
  r.rms_mm = std::sqrt(sq / r.used);
  r.ok = true;
  return r;
}

}  // namespace pipeloc
