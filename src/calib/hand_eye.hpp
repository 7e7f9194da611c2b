// Hand-eye from points: the calibration sphere's centre seen by the camera and read off the
// robot's pendant (its tool-centre point set to the sphere's centre) at several stations; the
// rigid transform between them by Umeyama's least squares (no scale).
#pragma once

#include <string>
#include <vector>

#include "core/pose.hpp"

namespace pipeloc {

struct HandEyeResult {
  bool ok = false;
  std::string error;
  Pose robot_from_camera = Pose::Identity();
  std::vector<double> residual_mm;  // per station: |robot_from_camera * camera - robot|
  std::vector<bool> outlier;        // residual > factor x median (and above the floor); left out of
                                    // the solution when at least 4 stations remain
  double rms_mm = 0;                // over the stations used
  int used = 0;
};

// At least 4 stations, not all on one line (the rotation about it would be unknown).
HandEyeResult solve_hand_eye(const std::vector<Eigen::Vector3d>& in_camera,
                             const std::vector<Eigen::Vector3d>& in_robot, double outlier_factor = 3,
                             double outlier_floor_mm = 1.0);

}  // namespace pipeloc
