// Beyond the paper: verification of a pose against the depth image.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "locate/locator.hpp"
#include "locate_fixtures.hpp"

namespace pipeloc {
namespace {

// Verification skips the faces of a closed model turned away from the camera: the depth drawn
// must be the same as with every face, at poses seen from above, from the side and tilted.
TEST(Verification, SkippingBackFacesOfAClosedModelDrawsTheSameDepth) {
  const PipeModel& model = preset_model("u");
  const Mesh welded = weld_vertices(model.mesh, model.tube_diameter_mm / 8);
  const Winding winding = closed_winding(model.mesh);
  ASSERT_EQ(winding, Winding::outward);
  Intrinsics k;
  k.width = 640, k.height = 480, k.fx = k.fy = 570, k.cx = 320, k.cy = 240;
  Image<float> all(k.width, k.height, 0.0f), front(k.width, k.height, 0.0f);
  ProjectedMesh projected;
  projected.reserve(welded);
  int drawn = 0;
  for (const Eigen::Vector3d& turn :
       {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1.2, 0.3, 0), Eigen::Vector3d(0.4, 1.5, 0.7)}) {
    Pose pose = Pose::Identity();
    if (turn.norm() > 0) pose.linear() = Eigen::AngleAxisd(turn.norm(), turn.normalized()).toRotationMatrix();
    pose.translation() = Eigen::Vector3d(20, -10, 900);
    const PixelBox a = render_depth_in_box(welded, pose, k, &all, &projected);
    const PixelBox b = render_depth_in_box(welded, pose, k, &front, &projected, winding);
    ASSERT_FALSE(a.empty());
    EXPECT_EQ(a.x0, b.x0);
    EXPECT_EQ(a.y1, b.y1);
    int differ = 0;
    for (int y = a.y0; y <= a.y1; ++y)
      for (int x = a.x0; x <= a.x1; ++x) {
        drawn += all.at(x, y) > 0;
        differ += std::abs(all.at(x, y) - front.at(x, y)) > 1e-3f;
      }
    EXPECT_EQ(differ, 0) << turn.transpose();
  }
  EXPECT_GT(drawn, 3000);
}

}  // namespace
}  // namespace pipeloc
