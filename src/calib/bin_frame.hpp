// calibrate-bin: the bin frame from one depth frame of the bin. The floor is the largest plane
// facing the camera (what is visible between pipes is enough); the walls are the sharpest
// straight edges of what stands above it. The frame: Z up (against gravity, out of the floor),
// X along the bin's longer side (towards the image's right), origin on the floor at the bin's
// centre; the interior is the rectangle between the walls' inner faces.
#pragma once

#include <string>

#include "calib/plane_fit.hpp"
#include "core/camera.hpp"
#include "core/image.hpp"

namespace pipeloc {

struct BinCalibParams {
  PlaneFitParams plane{};        // floor: inlier_mm, iterations, max_normal_deg from the optical axis
  double min_floor_share = 0.2;  // of the valid pixels: less and the frame holds no floor
  int min_floor_points = 2000;
  double wall_min_height_mm = 20;  // points this far above the floor may belong to a wall
  double wall_edge_share = 0.5;    // a wall's inner edge: where the count of high points per
                                   // 1 mm strip first reaches this share of its side's peak
  double roi_margin_mm = 5;        // the region of interest stays this far inside the walls
  // The walls not looked for (a camera that sees only part of the bin): world_to_cam from the
  // floor alone, origin at the floor's centroid in view, X along the image's x; no region of interest.
  bool floor_only = false;
  BinCalibParams() {
    plane.inlier_mm = 10;
    plane.iterations = 500;
    plane.max_normal_deg = 50;
    plane.facing = {0, 0, -1};
  }
};

struct BinCalib {
  bool ok = false;
  std::string error;  // why not, for the integrator
  Pose world_to_cam = Pose::Identity();
  double floor_rms_mm = 0;  // residual of the floor points about the plane
  double floor_share = 0;   // floor inliers / valid pixels
  int floor_points = 0, valid_points = 0;
  bool walls = false;  // the walls were found: the interior and the region of interest hold
  double interior_x_mm = 0, interior_y_mm = 0;  // between the walls' inner faces
  double roi_min_mm[2] = {0, 0}, roi_max_mm[2] = {0, 0};
};

BinCalib calibrate_bin(const Image<float>& depth_mm, const Intrinsics& k, const BinCalibParams& params = {});

// The result as TOML for the config ([source.openni2] world_to_cam, [locate] roi_*), with the
// fit's figures as comments.
std::string bin_calib_toml(const BinCalib& calib);

}  // namespace pipeloc
