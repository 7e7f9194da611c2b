// Beyond the paper: a point-to-plane refinement of a ridge fit on the whole observed region.
#pragma once

#include <cmath>

#include "locate/locate_config.hpp"
#include "locate/locator_model.hpp"

namespace pipeloc {

struct RefineResult {
  Pose pose = Pose::Identity();
  int inliers = 0;
  float rms_mm = 0;
};

// A model sample whose outward normal turns further than this from the camera (the sine of the
// angle beyond the silhouette's horizon, about 17 degrees) cannot be what a sensor point saw: the
// slack keeps the rim, where the tube's lateral place is read, for poses that far off.
constexpr float kFacingSlack = 0.3f;

// Point-to-plane ICP of observed points (bin frame) onto the model surface. With the camera's
// centre (bin frame), for a pipe that does not slide along itself:
// - with refine_ray_pairs (off by default), in the last iterations a point pairs with the tube
//   where the camera's ray through it meets it, near its nearest sample: its depth noise lies
//   along that ray (docs/experiments.md, "Points paired along the camera's rays");
// - else, or where that ray misses the tube, with its nearest sample, and with refine_facing_only
//   only if that faces the camera: a reading of the floor or a neighbour beside a thin tube
//   otherwise pairs with the tube's hidden underside and turns the fit ("The refinement pairs
//   points with the surface the camera sees").
// A pipe that slides along itself (an arc, a coil, a straight run; its ends place it) pairs with
// the nearest sample whatever it faces: facing only cost the zoo's 252-degree arc 4 of 6 pipes
// taken and a coil a wrong pick in 6 bins. Without the camera (NaN), with the nearest sample.
RefineResult refine_on_surface(const LocatorModel& lm, const Pose& start, const Eigen::Vector3f* observed,
                               int n, const LocateConfig& cfg,
                               const Eigen::Vector3f& camera_bin = Eigen::Vector3f::Constant(NAN));

}  // namespace pipeloc
