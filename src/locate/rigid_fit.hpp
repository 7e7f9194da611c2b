// Algorithm 2's step 2.2.3: the rigid transform best taking one point set onto another.
#pragma once

#include "core/pose.hpp"

namespace pipeloc {

// Rigid transform taking src onto dst in the least-squares sense (Kabsch), fixed-size maths.
// With `no_roll_on_line`, points lying along a line give no turn about that line (a straight
// tube's ridge: the turn would be the noise's, and roll the tube off its own top line).
Pose fit_rigid(const Eigen::Vector3f* src, const Eigen::Vector3f* dst, int n, bool no_roll_on_line = false);

}  // namespace pipeloc
