// III: the principal direction of a region.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "locate/locator.hpp"
#include "locate_fixtures.hpp"

namespace pipeloc {
namespace {

// III on the noisy frame against III on the ideal top view of the pipe at its true pose.
// Measured for the S-bend, where the cross-section count has one clear peak. For the U and the
// torus-like pipe the count is flat over tens of degrees even on ideal data (their median
// disagreement is 15 degrees, see the closing note of issue 3); the initial states absorb that
// by measuring the model the same way (LocatorModel::canonical_starts).
TEST(PrincipalAxis, WithinFiveDegreesOfTheIdealForTheSBend) {
  for (const char* name : {"sbend"}) {
    std::vector<double> errors;
    for (unsigned seed = 1; seed <= 5; ++seed) {
      OnePipe s = one_pipe(name, seed);
      Locator loc(preset_model(name), s.cfg, s.scene.camera.intrinsics);
      const LocateOutput& out = loc.locate(s.scene.depth_mm, s.scene.camera);
      if (out.traces.empty()) continue;
      const Eigen::Vector2f truth = top_view_axis(preset_model(name), s.scene.model_to_world[0], s.cfg).axis;
      errors.push_back(std::acos(std::min(1.0f, std::abs(truth.dot(out.traces[0].axis.axis)))) * 180 / M_PI);
    }
    // A lone pipe is found in most frames, and its direction agrees with the ideal one.
    ASSERT_GE(errors.size(), 3u) << name;
    std::sort(errors.begin(), errors.end());
    EXPECT_LT(errors[errors.size() / 2], 5.0) << name;
    EXPECT_LT(errors.back(), 15.0) << name;
  }
}

}  // namespace
}  // namespace pipeloc
