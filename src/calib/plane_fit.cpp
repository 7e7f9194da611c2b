#include "calib/plane_fit.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace pipeloc {
namespace {

int count_inliers(const std::vector<Eigen::Vector3d>& pts, const Eigen::Vector3d& n, double d, double tol) {
  int count = 0;
  for (const Eigen::Vector3d& p : pts) count += std::abs(n.dot(p) + d) <= tol;
  return count;
}

// Least squares: through the inliers' centroid, normal along their covariance's least eigenvector.
bool refit(const std::vector<Eigen::Vector3d>& pts, double tol, PlaneFit* fit) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (const Eigen::Vector3d& p : pts)
    if (std::abs(fit->distance(p)) <= tol) sum += p, ++n;
  if (n < 3) return false;
  const Eigen::Vector3d centroid = sum / n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3d& p : pts)
    if (std::abs(fit->distance(p)) <= tol) cov += (p - centroid) * (p - centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d normal = eig.eigenvectors().col(0);
  if (normal.dot(fit->normal) < 0) normal = -normal;
  fit->normal = normal;
  fit->offset_mm = -normal.dot(centroid);
  return true;
}

}  // namespace

PlaneFit fit_plane_ransac(const std::vector<Eigen::Vector3d>& pts, const PlaneFitParams& params) {
  PlaneFit best;
  if (pts.size() < 3) return best;
  std::mt19937 rng(params.seed);
  std::uniform_int_distribution<std::size_t> pick(0, pts.size() - 1);
  const double min_cos = std::cos(params.max_normal_deg * M_PI / 180.0);
  const Eigen::Vector3d facing = params.facing.normalized();
  // Hypotheses are scored on a fixed sample (fast); the winner is refitted on every point.
  std::vector<Eigen::Vector3d> sample;
  const std::size_t stride = std::max<std::size_t>(1, pts.size() / 20000);
  for (std::size_t i = 0; i < pts.size(); i += stride) sample.push_back(pts[i]);
  int best_count = 0;
  for (int it = 0; it < params.iterations; ++it) {
    const Eigen::Vector3d &a = pts[pick(rng)], &b = pts[pick(rng)], &c = pts[pick(rng)];
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-6) continue;
    n.normalize();
    if (n.dot(facing) < 0) n = -n;
    if (n.dot(facing) < min_cos) continue;
    const int count = count_inliers(sample, n, -n.dot(a), params.inlier_mm);
    if (count > best_count) {
      best_count = count;
      best.normal = n;
      best.offset_mm = -n.dot(a);
    }
  }
  if (best_count < 3) return best;
  for (int r = 0; r < params.refits; ++r)
    if (!refit(pts, params.inlier_mm, &best)) return PlaneFit{};
  if (best.normal.dot(facing) < 0) best.normal = -best.normal, best.offset_mm = -best.offset_mm;
  double sq = 0;
  int n = 0;
  for (const Eigen::Vector3d& p : pts) {
    const double d = best.distance(p);
    if (std::abs(d) <= params.inlier_mm) sq += d * d, ++n;
  }
  best.inliers = n;
  best.inlier_share = double(n) / double(pts.size());
  best.rms_mm = n ? std::sqrt(sq / n) : 0;
  return best;
}

}  // namespace pipeloc
