#include "locate/locator_model.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "locate/locate_config.hpp"
#include "locate/principal_axis.hpp"
#include "model/neighbors.hpp"
#include "model/slides.hpp"
#include "render/raster.hpp"

namespace pipeloc {

AxisEstimate top_view_axis(const PipeModel& model, const Pose& model_to_bin, const LocateConfig& cfg) {
  HeightMap hm;
  hm.cell_mm = cfg.zbuffer_pixel_mm;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e30), hi = -lo;
  for (const auto& v : model.mesh.vertices) {
    const Eigen::Vector3d p = model_to_bin * v.cast<double>();
    lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  }
  hm.origin_x_mm = lo.x() - 2 * hm.cell_mm;
  hm.origin_y_mm = lo.y() - 2 * hm.cell_mm;
  const int w = int((hi.x() - lo.x()) / hm.cell_mm) + 5, h = int((hi.y() - lo.y()) / hm.cell_mm) + 5;
  hm.z_mm.resize(w, h, -1e30f);
  render_height(model.mesh, model_to_bin, Envelope::top, &hm);
  ZBuffer zb;
  zb.origin_x_mm = hm.origin_x_mm;
  zb.origin_y_mm = hm.origin_y_mm;
  zb.pixel_mm = hm.cell_mm;
  zb.width = w;
  zb.height = h;
  zb.z.resize(w, h, ZBuffer::kEmpty);
  std::vector<int> cells;
  Eigen::Vector3f centroid = Eigen::Vector3f::Zero();
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i)
      if (hm.z_mm.at(i, j) > -1e29f) {
        zb.z.at(i, j) = hm.z_mm.at(i, j);
        cells.push_back(zb.index(i, j));
        centroid += zb.point(i, j);
      }
  centroid /= float(std::max<std::size_t>(1, cells.size()));
  AxisBuffers buf;
  reserve_axis(&buf, int(cells.size()), w, h);
  return estimate_axis(zb, cells.data(), int(cells.size()), centroid, cfg, model.tube_diameter_mm, &buf);
}

namespace {

// The model at `rotation`, seen from above as the localizer sees a pipe, moved so that its
// measured principal direction lies on +X and its measured centre at the origin.
Pose canonical_start(const PipeModel& model, const Eigen::Matrix3d& rotation, const LocateConfig& cfg) {
  Pose lying = Pose::Identity();
  lying.linear() = rotation;
  const AxisEstimate est = top_view_axis(model, lying, cfg);
  const double yaw = -std::atan2(est.axis.y(), est.axis.x());
  Pose to_canonical = Pose::Identity();
  to_canonical.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  to_canonical.translation() = -(to_canonical.linear() * est.centre.cast<double>());
  return to_canonical * lying;
}

// The tube's direction at a surface point p of outward normal n: the step of the centreline (`line`,
// ordered by arc length; `index` over it) nearest the point's centre, p moved D/2 inwards, made
// square to n. Zero where there is no centreline, where it lies further than D/2 from that
// centre, or where n is not square to the step within 45 degrees: not the tube's side (an end
// cap's face).
Eigen::Vector3f tube_direction_at(const std::vector<Eigen::Vector3f>& line, const KdTree3& index,
                                  const Eigen::Vector3f& p, const Eigen::Vector3f& n, float tube_d_mm) {
  int nearest = -1;
  float d2 = 0;
  if (line.size() < 2 || !index.nearest_within(p - 0.5f * tube_d_mm * n, 0.5f * tube_d_mm, &nearest, &d2))
    return Eigen::Vector3f::Zero();
  const std::size_t best = std::size_t(nearest);
  const std::size_t i0 = best == 0 ? 0 : best - 1, i1 = std::min(line.size() - 1, best + 1);
  const Eigen::Vector3f step = line[i1] - line[i0];
  const Eigen::Vector3f a = step - step.dot(n) * n;
  const float len = a.norm();
  return len > std::sqrt(0.5f) * step.norm() && len > 1e-6f ? Eigen::Vector3f(a / len)
                                                            : Eigen::Vector3f::Zero();
}

}  // namespace

LocatorModel prepare_locator_model(const PipeModel& model, float margin_mm, const LocateConfig& cfg) {
  LocatorModel lm;
  lm.model = &model;
  lm.tube_d_mm = model.tube_diameter_mm;
  lm.extent_l_mm = model.extent_mm;
  lm.centroid = model.centroid;
  const auto& pts = model.surface.points;
  const Eigen::Matrix3d axes = principal_axes(pts, model.centroid);
  lm.axis = axes.col(2).cast<float>();
  lm.up = axes.col(0).cast<float>();
  const Eigen::Vector3f side = axes.col(1).cast<float>();
  float side_lo = 1e30f, side_hi = -1e30f;
  for (const auto& p : pts)
    side_lo = std::min(side_lo, p.dot(side)), side_hi = std::max(side_hi, p.dot(side));
  lm.slide_across_mm = std::max(0.0f, 0.5f * (side_hi - side_lo - lm.tube_d_mm));
  lm.slide_along_mm = 0.25f * lm.extent_l_mm;

  // One ridge sample per 6 mm^2 of surface leaves few empty 2 mm ridge cells on the top half.
  const float area = model.mesh.surface_area();
  const std::size_t want = std::max<std::size_t>(500, std::size_t(area / 6));
  const std::size_t stride = std::max<std::size_t>(1, pts.size() / want);
  for (std::size_t i = 0; i < pts.size(); i += stride) {
    lm.ridge_samples.push_back(pts[i]);
    lm.ridge_normals.push_back(model.surface.normals[i]);
  }
  for (const float cell :
       {float(cfg.ridge_cell_mm), float(std::max(cfg.icp_probe_cell_mm, cfg.ridge_cell_mm))}) {
    const int take = ridge_sample_stride(cell, cfg);
    if (lm.ridge_columns_for(take)) continue;
    lm.ridge_columns.emplace_back();
    lm.ridge_columns.back().assign(lm.ridge_samples.data(), lm.ridge_normals.data(),
                                   int(lm.ridge_samples.size()), take);
  }
  lm.verify_mesh = weld_vertices(model.mesh, std::max(0.5f, lm.tube_d_mm / 8));
  lm.verify_winding = closed_winding(model.mesh);
  const std::size_t vstride = std::max<std::size_t>(1, model.mesh.vertices.size() / 64);
  for (std::size_t i = 0; i < model.mesh.vertices.size(); i += vstride)
    lm.check_points.push_back(model.mesh.vertices[i]);
  const Centreline centreline = centreline_of(model.surface, lm.tube_d_mm);
  constexpr std::size_t kCentrelinePoints = 64;
  const std::size_t cstride = std::max<std::size_t>(1, centreline.points.size() / kCentrelinePoints);
  for (std::size_t i = 0; i < centreline.points.size(); i += cstride)
    lm.centreline_points.push_back(centreline.points[i]);
  if (!centreline.points.empty()) lm.centreline_points.push_back(centreline.points.back());
  lm.centreline_step_mm = float(cstride) * centreline.step_mm;
  if (lm.centreline_points.size() >= 2) {
    const Eigen::Vector3f a = lm.centreline_points.front(), b = lm.centreline_points.back();
    const Eigen::Vector3f u = (b - a).normalized();
    constexpr float kStraightOfD = 0.1f;
    float off = 0;
    for (const auto& p : lm.centreline_points) off = std::max(off, ((p - a) - (p - a).dot(u) * u).norm());
    lm.straight = (b - a).norm() > lm.tube_d_mm && off <= kStraightOfD * lm.tube_d_mm;
  }

  // Voxel index by multi-source breadth-first propagation from each sample's voxel.
  Eigen::Vector3f lo = pts[0], hi = pts[0];
  for (const auto& p : pts) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  lm.voxel_origin = lo - Eigen::Vector3f::Constant(margin_mm);
  const Eigen::Vector3f size = hi - lo + Eigen::Vector3f::Constant(2 * margin_mm);
  lm.nx = int(size.x() / lm.voxel_mm) + 1;
  lm.ny = int(size.y() / lm.voxel_mm) + 1;
  lm.nz = int(size.z() / lm.voxel_mm) + 1;
  std::vector<int> voxel_sample(std::size_t(lm.nx) * lm.ny * lm.nz, -1);
  std::vector<int> queue;
  queue.reserve(voxel_sample.size());
  auto voxel_of = [&](const Eigen::Vector3f& p) {
    const Eigen::Vector3f g = (p - lm.voxel_origin) / lm.voxel_mm;
    return (std::size_t(g.z()) * lm.ny + std::size_t(g.y())) * lm.nx + std::size_t(g.x());
  };
  std::vector<float> best(voxel_sample.size(), 1e30f);
  auto centre_of = [&](std::size_t v) {
    const int i = int(v % lm.nx), j = int((v / lm.nx) % lm.ny), k = int(v / (std::size_t(lm.nx) * lm.ny));
    return Eigen::Vector3f(lm.voxel_origin + lm.voxel_mm * Eigen::Vector3f(i + 0.5f, j + 0.5f, k + 0.5f));
  };
  for (std::size_t s = 0; s < pts.size(); ++s) {
    const std::size_t v = voxel_of(pts[s]);
    const float d = (centre_of(v) - pts[s]).squaredNorm();
    if (voxel_sample[v] < 0) queue.push_back(int(v));
    if (d < best[v]) best[v] = d, voxel_sample[v] = int(s);
  }
  const float margin_sq = margin_mm * margin_mm;
  for (std::size_t head = 0; head < queue.size(); ++head) {
    const std::size_t v = std::size_t(queue[head]);
    const int s = voxel_sample[v];
    const int i = int(v % lm.nx), j = int((v / lm.nx) % lm.ny), k = int(v / (std::size_t(lm.nx) * lm.ny));
    const int nb[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
    for (const auto& o : nb) {
      const int a = i + o[0], b = j + o[1], c = k + o[2];
      if (a < 0 || b < 0 || c < 0 || a >= lm.nx || b >= lm.ny || c >= lm.nz) continue;
      const std::size_t w = (std::size_t(c) * lm.ny + b) * lm.nx + a;
      const float d = (centre_of(w) - pts[s]).squaredNorm();
      if (d > margin_sq || d >= best[w]) continue;
      if (voxel_sample[w] < 0) queue.push_back(int(w));
      best[w] = d;
      voxel_sample[w] = s;
    }
  }
  KdTree3 centreline_index;
  if (cfg.refine_ray_pairs) centreline_index.build(centreline.points.data(), centreline.points.size());
  // Compacted: only the samples some voxel names, numbered in sample order.
  std::vector<int> number(pts.size(), -1);
  for (const int s : voxel_sample)
    if (s >= 0) number[std::size_t(s)] = 0;
  for (std::size_t s = 0; s < pts.size(); ++s) {
    if (number[s] < 0) continue;
    number[s] = int(lm.samples.size());
    lm.samples.push_back({pts[s], model.surface.normals[s]});
    if (cfg.refine_ray_pairs)
      lm.sample_directions.push_back(tube_direction_at(centreline.points, centreline_index, pts[s],
                                                       model.surface.normals[s], lm.tube_d_mm));
  }
  // PipeModel caps its samples well below this; a larger model must not wrap the index around.
  if (lm.samples.size() >= LocatorModel::kNoSample)
    throw std::runtime_error("model: " + std::to_string(lm.samples.size()) +
                             " surface samples near voxels, more than the refinement's index holds (65534)");
  lm.voxel_sample.resize(voxel_sample.size());
  for (std::size_t v = 0; v < voxel_sample.size(); ++v)
    lm.voxel_sample[v] =
        voxel_sample[v] < 0 ? LocatorModel::kNoSample : std::uint16_t(number[std::size_t(voxel_sample[v])]);
  // Lying frame: largest spread along X, least spread up; then the turns about X.
  Eigen::Matrix3d lying;
  lying.row(0) = lm.axis.cast<double>().transpose();
  lying.row(2) = lm.up.cast<double>().transpose();
  lying.row(1) = lying.row(2).cross(lying.row(0));
  lm.yaw_offsets = std::max(1, int(std::lround(180.0 / cfg.initial_yaw_step_deg)));
  lm.yaw_step_rad = M_PI / lm.yaw_offsets;
  const int turns = std::max(1, cfg.initial_rotations);
  for (int k = 0; k < turns; ++k)
    lm.canonical_starts.push_back(canonical_start(
        model, Eigen::AngleAxisd(2 * M_PI * k / turns, Eigen::Vector3d::UnitX()).toRotationMatrix() * lying,
        cfg));
  // The slides and the turns about the length are judged as the near symmetries are: what lands
  // near_symmetry_min_share of the surface within near_symmetry_tolerance_of_diameter x D of itself.
  const ModelDerivation near;
  const float landing_tolerance_mm = near.near_symmetry_tolerance_of_diameter * lm.tube_d_mm;
  const SurfaceIndex surface(model.surface);
  {
    // Slides just beyond the ambiguity distance are the hardest to tell apart; longer ones are
    // judged too (a pose 5-45 mm along an arc was handed out as a pick before this check).
    // Far slides too, doubling from 8 steps as far as near_symmetry_min_share of the surface stays
    // on itself: a coil standing on its edge, turned a third of a turn round its helix, shows the
    // camera the same top arc, and was handed out 112 mm from its pipe (17-coil of the zoo).
    const float step = float(std::max(cfg.ambiguity_pose_mm, 0.5 * double(lm.tube_d_mm)));
    const float furthest = (1.0f - near.near_symmetry_min_share) * centreline.length_mm();
    std::vector<float> far;
    for (float arc = 8.0f * step; arc <= furthest; arc *= 2.0f) far.push_back(arc);
    const auto add_slides = [&](const std::vector<float>& arcs, std::vector<Pose>* to) {
      for (const Slide& s : find_slides(surface, centreline, lm.tube_d_mm, arcs, landing_tolerance_mm,
                                        near.near_symmetry_min_share))
        to->push_back(s.motion);
    };
    add_slides({1.5f * step, 3.0f * step, 5.0f * step}, &lm.slides);
    lm.short_slides = lm.slides.size();
    add_slides(far, &lm.slides);
    // Slides of D/12 up to D both ways place a pose its ends pin finer than the steps above
    // (place_slides_finely); slides of D, 2 D, ... as far as the far slides reach follow a pose
    // the tube goes on beyond to its end (follow_slides_to_ends).
    if (!lm.slides.empty()) {
      constexpr int kFineSteps = 12;
      std::vector<float> fine, follow;
      for (int k = 1; k <= kFineSteps; ++k) fine.push_back(lm.tube_d_mm * float(k) / float(kFineSteps));
      for (float arc = lm.tube_d_mm; arc <= furthest; arc += lm.tube_d_mm) follow.push_back(arc);
      add_slides(fine, &lm.fine_slides);
      add_slides(follow, &lm.follow_slides);
    }
  }
  if (lm.centreline_points.size() >= 3 && !lm.straight) {
    const Eigen::Vector3f c = centroid_of(lm.centreline_points);
    const Eigen::Vector3d axis = principal_axes(lm.centreline_points, c).col(2);
    // The turns judged and their steps: locator_model.hpp.
    const bool lands_on_itself =
        share_landing_on_itself(surface, turn_about(axis, c, 0.5 * M_PI), landing_tolerance_mm) >=
        near.near_symmetry_min_share;
    const int steps = lands_on_itself ? int(LocatorModel::kMostRolls) + 1 : lm.slides.empty() ? 4 : 0;
    for (int k = 1; k < steps; ++k) lm.rolls.push_back(turn_about(axis, c, 2.0 * M_PI * k / steps));
  }
  return lm;
}

int ridge_sample_stride(float cell_mm, const LocateConfig& cfg) {
  const int per_side = std::max(1, int(cell_mm / float(cfg.ridge_cell_mm) + 0.5f));
  return per_side * per_side;
}

namespace {

// The largest distance between a point of `points` under a and under b (under b composed with
// each symmetry, the least), cut short beyond bound_mm.
float points_distance_mm(const LocatorModel& lm, const std::vector<Eigen::Vector3f>& points, const Pose& a,
                         const Pose& b, float bound_mm) {
  const Eigen::Matrix4f ma = a.matrix().cast<float>();
  // A squared distance above this has a square root above bound_mm, rounding included.
  const float cut_sq = bound_mm * bound_mm * (1 + 1e-5f);
  // The worst squared distance for mb, or (cut short) one above cut_sq.
  auto worst_for = [&](const Eigen::Matrix4f& mb) {
    float worst = 0;
    for (const auto& p : points) {
      const Eigen::Vector3f d = (ma.topLeftCorner<3, 3>() - mb.topLeftCorner<3, 3>()) * p +
                                (ma.topRightCorner<3, 1>() - mb.topRightCorner<3, 1>());
      worst = std::max(worst, d.squaredNorm());
      if (worst > cut_sq) break;  // this symmetry is beyond the bound whatever the rest
    }
    return std::sqrt(worst);
  };
  float best = worst_for(b.matrix().cast<float>());
  for (const auto& s : lm.model->symmetries) best = std::min(best, worst_for((b * s).matrix().cast<float>()));
  return best;
}

}  // namespace

float pose_distance_mm(const LocatorModel& lm, const Pose& a, const Pose& b, float bound_mm) {
  return points_distance_mm(lm, lm.check_points, a, b, bound_mm);
}

float shared_tube(const LocatorModel& lm, const Pose& a, const Pose& b) {
  const std::vector<Eigen::Vector3f>& c = lm.centreline_points;
  if (c.size() < 2) return 1;
  // a's points in b's model frame, against b's centreline as a polyline.
  const Eigen::Matrix4f b_from_a = (b.inverse() * a).matrix().cast<float>();
  const float near_sq = 0.25f * lm.tube_d_mm * lm.tube_d_mm;
  int shared = 0;
  for (const Eigen::Vector3f& p : c) {
    const Eigen::Vector3f q = b_from_a.topLeftCorner<3, 3>() * p + b_from_a.topRightCorner<3, 1>();
    for (std::size_t k = 0; k + 1 < c.size(); ++k) {
      const Eigen::Vector3f s = c[k + 1] - c[k];
      const float along = std::clamp((q - c[k]).dot(s) / std::max(s.squaredNorm(), 1e-12f), 0.0f, 1.0f);
      if ((q - c[k] - along * s).squaredNorm() <= near_sq) {
        ++shared;
        break;
      }
    }
  }
  return float(shared) / float(c.size());
}

float pick_distance_mm(const LocatorModel& lm, const Pose& a, const Pose& b, float bound_mm) {
  return points_distance_mm(lm, lm.centreline_points.empty() ? lm.check_points : lm.centreline_points, a, b,
                            bound_mm);
}

}  // namespace pipeloc
