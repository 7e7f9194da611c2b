#include "plc/robot_pose.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace pipeloc {
namespace {
constexpr double kDeg = 180.0 / M_PI;
}

EulerConvention parse_euler_convention(const std::string& t) {
  if (t == "ZYX") return EulerConvention::zyx;
  if (t == "XYZ") return EulerConvention::xyz;
  throw std::invalid_argument("Euler convention '" + t + "': expected ZYX (KUKA, ABB, FANUC) or XYZ");
}

std::array<double, 3> euler_deg(const Eigen::Matrix3d& r, EulerConvention c) {
  if (c == EulerConvention::zyx) {
    // R = Rz(a) Ry(b) Rx(g): r20 = -sin b.
    const double b = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
    double a, g;
    if (std::abs(r(2, 0)) < 1 - 1e-9) {
      a = std::atan2(r(1, 0), r(0, 0));
      g = std::atan2(r(2, 1), r(2, 2));
    } else {  // gimbal lock: put all of the turn in z
      a = std::atan2(-r(0, 1), r(1, 1));
      g = 0;
    }
    return {g * kDeg, b * kDeg, a * kDeg};
  }
  // R = Rx(a) Ry(b) Rz(g): r02 = sin b.
  const double b = std::asin(std::clamp(r(0, 2), -1.0, 1.0));
  double a, g;
  if (std::abs(r(0, 2)) < 1 - 1e-9) {
    a = std::atan2(-r(1, 2), r(2, 2));
    g = std::atan2(-r(0, 1), r(0, 0));
  } else {
    a = std::atan2(r(2, 1), r(1, 1));
    g = 0;
  }
  return {a * kDeg, b * kDeg, g * kDeg};
}

Eigen::Matrix3d rotation_from_euler_deg(const std::array<double, 3>& e, EulerConvention c) {
  const Eigen::AngleAxisd rx(e[0] / kDeg, Eigen::Vector3d::UnitX()),
      ry(e[1] / kDeg, Eigen::Vector3d::UnitY()), rz(e[2] / kDeg, Eigen::Vector3d::UnitZ());
  return c == EulerConvention::zyx ? (rz * ry * rx).toRotationMatrix() : (rx * ry * rz).toRotationMatrix();
}

RobotPose to_robot(const Pose& model_to_cam, const Pose& robot_from_camera, const Pose& grasp,
                   EulerConvention c) {
  const Pose p = robot_from_camera * model_to_cam * grasp;
  RobotPose out;
  out.xyz_mm = {p.translation().x(), p.translation().y(), p.translation().z()};
  out.rxyz_deg = euler_deg(p.linear(), c);
  Eigen::Quaterniond q(p.linear());
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1;  // one of the two: w >= 0
  out.wxyz = {q.w(), q.x(), q.y(), q.z()};
  return out;
}

}  // namespace pipeloc
