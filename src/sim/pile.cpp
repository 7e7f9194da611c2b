#include "sim/pile.hpp"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>

#include "render/raster.hpp"

namespace pipeloc {
namespace {

constexpr double kDeg = M_PI / 180.0;
// bin_for_pile: a pipe up to this share of the bin's shorter side still fits in most drops (the
// drops that leave the bin are tried again); the pile's volume spread evenly over where the
// pipes fall is at most this high, or this many pipes thick (pipes do not slide down a heap
// here, so a pile is taller in the middle than this).
constexpr double kLengthShareOfSide = 0.6;
constexpr double kPileHeightMm = 40;
constexpr double kPileLayers = 1.5;

// Model rotation that lays the pipe flat: its direction of least spread points up.
Eigen::Matrix3d lying_rotation(const PipeModel& model) {
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& p : model.surface.points) {
    const Eigen::Vector3d d = (p - model.centroid).cast<double>();
    cov += d * d.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Matrix3d axes = eig.eigenvectors();  // ascending: col 0 = least spread
  Eigen::Matrix3d r;
  r.row(0) = axes.col(2).transpose();
  r.row(1) = axes.col(1).transpose();
  r.row(2) = axes.col(0).transpose();
  if (r.determinant() < 0) r.row(1) *= -1;
  return r;
}

struct Dropper {
  const std::vector<Eigen::Vector3f>& points;  // model frame, a subset of surface samples
  const HeightMap& below;
  double half_x, half_y;

  // Moves `pose` vertically to where it just touches the pile; NaN if it leaves the bin.
  double drop(Pose* pose) const {
    double lift = -std::numeric_limits<double>::infinity();
    for (const auto& p : points) {
      const Eigen::Vector3d w = *pose * p.cast<double>();
      if (std::abs(w.x()) > half_x || std::abs(w.y()) > half_y) return std::nan("");
      lift = std::max(lift, double(below.at(w.x(), w.y(), 0.f)) - w.z());
    }
    pose->translation().z() += lift;
    return lift;
  }
};

}  // namespace

PileSize pile_size(const PipeModel& model, const PileParams& params) {
  // The pipe lying flat: its extents along its axes of most, middle and least spread.
  const Eigen::Matrix3d lying = lying_rotation(model);
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e18), hi = -lo;
  for (const auto& p : model.surface.points) {
    const Eigen::Vector3d q = lying * p.cast<double>();
    lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
  }
  const Eigen::Vector3d extent = hi - lo;
  PileSize size;
  size.length_mm = std::max(extent.x(), extent.y());
  // Pipes fall over the drop area and reach out of it by half their length on each side.
  const double area = (params.drop_spread * params.bin.inner_x_mm + size.length_mm) *
                      (params.drop_spread * params.bin.inner_y_mm + size.length_mm);
  size.mean_height_mm = params.pipes * extent.x() * extent.y() * extent.z() / area;
  size.thickness_mm = extent.z();
  return size;
}

BinSpec bin_for_pile(const PipeModel& model, const PileParams& params) {
  PileParams grown = params;
  const double shorter = std::min(params.bin.inner_x_mm, params.bin.inner_y_mm);
  for (double scale = 1.0;; scale += 0.02) {
    grown.bin.inner_x_mm = std::ceil(params.bin.inner_x_mm * scale);
    grown.bin.inner_y_mm = std::ceil(params.bin.inner_y_mm * scale);
    const PileSize size = pile_size(model, grown);
    if (size.length_mm <= kLengthShareOfSide * shorter * scale &&
        size.mean_height_mm <= std::max(kPileHeightMm, kPileLayers * size.thickness_mm))
      return scale == 1.0 ? params.bin : grown.bin;
  }
}

Mesh make_bin_mesh(const BinSpec& bin) {
  Mesh mesh;
  auto box = [&](Eigen::Vector3f lo, Eigen::Vector3f hi) {
    const int b = int(mesh.vertices.size());
    for (int i = 0; i < 8; ++i)
      mesh.vertices.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
    const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& q : quads) {
      mesh.faces.push_back({b + q[0], b + q[1], b + q[2]});
      mesh.faces.push_back({b + q[0], b + q[2], b + q[3]});
    }
  };
  const float hx = float(bin.inner_x_mm / 2), hy = float(bin.inner_y_mm / 2);
  const float t = float(bin.wall_thickness_mm), h = float(bin.wall_height_mm);
  box({-hx - t, -hy - t, -t}, {hx + t, hy + t, 0});  // floor, top face at z = 0
  box({-hx - t, -hy - t, 0}, {-hx, hy + t, h});      // walls
  box({hx, -hy - t, 0}, {hx + t, hy + t, h});
  box({-hx, -hy - t, 0}, {hx, -hy, h});
  box({-hx, hy, 0}, {hx, hy + t, h});
  return mesh;
}

std::vector<Pose> build_pile(const PipeModel& model, const PileParams& params, std::mt19937& rng) {
  HeightMap map;
  map.cell_mm = params.cell_mm;
  map.origin_x_mm = -params.bin.inner_x_mm / 2;
  map.origin_y_mm = -params.bin.inner_y_mm / 2;
  map.z_mm.resize(int(params.bin.inner_x_mm / params.cell_mm) + 1,
                  int(params.bin.inner_y_mm / params.cell_mm) + 1, 0.0f);

  // Contact points: about one per 4 mm^2 is finer than the height map.
  std::vector<Eigen::Vector3f> contact;
  const std::size_t stride = std::max<std::size_t>(1, model.surface.points.size() / 6000);
  for (std::size_t i = 0; i < model.surface.points.size(); i += stride)
    contact.push_back(model.surface.points[i]);
  const Dropper dropper{contact, map, params.bin.inner_x_mm / 2 - 1, params.bin.inner_y_mm / 2 - 1};

  const Eigen::Matrix3d lying = lying_rotation(model);
  const Eigen::Vector3d c_model = model.centroid.cast<double>();
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<Pose> poses;
  for (int n = 0, attempts = 0; n < params.pipes && attempts < params.pipes * 20; ++attempts) {
    Pose pose = Pose::Identity();
    const Eigen::Matrix3d flip = uniform(rng) < 0.5
                                     ? Eigen::Matrix3d::Identity()
                                     : Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
    const double yaw = uniform(rng) * 2 * M_PI;
    // A random initial lean so that pipes do not all start parallel to the floor.
    const double lean_dir = uniform(rng) * 2 * M_PI;
    const Eigen::Vector3d lean_axis(std::cos(lean_dir), std::sin(lean_dir), 0);
    pose.linear() = Eigen::AngleAxisd(uniform(rng) * 25 * kDeg, lean_axis) *
                    Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * flip * lying;
    // Drop over the middle of the bin, where piles form; reject if the pipe would not fit there.
    const Eigen::Vector3d target((uniform(rng) - 0.5) * params.bin.inner_x_mm * params.drop_spread,
                                 (uniform(rng) - 0.5) * params.bin.inner_y_mm * params.drop_spread, 0);
    pose.translation() = target - pose.linear() * c_model;
    if (std::isnan(dropper.drop(&pose))) continue;

    // Settle: rotate about horizontal axes through the centroid while that lowers it.
    for (double step = params.max_settle_deg; step >= 1.0; step /= 2) {
      for (int iter = 0; iter < 6; ++iter) {
        const double height = (pose * c_model).z();
        Pose best = pose;
        double best_height = height - 0.05;
        for (int axis = 0; axis < 4; ++axis) {
          const Eigen::Vector3d a = axis < 2 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
          const double angle = (axis % 2 ? -step : step) * kDeg;
          Pose trial = pose;
          const Eigen::Vector3d c_world = pose * c_model;
          trial.linear() = Eigen::AngleAxisd(angle, a) * pose.linear();
          trial.translation() = c_world - trial.linear() * c_model;
          if (std::isnan(dropper.drop(&trial))) continue;
          const double h = (trial * c_model).z();
          if (h < best_height) best_height = h, best = trial;
        }
        if (best_height >= height - 0.05) break;
        pose = best;
      }
    }
    render_height(model.mesh, pose, Envelope::top, &map);
    poses.push_back(pose);
    ++n;
  }
  return poses;
}

}  // namespace pipeloc
