// Algorithm 2's step 2.2.3: the rigid transform best taking one point set onto another.
#pragma once

#include "core/pose.hpp"

namespace pipeloc {

// Rigid transform taking src onto dst in the least-squares sense (Kabsch), fixed-size maths.
Pose fit_rigid(const Eigen::Vector3f* src, const Eigen::Vector3f* dst, int n);

}  // namespace pipeloc
