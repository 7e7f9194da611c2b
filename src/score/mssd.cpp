#include "score/mssd.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

namespace pipeloc {
namespace {

double max_distance(const std::vector<Eigen::Vector3d>& vertices, const Eigen::Matrix4d& diff,
                    double stop_sq) {
  // diff = T_est^-1-free form: |A v + b| where A = R_est - R_true S, b = t_est - t_true S.
  const Eigen::Matrix3d a = diff.topLeftCorner<3, 3>();
  const Eigen::Vector3d b = diff.topRightCorner<3, 1>();
  double worst = 0;
  for (const auto& v : vertices) {
    worst = std::max(worst, (a * v + b).squaredNorm());
    if (worst > stop_sq) break;
  }
  return std::sqrt(worst);
}

}  // namespace

double mssd(const std::vector<Eigen::Vector3d>& vertices, const Pose& est, const Pose& truth,
            const std::vector<Pose>& symmetries, double cap_mm) {
  double best = std::numeric_limits<double>::infinity();
  auto consider = [&](const Pose& t) {
    const Eigen::Matrix4d diff = est.matrix() - t.matrix();
    const double limit = std::min(best, cap_mm);
    best = std::min(best, max_distance(vertices, diff, limit * limit));
  };
  consider(truth);
  for (const auto& s : symmetries) consider(truth * s);
  return best;
}

std::vector<Pose> with_tube_turns(const std::vector<Eigen::Vector3d>& vertices,
                                  const std::vector<Pose>& symmetries, int steps) {
  if (vertices.size() < 8) return symmetries;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& v : vertices) c += v;
  c /= double(vertices.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& v : vertices) cov += (v - c) * (v - c).transpose();
  const Eigen::Vector3d axis = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(2);
  std::vector<double> radius;
  for (const auto& v : vertices) radius.push_back(((v - c) - (v - c).dot(axis) * axis).norm());
  std::vector<double> sorted = radius;
  std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
  const double median = sorted[sorted.size() / 2];
  if (median <= 0 || *std::max_element(radius.begin(), radius.end()) > 1.03 * median) return symmetries;

  std::vector<Pose> out = symmetries;
  for (int k = 1; k < steps; ++k) {
    Pose turn = Pose::Identity();
    turn.linear() = Eigen::AngleAxisd(2 * M_PI * k / steps, axis).toRotationMatrix();
    turn.translation() = c - turn.linear() * c;
    out.push_back(turn);
    for (const auto& s : symmetries) out.push_back(turn * s);
  }
  return out;
}

}  // namespace pipeloc
