// The calibration sphere in a depth frame: RANSAC over triples of nearby pixels with the sphere's
// known radius (two centres fit a triple; the one behind the surface is kept), scored by the
// pixels on its visible cap minus those seen through it; then Gauss-Newton on the centre. Found
// when the cap covers enough of the sphere's outline (a plane touching a sphere covers a quarter).
#pragma once

#include <Eigen/Core>

#include "core/camera.hpp"
#include "core/image.hpp"

namespace pipeloc {

struct SphereFitParams {
  double radius_mm = 25;
  double inlier_mm = 4;  // |distance to centre - radius| for a pixel on the sphere
  int iterations = 3000;
  double min_cap_share = 0.5;  // of the pixels a sphere at that distance covers: fewer, none found
  unsigned seed = 1;
};

struct SphereFit {
  bool ok = false;
  Eigen::Vector3d centre_mm = Eigen::Vector3d::Zero();  // camera frame
  int inliers = 0;
  int expected_px = 0;  // pixels the sphere covers at that distance
  double rms_mm = 0;
};

SphereFit find_sphere(const Image<float>& depth_mm, const Intrinsics& k, const SphereFitParams& params);

}  // namespace pipeloc
