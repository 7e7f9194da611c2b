// The pose handed to the robot: the gripper's closing pose in the robot frame, as X Y Z (mm),
// three Euler angles (degrees) in the configured convention, and a unit quaternion.
#pragma once

#include <array>
#include <string>

#include "core/pose.hpp"

namespace pipeloc {

// zyx: R = Rz(rz) Ry(ry) Rx(rx) (intrinsic Z-Y'-X'' = fixed X-Y-Z): KUKA A B C = rz ry rx,
//      FANUC W P R = rx ry rz, ABB Euler ZYX. The same angles, only named differently.
// xyz: R = Rx(rx) Ry(ry) Rz(rz) (intrinsic X-Y'-Z'', e.g. Staubli).
enum class EulerConvention { zyx, xyz };
EulerConvention parse_euler_convention(const std::string& text);  // "ZYX" or "XYZ"

struct RobotPose {
  std::array<double, 3> xyz_mm{};
  std::array<double, 3> rxyz_deg{};  // about x, y, z, as the convention composes them
  std::array<double, 4> wxyz{};      // w >= 0
};

std::array<double, 3> euler_deg(const Eigen::Matrix3d& r, EulerConvention convention);
Eigen::Matrix3d rotation_from_euler_deg(const std::array<double, 3>& rxyz_deg, EulerConvention convention);

// robot_from_camera: the hand-eye calibration (identity: the camera frame). grasp: where the
// gripper closes, in the model frame.
RobotPose to_robot(const Pose& model_to_cam, const Pose& robot_from_camera, const Pose& grasp_in_model,
                   EulerConvention convention);

}  // namespace pipeloc
