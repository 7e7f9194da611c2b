#include "core/pose.hpp"

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace pipeloc {

Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& m) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixU() * svd.matrixV().transpose()).determinant() < 0 ? -1.0 : 1.0;
  return svd.matrixU() * d * svd.matrixV().transpose();
}

Pose pose_from_rt(const std::array<double, 9>& r, const std::array<double, 3>& t) {
  Eigen::Matrix3d m;
  m << r[0], r[1], r[2], r[3], r[4], r[5], r[6], r[7], r[8];
  Pose pose = Pose::Identity();
  pose.linear() = nearest_rotation(m);
  pose.translation() = Eigen::Vector3d(t[0], t[1], t[2]);
  return pose;
}

std::array<double, 9> rotation_rowmajor(const Pose& pose) {
  const Eigen::Matrix3d r = pose.linear();
  return {r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)};
}

std::array<double, 3> translation_mm(const Pose& pose) {
  return {pose.translation().x(), pose.translation().y(), pose.translation().z()};
}

double rotation_angle_deg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const double c = std::clamp(((a.transpose() * b).trace() - 1.0) / 2.0, -1.0, 1.0);
  return std::acos(c) * 180.0 / M_PI;
}

Pose pose_from_matrix_rowmajor(const double* m16) {
  Eigen::Matrix4d m;
  for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = m16[i];
  Pose p = Pose::Identity();
  p.linear() = nearest_rotation(m.topLeftCorner<3, 3>());
  p.translation() = m.topRightCorner<3, 1>();
  return p;
}

}  // namespace pipeloc
