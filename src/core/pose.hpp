// Rigid poses as BOP stores them: R row-major (9 values) and t in mm, model -> camera.
#pragma once

#include <Eigen/Geometry>
#include <array>

namespace pipeloc {

using Pose = Eigen::Isometry3d;

Pose pose_from_rt(const std::array<double, 9>& r_rowmajor, const std::array<double, 3>& t_mm);
std::array<double, 9> rotation_rowmajor(const Pose& pose);
std::array<double, 3> translation_mm(const Pose& pose);

// A 4x4 row-major matrix (16 values, mm) as a pose; its rotation part is made proper (SVD), so a
// calibration typed with few digits still gives a rigid transform.
Pose pose_from_matrix_rowmajor(const double* m16);

// Nearest proper rotation (SVD): BOP files carry rounded values.
Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& m);

// Rotation angle in degrees between two rotations.
double rotation_angle_deg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);

}  // namespace pipeloc
