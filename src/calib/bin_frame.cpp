#include "calib/bin_frame.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace pipeloc {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A point above the floor, in floor coordinates (u, v along the floor; mm), with the half-width of
// its pixel's footprint there (so that a strip profile has no gaps between sparse pixels).
struct FloorPoint {
  double u, v, h, half;
};

// Sharpness of the projections of the high points on two perpendicular axes turned by theta:
// straight walls along the axes pile up in few 2 mm strips (the sum of squared strip counts is
// largest); curved pipes spread over many.
double projection_sharpness(const std::vector<FloorPoint>& pts, double theta, std::vector<int>* bins) {
  constexpr double kStrip = 2, kReach = 2000;
  const int n = int(2 * kReach / kStrip);
  bins->assign(std::size_t(2 * n), 0);
  const double c = std::cos(theta), s = std::sin(theta);
  for (const FloorPoint& p : pts) {
    const int a = int((c * p.u + s * p.v + kReach) / kStrip), b = int((-s * p.u + c * p.v + kReach) / kStrip);
    if (a >= 0 && a < n) ++(*bins)[std::size_t(a)];
    if (b >= 0 && b < n) ++(*bins)[std::size_t(n + b)];
  }
  double sum = 0;
  for (int k : *bins) sum += double(k) * k;
  return sum;
}

// Density of high points per 1 mm strip along one axis (each point spread over its footprint).
struct Profile {
  static constexpr double kReach = 2000;
  std::vector<double> w = std::vector<double>(std::size_t(2 * kReach), 0.0);
  void add(double x, double half) {
    const double lo = x - half + kReach, hi = x + half + kReach;
    const int k0 = std::max(0, int(std::floor(lo))), k1 = std::min(int(w.size()) - 1, int(std::floor(hi)));
    for (int k = k0; k <= k1; ++k) {
      const double overlap = std::min(hi, k + 1.0) - std::max(lo, double(k));
      if (overlap > 0) w[std::size_t(k)] += overlap / (hi - lo);
    }
  }
  double centre(int k) const { return k + 0.5 - kReach; }
  int bin(double x) const { return std::clamp(int(std::floor(x + kReach)), 0, int(w.size()) - 1); }
};

// The strip with the most high points on one side (dir = +1 or -1) of `from`: a wall seen there
// (its inner face, its top, or its outer face when the camera is beyond it). NaN: below min_peak.
double densest_strip(const Profile& p, double from, int dir, double min_peak) {
  double peak = 0;
  int at = -1;
  for (int k = p.bin(from); k >= 0 && k < int(p.w.size()); k += dir)
    if (p.w[std::size_t(k)] > peak) peak = p.w[std::size_t(k)], at = k;
  return peak < min_peak ? std::nan("") : p.centre(at);
}

// A wall's inner face, near `wall` (its densest strip) on the side dir of the centre: the inner
// edge of its top, which every camera above the bin sees. The top is the commonest height there;
// its points are profiled alone (a visible inner face would blur the edge by the depth noise),
// and the edge is where that profile, coming from the centre, reaches `share` of its plateau.
double wall_inner_face(const std::vector<FloorPoint>& high, double c, double s, double wall, int dir,
                       const BinCalibParams& params) {
  constexpr double kNear = 40, kReach = 100, kTopBand = 12;
  // The top's height: the most common height of the high points there (a horizontal surface puts
  // all its points at one height; a visible face and pipes piled against the wall spread theirs).
  constexpr double kHeightBin = 4;
  std::vector<int> count(1000, 0);
  int near = 0;
  for (const FloorPoint& p : high)
    if (std::abs(c * p.u + s * p.v - wall) <= kNear && p.h < 4000)
      ++count[std::size_t(p.h / kHeightBin)], ++near;
  if (near < 50) return std::nan("");
  std::size_t mode = 0;
  for (std::size_t i = 1; i + 1 < count.size(); ++i)
    if (count[i - 1] + count[i] + count[i + 1] > count[mode - (mode > 0)] + count[mode] + count[mode + 1])
      mode = i;
  const double top = (double(mode) + 0.5) * kHeightBin;
  Profile tp;
  for (const FloorPoint& p : high) {
    const double x = c * p.u + s * p.v;
    if (std::abs(p.h - top) <= kTopBand && std::abs(x - wall) <= kReach) tp.add(x, p.half);
  }
  const double start = wall - dir * kReach;
  double plateau = 0;
  for (int k = tp.bin(start); k >= 0 && k < int(tp.w.size()) && std::abs(tp.centre(k) - wall) <= kReach;
       k += dir)
    plateau = std::max(plateau, tp.w[std::size_t(k)]);
  const double level = params.wall_edge_share * plateau;
  for (int k = tp.bin(start) + dir; k >= 0 && k < int(tp.w.size()); k += dir) {
    const double c1 = tp.w[std::size_t(k)];
    if (c1 < level) continue;
    const double c0 = tp.w[std::size_t(k - dir)];
    return tp.centre(k - dir) + dir * (level - c0) / (c1 - c0);
  }
  return std::nan("");
}

}  // namespace

BinCalib calibrate_bin(const Image<float>& depth, const Intrinsics& k, const BinCalibParams& params) {
  BinCalib out;
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(depth.pixels.size());
  for (int v = 0; v < depth.height; ++v)
    for (int u = 0; u < depth.width; ++u)
      if (const float d = depth.at(u, v); d > 0) pts.push_back(k.unproject(u, v, d));
  out.valid_points = int(pts.size());
  if (pts.size() < std::size_t(params.min_floor_points)) {
    out.error = "only " + std::to_string(pts.size()) + " valid depth pixels: no floor to fit";
    return out;
  }

  // The floor: the largest plane facing the camera.
  const PlaneFit floor = fit_plane_ransac(pts, params.plane);
  out.floor_points = floor.inliers;
  out.floor_share = floor.inlier_share;
  out.floor_rms_mm = floor.rms_mm;
  if (floor.inliers < params.min_floor_points || floor.inlier_share < params.min_floor_share) {
    std::ostringstream s;
    s.precision(3);
    s << "no floor plane: the best plane within " << params.plane.max_normal_deg
      << " deg of the optical axis holds " << 100 * floor.inlier_share << " % of the " << pts.size()
      << " valid pixels within " << params.plane.inlier_mm << " mm (need " << 100 * params.min_floor_share
      << " %)";
    out.error = s.str();
    return out;
  }

  // Floor coordinates: z = the normal (towards the camera: up), x0 = the image's x on the floor.
  const Eigen::Vector3d z = floor.normal;
  const Eigen::Vector3d x0 = (Eigen::Vector3d::UnitX() - z * z.x()).normalized();
  const Eigen::Vector3d y0 = z.cross(x0);
  Eigen::Vector3d origin0 = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : pts)
    if (std::abs(floor.distance(p)) <= params.plane.inlier_mm) origin0 += p;
  origin0 /= floor.inliers;
  origin0 -= z * floor.distance(origin0);
  if (params.floor_only) {
    out.world_to_cam.linear().col(0) = x0;
    out.world_to_cam.linear().col(1) = y0;
    out.world_to_cam.linear().col(2) = z;
    out.world_to_cam.translation() = origin0;
    out.ok = true;
    return out;
  }
  std::vector<FloorPoint> high;
  for (const Eigen::Vector3d& p : pts) {
    const Eigen::Vector3d q = p - origin0;
    if (z.dot(q) > params.wall_min_height_mm)
      high.push_back({x0.dot(q), y0.dot(q), z.dot(q), 0.5 * p.z() / k.fx});
  }

  // The walls' direction: the turn that projects the high points most sharply (coarse, then fine).
  std::vector<int> bins;
  double best_theta = 0, best = -1;
  for (double deg = -45; deg < 45; deg += 0.5)
    if (const double s = projection_sharpness(high, deg * kDeg, &bins); s > best) best = s, best_theta = deg;
  const double coarse = best_theta;
  for (double deg = coarse - 0.5; deg <= coarse + 0.5; deg += 0.05)
    if (const double s = projection_sharpness(high, deg * kDeg, &bins); s > best) best = s, best_theta = deg;
  const double c = std::cos(best_theta * kDeg), s = std::sin(best_theta * kDeg);
  const Eigen::Vector3d ea = c * x0 + s * y0, eb = -s * x0 + c * y0;

  // The walls' inner faces: from the floor's centroid outwards, the first strip dense with high points.
  Profile pa, pb;
  for (const FloorPoint& p : high) {
    pa.add(c * p.u + s * p.v, p.half);
    pb.add(-s * p.u + c * p.v, p.half);
  }
  const double min_peak = 20;  // high points per mm of strip: a wall seen over at least a few cm
  const double walls[4] = {densest_strip(pa, 0, -1, min_peak), densest_strip(pa, 0, +1, min_peak),
                           densest_strip(pb, 0, -1, min_peak), densest_strip(pb, 0, +1, min_peak)};
  double faces[4];
  for (int i = 0; i < 4; ++i) {
    const int dir = i % 2 ? +1 : -1;
    faces[i] = std::isnan(walls[i]) ? walls[i]
               : i < 2              ? wall_inner_face(high, c, s, walls[i], dir, params)
                                    : wall_inner_face(high, -s, c, walls[i], dir, params);
  }
  const double a_lo = faces[0], a_hi = faces[1], b_lo = faces[2], b_hi = faces[3];
  if (std::isnan(a_lo) || std::isnan(a_hi) || std::isnan(b_lo) || std::isnan(b_hi)) {
    out.error =
        "floor found, but not four walls around it (is the whole bin in view? --floor-only gives the "
        "floor's frame alone)";
    return out;
  }
  const Eigen::Vector3d centre = origin0 + 0.5 * (a_lo + a_hi) * ea + 0.5 * (b_lo + b_hi) * eb;
  const double la = a_hi - a_lo, lb = b_hi - b_lo;
  // Faces crossing each other (something standing on the floor taken for walls) leave no interior.
  if (!(la > 2 * params.roi_margin_mm && lb > 2 * params.roi_margin_mm)) {
    std::ostringstream why;
    why.setf(std::ios::fixed);
    why.precision(1);
    why << "floor found, but the walls found around it leave no interior (" << la << " x " << lb
        << " mm between their inner faces, " << params.roi_margin_mm
        << " mm margin each side): is the whole bin in view? (--floor-only gives the floor's frame alone)";
    out.error = why.str();
    return out;
  }
  Eigen::Vector3d x_axis = la >= lb ? ea : eb;
  if (x_axis.x() < 0) x_axis = -x_axis;
  out.interior_x_mm = la >= lb ? la : lb;
  out.interior_y_mm = la >= lb ? lb : la;
  Eigen::Matrix3d r;
  r.col(0) = x_axis;
  r.col(1) = z.cross(x_axis);
  r.col(2) = z;
  out.world_to_cam.linear() = r;
  out.world_to_cam.translation() = centre;
  for (int i = 0; i < 2; ++i) {
    const double half = 0.5 * (i == 0 ? out.interior_x_mm : out.interior_y_mm) - params.roi_margin_mm;
    out.roi_min_mm[i] = -half;
    out.roi_max_mm[i] = half;
  }
  out.walls = true;
  out.ok = true;
  return out;
}

std::string bin_calib_toml(const BinCalib& b) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(1);
  s << "# pipeloc calibrate-bin: floor from " << b.floor_points << " of " << b.valid_points
    << " valid pixels (" << 100 * b.floor_share << " % inliers), residual " << std::setprecision(2)
    << b.floor_rms_mm << " mm RMS\n";
  s.precision(1);
  if (b.walls)
    s << "# bin interior " << b.interior_x_mm << " x " << b.interior_y_mm
      << " mm between the walls' inner faces; frame: Z up, X along the longer side, origin on the floor at "
         "the centre\n";
  else
    s << "# the floor alone (walls not looked for): frame Z up, X along the image's x, origin on the floor "
         "at the centroid of what is in view; no region of interest\n";
  s << "[source.openni2]\nworld_to_cam = [";
  const Eigen::Matrix4d m = b.world_to_cam.matrix();
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      s.precision(j == 3 ? 2 : 7);
      s << (i == 3 ? m(i, j) == 1 ? "1" : "0" : "");
      if (i < 3) s << m(i, j);
      s << (i == 3 && j == 3 ? "" : j == 3 ? ",  " : ", ");
    }
  }
  s << "]\n";
  if (!b.walls) return s.str();
  s.precision(1);
  s << "[locate]\nroi_min_mm = [" << b.roi_min_mm[0] << ", " << b.roi_min_mm[1] << "]\n";
  s << "roi_max_mm = [" << b.roi_max_mm[0] << ", " << b.roi_max_mm[1] << "]\n";
  return s.str();
}

}  // namespace pipeloc
