// pipeloc calibrate-hand-eye: robot_from_camera from a calibration sphere held by the gripper at
// several stations, each a depth frame and the sphere's position read off the robot's pendant.
#include <spdlog/spdlog.h>

#include <iostream>
#include <memory>
#include <sstream>

#include "app/commands.hpp"
#include "calib/hand_eye.hpp"
#include "calib/sphere_fit.hpp"
#include "calib/stations.hpp"
#include "io/bop.hpp"
#include "io/png.hpp"

namespace pipeloc::app {
namespace {

std::string matrix_toml(const Pose& p) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  const Eigen::Matrix4d m = p.matrix();
  s << "[";
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) {
      s.precision(j == 3 ? 2 : 7);
      s << m(i, j) << ", ";
    }
    s << " ";
  }
  s << "0, 0, 0, 1]";
  return s.str();
}

}  // namespace

void add_calibrate_hand_eye(CLI::App& app) {
  struct Options {
    std::string stations;
    double outlier_factor = 3;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "calibrate-hand-eye",
      "Solve robot_from_camera from a sphere seen at 4 or more robot stations; print TOML");
  cmd->add_option("--stations", opt->stations, "TOML file listing the stations (docs/calibration.md)")
      ->required();
  cmd->add_option("--outlier-factor", opt->outlier_factor,
                  "flag stations whose residual exceeds this x the median")
      ->check(CLI::Range(1.5, 100.0));
  cmd->callback([opt] {
    const StationFile file = read_stations(opt->stations);
    const auto cameras = read_scene_camera(file.camera);
    if (cameras.empty()) throw IoError("'" + file.camera + "': holds no camera");
    const CameraInfo& cam = cameras.begin()->second;
    SphereFitParams params;
    params.radius_mm = file.radius_mm;
    std::vector<Eigen::Vector3d> in_camera, in_robot;
    std::vector<SphereFit> fits;
    for (std::size_t i = 0; i < file.stations.size(); ++i) {
      const Station& s = file.stations[i];
      CameraInfo sized = cam;
      const Image<float> depth = read_depth_for_camera(s.depth, file.camera, cameras.begin()->first, &sized);
      const Intrinsics k = sized.intrinsics;
      const SphereFit fit = find_sphere(depth, k, params);
      if (!fit.ok) {
        spdlog::error(
            "calibrate-hand-eye: station {} '{}': no sphere of radius {} mm found ({} px on the best "
            "cap, {} expected)",
            i + 1, s.depth, file.radius_mm, fit.inliers, fit.expected_px);
        exit_status() = 2;
        return;
      }
      fits.push_back(fit);
      in_camera.push_back(fit.centre_mm);
      in_robot.push_back(s.sphere_in_robot);
    }
    const HandEyeResult he = solve_hand_eye(in_camera, in_robot, opt->outlier_factor);
    if (!he.ok) {
      spdlog::error("calibrate-hand-eye: '{}': {}", opt->stations, he.error);
      exit_status() = 2;
      return;
    }
    std::printf("# pipeloc calibrate-hand-eye: %zu stations, %d used, residual %.2f mm RMS\n",
                file.stations.size(), he.used, he.rms_mm);
    std::printf("# station  sphere in camera (mm)            px on cap  fit rms  residual\n");
    for (std::size_t i = 0; i < fits.size(); ++i)
      std::printf("# %7zu  %8.1f %8.1f %8.1f  %9d  %5.2f mm  %5.2f mm%s\n", i + 1, fits[i].centre_mm.x(),
                  fits[i].centre_mm.y(), fits[i].centre_mm.z(), fits[i].inliers, fits[i].rms_mm,
                  he.residual_mm[i],
                  he.outlier[i] ? "  OUTLIER: check this station's pendant reading and frame" : "");
    std::printf("[plc]\nrobot_from_camera = %s\n", matrix_toml(he.robot_from_camera).c_str());
    for (std::size_t i = 0; i < fits.size(); ++i)
      if (he.outlier[i])
        spdlog::warn("station {} '{}' is an outlier: residual {:.2f} mm", i + 1, file.stations[i].depth,
                     he.residual_mm[i]);
  });
}

}  // namespace pipeloc::app
