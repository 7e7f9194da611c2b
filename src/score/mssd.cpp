#include "score/mssd.hpp"

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

}  // namespace pipeloc
