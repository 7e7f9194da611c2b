#include "sim/scene.hpp"

#include <cmath>

namespace pipeloc {
namespace {

constexpr double kDeg = M_PI / 180.0;

}  // namespace

// Camera above the bin looking down at its centre, tilted by `tilt_deg` towards `azimuth`.
Pose camera_pose(double height_mm, double tilt_rad, double azimuth_rad, const Eigen::Vector3d& look_at) {
  // Camera axes in the world: z looks down (tilted), x along world x as far as possible.
  const Eigen::Vector3d down(std::sin(tilt_rad) * std::cos(azimuth_rad),
                             std::sin(tilt_rad) * std::sin(azimuth_rad), -std::cos(tilt_rad));
  const Eigen::Vector3d centre = look_at - down * (height_mm / std::cos(tilt_rad));
  Eigen::Vector3d x_axis = Eigen::Vector3d::UnitX() - down * down.x();
  x_axis.normalize();
  const Eigen::Vector3d y_axis = down.cross(x_axis);
  Eigen::Matrix3d cam_to_world;
  cam_to_world.col(0) = x_axis;
  cam_to_world.col(1) = y_axis;
  cam_to_world.col(2) = down;
  Pose world_to_cam = Pose::Identity();
  world_to_cam.linear() = cam_to_world.transpose();
  world_to_cam.translation() = -cam_to_world.transpose() * centre;
  return world_to_cam;
}

Pose draw_camera(const SceneParams& p, std::mt19937& rng) {
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const double height =
      p.camera_height_min_mm + uniform(rng) * (p.camera_height_max_mm - p.camera_height_min_mm);
  const double tilt = uniform(rng) * p.max_tilt_deg * kDeg;
  const double azimuth = uniform(rng) * 2 * M_PI;
  const Eigen::Vector3d look_at((uniform(rng) - 0.5) * 2 * p.camera_offset_mm,
                                (uniform(rng) - 0.5) * 2 * p.camera_offset_mm, 0);
  return camera_pose(height, tilt, azimuth, look_at);
}

bool camera_and_projector_see(const SceneParams& p, const Eigen::Vector3d& p_cam) {
  if (p_cam.z() <= 0) return false;
  const Intrinsics& k = p.intrinsics;
  for (const Eigen::Vector3d& in :
       {p_cam, Eigen::Vector3d(p_cam - Eigen::Vector3d(p.sensor.baseline_mm, 0, 0))}) {
    const Eigen::Vector2d px = k.project(in);
    if (px.x() < 0 || px.y() < 0 || px.x() > k.width - 1 || px.y() > k.height - 1) return false;
  }
  return true;
}

double lowest_camera_seeing_bin(const SceneParams& p) {
  const BinSpec& bin = p.pile.bin;
  const double hx = bin.inner_x_mm / 2, hy = bin.inner_y_mm / 2, o = p.camera_offset_mm;
  // Every camera draw_camera may draw at this height: tilts and azimuths in steps, the look-at
  // point at the centre and at the corners of its square; each sees the rim's four inner corners
  // with its camera and its projector.
  const auto sees_rim = [&](double height) {
    for (double tilt_share : {0.0, 0.5, 1.0})
      for (int a = 0; a < 24; ++a)
        for (const Eigen::Vector2d& at :
             {Eigen::Vector2d(0, 0), Eigen::Vector2d(o, o), Eigen::Vector2d(o, -o), Eigen::Vector2d(-o, o),
              Eigen::Vector2d(-o, -o)}) {
          const Pose world_to_cam =
              camera_pose(height, tilt_share * p.max_tilt_deg * kDeg, a * M_PI / 12, {at.x(), at.y(), 0});
          for (double sx : {-1.0, 1.0})
            for (double sy : {-1.0, 1.0}) {
              if (!camera_and_projector_see(
                      p, world_to_cam * Eigen::Vector3d(sx * hx, sy * hy, bin.wall_height_mm)))
                return false;
            }
        }
    return true;
  };
  constexpr double kStepMm = 10, kHighestMm = 5000;
  double height = p.camera_height_min_mm;
  while (!sees_rim(height) && height < kHighestMm) height += kStepMm;
  return height;
}

namespace {

void render_all(const PipeModel& model, const Mesh& bin, const std::vector<Pose>& poses,
                const Pose& world_to_cam, const Intrinsics& k, DepthTarget* target) {
  target->reset(k.width, k.height);
  render_perspective(bin, world_to_cam, k, int(poses.size()), target);
  for (std::size_t i = 0; i < poses.size(); ++i)
    render_perspective(model.mesh, world_to_cam * poses[i], k, int(i), target);
}

}  // namespace

void render_views(const PipeModel& model, const std::vector<Pose>& model_to_world, const Pose& world_to_cam,
                  const SceneParams& params, DepthTarget* camera, DepthTarget* projector) {
  const Mesh bin = make_bin_mesh(params.pile.bin);
  render_all(model, bin, model_to_world, world_to_cam, params.intrinsics, camera);
  // The projector sits beside the camera: its view is the camera's shifted along camera x.
  Pose world_to_projector = world_to_cam;
  world_to_projector.translation().x() -= params.sensor.baseline_mm;
  render_all(model, bin, model_to_world, world_to_projector, params.intrinsics, projector);
}

std::vector<GtInfo> visibility_info(const PipeModel& model, const SimulatedScene& scene) {
  const int n = int(scene.model_to_world.size());
  std::vector<GtInfo> info(n);
  // Each pipe alone, drawn only into the box it covers, on a canvas three times the image's size
  // with the image in its middle (as the BOP toolkit's calc_gt_info does): a pipe reaching out of
  // the view counts its whole silhouette, and the part outside is not seen.
  const Intrinsics& k = scene.camera.intrinsics;
  Intrinsics wide = k;
  wide.width = 3 * k.width, wide.height = 3 * k.height;
  wide.cx = k.cx + k.width, wide.cy = k.cy + k.height;
  Image<float> alone(wide.width, wide.height, 0.0f);
  ProjectedMesh projected;
  projected.reserve(model.mesh);
  for (int i = 0; i < n; ++i) {
    const PixelBox box = render_depth_in_box(model.mesh, scene.model_to_cam(i), wide, &alone, &projected);
    int all = 0, visib = 0, valid = 0, by_pipes = 0;
    for (int y = box.y0; y <= box.y1; ++y)
      for (int x = box.x0; x <= box.x1; ++x) {
        if (alone.at(x, y) <= 0) continue;
        ++all;
        const int u = x - k.width, v = y - k.height;  // in the image
        if (u < 0 || v < 0 || u >= k.width || v >= k.height) continue;
        const int front = scene.clean.label.at(u, v);
        if (front == i) {
          ++visib;
          if (scene.depth_mm.at(u, v) > 0) ++valid;
        } else if (front >= 0 && front < n) {
          ++by_pipes;
        }
      }
    GtInfo& g = info[i];
    g.px_count_all = all;
    g.px_count_visib = visib;
    g.px_count_valid = valid;
    g.visib_fract = all ? double(visib) / all : 0.0;
    g.occ_by_pipes = all ? double(by_pipes) / all : 1.0;
    // DESIGN.md: a top pipe is at most 5 % covered by pipes and at least 40 % validly seen.
    g.top = all > 0 && g.occ_by_pipes <= 0.05 && double(valid) / all >= 0.40;
  }
  return info;
}

SimulatedScene render_scene(const PipeModel& model, std::vector<Pose> model_to_world,
                            const SceneParams& params, std::mt19937& rng) {
  SimulatedScene scene;
  scene.model_to_world = std::move(model_to_world);
  scene.camera.intrinsics = params.intrinsics;
  scene.camera.depth_scale = 1.0;
  scene.camera.world_to_cam = draw_camera(params, rng);
  DepthTarget projector;
  render_views(model, scene.model_to_world, *scene.camera.world_to_cam, params, &scene.clean, &projector);
  scene.depth_mm = apply_sensor_model(scene.clean, projector, params.intrinsics, params.sensor,
                                      int(scene.model_to_world.size()), rng);
  scene.info = visibility_info(model, scene);
  return scene;
}

SimulatedScene simulate_scene(const PipeModel& model, const SceneParams& params, std::mt19937& rng) {
  return render_scene(model, build_pile(model, params.pile, rng), params, rng);
}

}  // namespace pipeloc
