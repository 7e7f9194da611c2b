// Beyond the paper: a point-to-plane refinement of a ridge fit on the whole observed region.
#pragma once

#include "locate/locate_config.hpp"
#include "locate/locator_model.hpp"

namespace pipeloc {

struct RefineResult {
  Pose pose = Pose::Identity();
  int inliers = 0;
  float rms_mm = 0;
};

// Point-to-plane ICP of observed points (bin frame) onto the model surface.
RefineResult refine_on_surface(const LocatorModel& lm, const Pose& start, const Eigen::Vector3f* observed,
                               int n, const LocateConfig& cfg);

}  // namespace pipeloc
