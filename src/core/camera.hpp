// Pinhole intrinsics and the optional world (bin) frame of a depth image.
#pragma once

#include <Eigen/Geometry>
#include <optional>

#include "core/pose.hpp"

namespace pipeloc {

struct Intrinsics {
  int width = 640;
  int height = 480;
  double fx = 570.3, fy = 570.3, cx = 319.5, cy = 239.5;

  Eigen::Vector2d project(const Eigen::Vector3d& p_cam) const {
    return {fx * p_cam.x() / p_cam.z() + cx, fy * p_cam.y() / p_cam.z() + cy};
  }
  Eigen::Vector3d unproject(double u, double v, double z_mm) const {
    return {(u - cx) * z_mm / fx, (v - cy) * z_mm / fy, z_mm};
  }
};

struct CameraInfo {
  Intrinsics intrinsics;
  double depth_scale = 1.0;          // depth_mm = png value * depth_scale
  std::optional<Pose> world_to_cam;  // cam_R_w2c / cam_t_w2c: world Z points up
  bool size_given = false;           // the camera file gave width/height (BOP's files need not)
};

}  // namespace pipeloc
