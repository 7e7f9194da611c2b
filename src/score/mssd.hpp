// Maximum symmetry-aware surface distance (DESIGN.md scoring; BOP's MSSD).
#pragma once

#include <vector>

#include "core/pose.hpp"

namespace pipeloc {

// max over vertices |T_est v - T_true S v|, minimised over S in {I} + symmetries.
// Work stops once an error is known to exceed `cap_mm`; such errors are returned as > cap_mm.
double mssd(const std::vector<Eigen::Vector3d>& vertices, const Pose& est, const Pose& truth,
            const std::vector<Pose>& symmetries, double cap_mm);

// A straight tube is the same under any turn about its axis (BOP's continuous symmetry), which
// no finite list holds. For scoring and for judging picks: if the vertices form a straight tube
// (none farther than 3 % beyond the median distance from the principal axis), the turns about
// that axis in `steps` steps, each also combined with `symmetries`; otherwise `symmetries`.
// 72 steps leave at most R sin(2.5 deg), under 1 mm for a 45 mm tube.
std::vector<Pose> with_tube_turns(const std::vector<Eigen::Vector3d>& vertices,
                                  const std::vector<Pose>& symmetries, int steps = 72);

}  // namespace pipeloc
