// Maximum symmetry-aware surface distance (DESIGN.md scoring; BOP's MSSD).
#pragma once

#include <vector>

#include "core/pose.hpp"

namespace pipeloc {

// max over vertices |T_est v - T_true S v|, minimised over S in {I} + symmetries.
// Work stops once an error is known to exceed `cap_mm`; such errors are returned as > cap_mm.
double mssd(const std::vector<Eigen::Vector3d>& vertices, const Pose& est, const Pose& truth,
            const std::vector<Pose>& symmetries, double cap_mm);

}  // namespace pipeloc
