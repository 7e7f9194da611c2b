#include "locate/rigid_fit.hpp"

#include <Eigen/Dense>

namespace pipeloc {

Pose fit_rigid(const Eigen::Vector3f* src, const Eigen::Vector3f* dst, int n, bool no_roll_on_line) {
  Eigen::Vector3d cs = Eigen::Vector3d::Zero(), cd = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) cs += src[i].cast<double>(), cd += dst[i].cast<double>();
  cs /= n;
  cd /= n;
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) h += (src[i].cast<double>() - cs) * (dst[i].cast<double>() - cd).transpose();
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  d(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0 ? -1 : 1;
  Eigen::Matrix3d r = svd.matrixV() * d * svd.matrixU().transpose();
  if (!no_roll_on_line) {
    Pose out = Pose::Identity();
    out.linear() = r;
    out.translation() = cd - out.linear() * cs;
    return out;
  }
  // Points along a line (a straight tube's ridge) leave the turn about that line to the noise:
  // the fit would roll the tube about its own top line, off the ridge, and the next pairs pull
  // it back. Below kLineSpreadRatio of cross spread to length spread, that turn is left out.
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i = 0; i < n; ++i) cov += (src[i].cast<double>() - cs) * (src[i].cast<double>() - cs).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> spread(cov);
  constexpr double kLineSpreadRatio = 0.1;
  const double along = spread.eigenvalues()(2), across = spread.eigenvalues()(1);
  if (along > 0 && across < kLineSpreadRatio * kLineSpreadRatio * along) {
    const Eigen::Vector3d line = spread.eigenvectors().col(2);
    const Eigen::AngleAxisd turn(r);
    Eigen::Vector3d v = turn.angle() * turn.axis();
    v -= v.dot(line) * line;
    const double angle = v.norm();
    r = angle > 0 ? Eigen::AngleAxisd(angle, v / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
  }
  Pose out = Pose::Identity();
  out.linear() = r;
  out.translation() = cd - out.linear() * cs;
  return out;
}

}  // namespace pipeloc
