#include "model/slides.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <queue>

#include "model/neighbors.hpp"

namespace pipeloc {
namespace {

constexpr std::size_t kMaxCentrePoints = 4000;  // enough for a few points per mm of any pipe
constexpr int kMaxNeighbours = 48;
constexpr float kLinkOfD = 0.5f;   // centre points this close are neighbours along the tube
constexpr float kStepOfD = 0.25f;  // the polyline's step
constexpr float kMinReached = 0.9f;  // of the centre points: fewer and the cloud is not one tube
constexpr std::size_t kLandingSamples = 1500;

// Distances through the cloud from `from` along links shorter than link_mm (Dijkstra).
std::vector<float> distances_through(const std::vector<Eigen::Vector3f>& pts, const KdTree3& tree, int from,
                                     float link_mm) {
  std::vector<float> dist(pts.size(), std::numeric_limits<float>::infinity());
  using Item = std::pair<float, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> open;
  dist[std::size_t(from)] = 0;
  open.push({0.0f, from});
  int idx[kMaxNeighbours];
  float d2[kMaxNeighbours];
  while (!open.empty()) {
    const auto [d, at] = open.top();
    open.pop();
    if (d > dist[std::size_t(at)]) continue;
    const int found = tree.radius(pts[std::size_t(at)], link_mm, idx, d2, kMaxNeighbours);
    for (int k = 0; k < found; ++k) {
      const float nd = d + std::sqrt(d2[k]);
      if (nd < dist[std::size_t(idx[k])]) dist[std::size_t(idx[k])] = nd, open.push({nd, idx[k]});
    }
  }
  return dist;
}

int farthest_reached(const std::vector<float>& dist) {
  int best = 0;
  for (std::size_t i = 0; i < dist.size(); ++i)
    if (std::isfinite(dist[i]) && dist[i] > dist[std::size_t(best)]) best = int(i);
  return best;
}

}  // namespace

Centreline centreline_of(const SurfaceSamples& surface, float d) {
  Centreline out;
  if (surface.points.size() < 10 || !(d > 0)) return out;
  const std::size_t stride = std::max<std::size_t>(1, surface.points.size() / kMaxCentrePoints);
  std::vector<Eigen::Vector3f> centres;
  for (std::size_t i = 0; i < surface.points.size(); i += stride)
    centres.push_back(surface.points[i] - 0.5f * d * surface.normals[i]);
  KdTree3 tree;
  tree.build(centres.data(), centres.size());
  const float link = kLinkOfD * d;
  // From an end: the point farthest through the cloud from any point is one.
  const int end = farthest_reached(distances_through(centres, tree, 0, link));
  const std::vector<float> along = distances_through(centres, tree, end, link);
  // Binned along the distance and averaged (the links zig-zag: the bins' own spacing is the length).
  const float bin = std::max(0.5f, kStepOfD * d);
  float longest = 0;
  std::size_t reached = 0;
  for (float a : along)
    if (std::isfinite(a)) longest = std::max(longest, a), ++reached;
  if (float(reached) < kMinReached * float(centres.size())) return out;
  const std::size_t bins = std::size_t(longest / bin) + 1;
  std::vector<Eigen::Vector3f> sum(bins, Eigen::Vector3f::Zero());
  std::vector<int> count(bins, 0);
  for (std::size_t i = 0; i < centres.size(); ++i) {
    if (!std::isfinite(along[i])) continue;
    const std::size_t b = std::min(bins - 1, std::size_t(along[i] / bin));
    sum[b] += centres[i], ++count[b];
  }
  std::vector<Eigen::Vector3f> coarse;
  for (std::size_t b = 0; b < bins; ++b)
    if (count[b] > 0) coarse.push_back(sum[b] / float(count[b]));
  if (coarse.size() < 2) return out;
  // Resampled at equal steps of its own length.
  out.step_mm = bin;
  out.points.push_back(coarse[0]);
  float carried = 0;  // length walked since the last point written
  for (std::size_t i = 1; i < coarse.size(); ++i) {
    const Eigen::Vector3f a = coarse[i - 1], b = coarse[i];
    const float seg = (b - a).norm();
    float at = bin - carried;
    while (at <= seg) {
      out.points.push_back(a + (b - a) * (at / seg));
      at += bin;
    }
    carried = seg - (at - bin);
  }
  return out;
}

Pose best_reversal(const Centreline& line) {
  const int n = int(line.points.size());
  Pose best = Pose::Identity();
  if (n < 8) return best;
  constexpr int kCentresTried = 200;  // centres tried at most: every L / 200 along the line
  const int step = std::max(1, n / kCentresTried);
  double best_cost = std::numeric_limits<double>::infinity();
  for (int c = n / 4; c <= n - 1 - n / 4; c += step) {
    const int m = std::min(c, n - 1 - c);  // pairs each side: c - u with c + u
    Eigen::Matrix3Xd from(3, 2 * m), to(3, 2 * m);
    for (int u = 1; u <= m; ++u) {
      const Eigen::Vector3d a = line.points[std::size_t(c - u)].cast<double>();
      const Eigen::Vector3d b = line.points[std::size_t(c + u)].cast<double>();
      from.col(2 * (u - 1)) = a, to.col(2 * (u - 1)) = b;
      from.col(2 * (u - 1) + 1) = b, to.col(2 * (u - 1) + 1) = a;
    }
    Pose m_pose;
    m_pose.matrix() = Eigen::umeyama(from, to, false);
    if (!m_pose.matrix().allFinite()) continue;
    m_pose.linear() = nearest_rotation(m_pose.linear());
    double sq = 0;
    for (int i = 0; i < 2 * m; ++i) sq += (m_pose * from.col(i) - to.col(i)).squaredNorm();
    // Ties (an arc, a coil, a straight run map onto themselves reversed about any of their
    // points) go to the middle: a millimetre of fit per 100 mm of the line left unshared.
    constexpr double kUnsharedWeight = 0.01;
    const double cost =
        std::sqrt(sq / double(2 * m)) + kUnsharedWeight * double(n - 1 - 2 * m) * line.step_mm;
    if (cost < best_cost) best_cost = cost, best = m_pose;
  }
  return best;
}

std::vector<Slide> find_slides(const SurfaceIndex& surface, const Centreline& line, float d,
                               const std::vector<float>& arc_mm, float tolerance_mm, float min_share) {
  std::vector<Slide> found;
  const int n = int(line.points.size());
  if (n < 4) return found;
  for (float s : arc_mm) {
    const int k = int(std::lround(s / line.step_mm));
    if (k <= 0 || n - k < 3) continue;
    for (int sign : {1, -1}) {
      // Pairs: the centreline onto itself moved by s (by -s: the same pairs the other way).
      Eigen::Matrix3Xd from(3, n - k), to(3, n - k);
      for (int i = 0; i + k < n; ++i) {
        const Eigen::Vector3d a = line.points[std::size_t(i)].cast<double>();
        const Eigen::Vector3d b = line.points[std::size_t(i + k)].cast<double>();
        from.col(i) = sign > 0 ? a : b, to.col(i) = sign > 0 ? b : a;
      }
      Pose m;
      m.matrix() = Eigen::umeyama(from, to, false);
      if (!m.matrix().allFinite()) continue;
      m.linear() = nearest_rotation(m.linear());
      const float share = share_landing_on_itself(surface, m, tolerance_mm);
      double sq = 0;
      for (int i = 0; i < n - k; ++i) sq += (m * from.col(i) - to.col(i)).squaredNorm();
      const float rms = float(std::sqrt(sq / double(n - k)));
      if (share >= min_share && rms <= kSlideCentrelineRmsOfD * d)
        found.push_back({m, float(sign) * float(k) * line.step_mm, share, rms});
    }
  }
  return found;
}

float share_landing_on_itself(const SurfaceIndex& index, const Pose& m, float tolerance_mm) {
  const SurfaceSamples& surface = index.surface;
  const std::size_t stride = std::max<std::size_t>(1, surface.points.size() / kLandingSamples);
  int within = 0, n = 0;
  for (std::size_t i = 0; i < surface.points.size(); i += stride, ++n) {
    int idx = 0;
    float d2 = 0;
    within += index.tree.nearest_within((m * surface.points[i].cast<double>()).cast<float>(), tolerance_mm,
                                        &idx, &d2);
  }
  return n > 0 ? float(within) / float(n) : 0.0f;
}

}  // namespace pipeloc
