#include "locate/rigid_fit.hpp"

#include <Eigen/Dense>

namespace pipeloc {

Pose fit_rigid(const Eigen::Vector3f* src, const Eigen::Vector3f* dst, int n) {
  Eigen::Vector3d cs = Eigen::Vector3d::Zero(), cd = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) cs += src[i].cast<double>(), cd += dst[i].cast<double>();
  cs /= n;
  cd /= n;
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) h += (src[i].cast<double>() - cs) * (dst[i].cast<double>() - cd).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  Pose out = Pose::Identity();
  out.linear() = svd.matrixV() * d * svd.matrixU().transpose();
  out.translation() = cd - out.linear() * cs;
  return out;
}

}  // namespace pipeloc
