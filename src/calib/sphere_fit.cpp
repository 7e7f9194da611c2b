#include "calib/sphere_fit.hpp"

#include <Eigen/Dense>
#include <cmath>
#include <random>

namespace pipeloc {
namespace {

// Centres of the spheres of radius r through a, b, c: the circumcentre of the triangle moved
// along its normal; the one farther from the camera (the visible cap faces the camera).
bool sphere_through(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, double r,
                    Eigen::Vector3d* centre) {
  const Eigen::Vector3d ab = b - a, ac = c - a, n = ab.cross(ac);
  const double n2 = n.squaredNorm();
  if (n2 < 1e-9) return false;
  const Eigen::Vector3d to_cc = (ac.squaredNorm() * n.cross(ab) + ab.squaredNorm() * ac.cross(n)) / (2 * n2);
  const double h2 = r * r - to_cc.squaredNorm();
  if (h2 < 0) return false;
  const Eigen::Vector3d cc = a + to_cc, unit = n / std::sqrt(n2);
  const Eigen::Vector3d c1 = cc + std::sqrt(h2) * unit, c2 = cc - std::sqrt(h2) * unit;
  *centre = c1.z() > c2.z() ? c1 : c2;
  return true;
}

struct Window {
  int u0, v0, u1, v1;
};
Window window_of(const Eigen::Vector3d& centre, double r, const Intrinsics& k, const Image<float>& depth) {
  const Eigen::Vector2d px = k.project(centre);
  const double rad = 1.3 * r * k.fx / centre.z() + 2;
  return {std::max(0, int(px.x() - rad)), std::max(0, int(px.y() - rad)),
          std::min(depth.width - 1, int(px.x() + rad)), std::min(depth.height - 1, int(px.y() + rad))};
}

// Pixels on the cap minus those that rule the sphere out: seen inside it, or seen through it
// (beyond it, within its outline). A plane touching a sphere leaves few on the cap.
int cap_score(const Image<float>& depth, const Intrinsics& k, const Eigen::Vector3d& c,
              const SphereFitParams& p, int* inliers) {
  const Window w = window_of(c, p.radius_mm, k, depth);
  int on = 0, inside = 0, through = 0;
  for (int v = w.v0; v <= w.v1; ++v)
    for (int u = w.u0; u <= w.u1; ++u) {
      const float d = depth.at(u, v);
      if (!(d > 0)) continue;
      const Eigen::Vector3d q = k.unproject(u, v, d);
      const double e = (q - c).norm() - p.radius_mm;
      on += std::abs(e) <= p.inlier_mm;
      inside += e < -p.inlier_mm;
      // Beyond the sphere's centre and closer to its line of sight than the radius: seen through.
      const Eigen::Vector3d ray = q.normalized();
      through += q.z() > c.z() && e > p.inlier_mm && (c - ray * ray.dot(c)).norm() < p.radius_mm;
    }
  *inliers = on;
  return on - inside - through;
}

}  // namespace

SphereFit find_sphere(const Image<float>& depth, const Intrinsics& k, const SphereFitParams& p) {
  SphereFit fit;
  std::vector<int> valid;
  for (int i = 0; i < int(depth.pixels.size()); ++i)
    if (depth.pixels[std::size_t(i)] > 0) valid.push_back(i);
  if (valid.size() < 10) return fit;
  std::mt19937 rng(p.seed);
  std::uniform_int_distribution<std::size_t> pick(0, valid.size() - 1);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  auto point = [&](int u, int v) { return k.unproject(u, v, depth.at(u, v)); };
  int best_score = 0;
  for (int it = 0; it < p.iterations; ++it) {
    const int i = valid[pick(rng)], u = i % depth.width, v = i / depth.width;
    const Eigen::Vector3d a = point(u, v);
    const double reach_px = p.radius_mm * k.fx / a.z();  // the others within a radius of it
    Eigen::Vector3d others[2];
    bool got = true;
    for (Eigen::Vector3d& o : others) {
      const int ou = u + int(std::lround(unit(rng) * reach_px)),
                ov = v + int(std::lround(unit(rng) * reach_px));
      if (ou < 0 || ov < 0 || ou >= depth.width || ov >= depth.height || !(depth.at(ou, ov) > 0)) {
        got = false;
        break;
      }
      o = point(ou, ov);
    }
    Eigen::Vector3d c;
    if (!got || !sphere_through(a, others[0], others[1], p.radius_mm, &c)) continue;
    int inliers = 0;
    const int score = cap_score(depth, k, c, p, &inliers);
    if (score > best_score) best_score = score, fit.centre_mm = c;
  }
  if (best_score == 0) return fit;
  // Gauss-Newton on the centre, radius fixed: residual |p - c| - r over the cap's pixels.
  for (int iter = 0; iter < 15; ++iter) {
    const Window w = window_of(fit.centre_mm, p.radius_mm, k, depth);
    Eigen::Matrix3d jtj = Eigen::Matrix3d::Zero();
    Eigen::Vector3d jtr = Eigen::Vector3d::Zero();
    double sq = 0;
    int n = 0;
    for (int v = w.v0; v <= w.v1; ++v)
      for (int u = w.u0; u <= w.u1; ++u) {
        if (!(depth.at(u, v) > 0)) continue;
        const Eigen::Vector3d q = point(u, v) - fit.centre_mm;
        const double dist = q.norm(), e = dist - p.radius_mm;
        if (std::abs(e) > p.inlier_mm || dist < 1e-9) continue;
        const Eigen::Vector3d j = -q / dist;
        jtj += j * j.transpose(), jtr += j * e, sq += e * e, ++n;
      }
    if (n < 10) return SphereFit{};
    const Eigen::Vector3d step = -jtj.ldlt().solve(jtr);
    fit.centre_mm += step;
    fit.inliers = n;
    fit.rms_mm = std::sqrt(sq / n);
    if (step.norm() < 1e-4) break;
  }
  const double r_px = p.radius_mm * k.fx / fit.centre_mm.z();
  fit.expected_px = int(M_PI * r_px * r_px);
  // The refined sphere must still leave nothing seen inside or through it.
  int on = 0;
  const int score = cap_score(depth, k, fit.centre_mm, p, &on);
  fit.ok = score >= p.min_cap_share * fit.expected_px;
  return fit;
}

}  // namespace pipeloc
