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

// The rasterizer scans each row only where a triangle can cover it: it must draw exactly the pixel
// centres inside each triangle, as a test of every pixel of the image finds them, for long thin
// triangles lying across the image (a straight tube's faces), edges along a row, tiny triangles
// and triangles reaching beyond the image.
TEST(Verification, ATriangleDrawsExactlyThePixelCentresInsideIt) {
  Intrinsics k;
  k.width = 640, k.height = 480, k.fx = k.fy = 570, k.cx = 319.5, k.cy = 239.5;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> across(-80, 720), near(-3, 3), depth(800, 1200);
  const auto inside = [](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                         double x, double y) {
    const auto side = [&](const Eigen::Vector2d& p, const Eigen::Vector2d& q) {
      return (q.x() - p.x()) * (y - p.y()) - (q.y() - p.y()) * (x - p.x());
    };
    const double s0 = side(b, c), s1 = side(c, a), s2 = side(a, b);
    return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
  };
  Image<float> z(k.width, k.height, 0.0f);
  ProjectedMesh projected;
  int drawn = 0, differ = 0;
  for (int t = 0; t < 400; ++t) {
    Eigen::Vector2d px[3];
    px[0] = {across(rng), across(rng) * 0.6};
    switch (t % 4) {
      case 0:  // a sliver across the image
        px[1] = {across(rng), across(rng) * 0.6}, px[2] = px[1] + Eigen::Vector2d(near(rng), near(rng));
        break;
      case 1:  // an edge along a row
        px[1] = {across(rng), px[0].y()}, px[2] = {across(rng), across(rng) * 0.6};
        break;
      case 2:  // a few pixels wide
        px[1] = px[0] + Eigen::Vector2d(near(rng), near(rng)),
        px[2] = px[0] + Eigen::Vector2d(near(rng), near(rng));
        break;
      default:
        px[1] = {across(rng), across(rng) * 0.6}, px[2] = {across(rng), across(rng) * 0.6};
    }
    Mesh tri;
    for (const Eigen::Vector2d& p : px) {
      const double d = depth(rng);
      tri.vertices.emplace_back(float((p.x() - k.cx) / k.fx * d), float((p.y() - k.cy) / k.fy * d), float(d));
    }
    tri.faces.push_back({0, 1, 2});
    projected.reserve(tri);
    z.fill(0.0f);
    const PixelBox box = render_depth_in_box(tri, Pose::Identity(), k, &z, &projected);
    // The corners as the renderer projects them: its test and this one then judge the same triangle.
    const Eigen::Vector2d &a = projected.px[0], &b = projected.px[1], &c = projected.px[2];
    for (int y = 0; y < k.height; ++y)
      for (int x = 0; x < k.width; ++x) {
        const bool in_box = x >= box.x0 && x <= box.x1 && y >= box.y0 && y <= box.y1;
        const bool expected = in_box && inside(a, b, c, x, y);
        drawn += z.at(x, y) > 0;
        differ += (z.at(x, y) > 0) != expected;
      }
  }
  EXPECT_EQ(differ, 0);
  EXPECT_GT(drawn, 100000);
}

// Verification reads only the columns the renderer kept per row: they must hold every pixel it
// drew, for a U seen from above, from the side and tilted, and a straight tube lying across the
// image (long faces); and a verification with them must count what one over the whole box does.
TEST(Verification, TheDrawnColumnsHoldEveryPixelDrawn) {
  Intrinsics k;
  k.width = 640, k.height = 480, k.fx = k.fy = 570, k.cx = 320, k.cy = 240;
  Image<float> z(k.width, k.height, 0.0f), depth(k.width, k.height, 0.0f);
  const PipeModel straight = pipe_of("S600", 30, "straight");
  for (const PipeModel* pipe : {&preset_model("u"), &straight}) {
    const PipeModel& model = *pipe;
    const std::string& name = model.source;
    const Mesh welded = weld_vertices(model.mesh, model.tube_diameter_mm / 8);
    ProjectedMesh rows, no_rows;
    rows.reserve(welded, k.height);
    no_rows.reserve(welded);
    int drawn = 0;
    for (const Eigen::Vector3d& turn :
         {Eigen::Vector3d(0, 0, 0.6), Eigen::Vector3d(1.2, 0.3, 0), Eigen::Vector3d(0.4, 1.5, 0.7)}) {
      Pose pose = Pose::Identity();
      pose.linear() = Eigen::AngleAxisd(turn.norm(), turn.normalized()).toRotationMatrix();
      pose.translation() = Eigen::Vector3d(20, -10, 900) - pose.linear() * model.centroid.cast<double>();
      const PixelBox box = render_depth_in_box(welded, pose, k, &z, &rows);
      ASSERT_FALSE(box.empty());
      int outside = 0;
      for (int y = box.y0; y <= box.y1; ++y)
        for (int x = box.x0; x <= box.x1; ++x)
          if (z.at(x, y) > 0) {
            ++drawn;
            outside += x < rows.row_first[std::size_t(y)] || x > rows.row_last[std::size_t(y)];
          }
      EXPECT_EQ(outside, 0) << name << " " << turn.transpose();
      // The image: the pipe as drawn in the box's upper half, seen through in its lower half, and
      // a floor 1200 mm away around it.
      for (int y = 0; y < k.height; ++y)
        for (int x = 0; x < k.width; ++x)
          depth.at(x, y) = z.at(x, y) > 0 ? z.at(x, y) + (2 * y > box.y0 + box.y1 ? 20.0f : 0.0f) : 1200.0f;
      const int hole_side = 3;
      const Verification a =
          verify_pose(welded, Winding::open, pose, depth, k, 7, 10, 2, &z, &rows, hole_side);
      const Verification b =
          verify_pose(welded, Winding::open, pose, depth, k, 7, 10, 2, &z, &no_rows, hole_side);
      EXPECT_GT(a.agree_px, 0) << name;
      EXPECT_GT(a.free_space_px, 0) << name;
      EXPECT_EQ(a.model_px, b.model_px);
      EXPECT_EQ(a.inner_px, b.inner_px);
      EXPECT_EQ(a.agree_px, b.agree_px);
      EXPECT_EQ(a.free_space_px, b.free_space_px);
      EXPECT_EQ(a.inner_free_space_px, b.inner_free_space_px);
      EXPECT_EQ(a.side_px, b.side_px);
      EXPECT_EQ(a.side_level_px, b.side_level_px);
      EXPECT_EQ(a.seen_through_patch, b.seen_through_patch);
    }
    EXPECT_GT(drawn, 3000) << name;
  }
}

// A pose whose pipe lies wholly beside the image, level with its rows, draws nothing: its
// verification reads no pixel, whatever earlier renders left in the scratch image and its rows
// (such a pose once read a pipe rendered before it: agreement 0.78 or 0.43 by the order in which
// the threads had taken the candidates, on a zoo arc).
TEST(Verification, APipeBesideTheImageReadsNothingLeftByAnEarlierRender) {
  Intrinsics k;
  k.width = 640, k.height = 480, k.fx = k.fy = 570, k.cx = 320, k.cy = 240;
  const PipeModel& model = preset_model("u");
  const Mesh welded = weld_vertices(model.mesh, model.tube_diameter_mm / 8);
  Image<float> z(k.width, k.height, 0.0f), depth(k.width, k.height, 0.0f);
  ProjectedMesh rows;
  rows.reserve(welded, k.height);
  Pose seen = Pose::Identity();
  seen.translation() = Eigen::Vector3d(0, 0, 900) - model.centroid.cast<double>();
  ASSERT_FALSE(render_depth_in_box(welded, seen, k, &depth, &rows).empty());  // the image: the pipe
  const Verification first = verify_pose(welded, Winding::open, seen, depth, k, 7, 10, 2, &z, &rows);
  ASSERT_GT(first.agree_px, 1000);
  for (const double x_mm : {-2000.0, 2000.0}) {
    Pose beside = seen;
    beside.translation().x() += x_mm;  // the same rows, left or right of the image
    const Verification v = verify_pose(welded, Winding::open, beside, depth, k, 7, 10, 2, &z, &rows);
    EXPECT_TRUE(v.box.empty()) << x_mm;
    EXPECT_EQ(v.model_px, 0) << x_mm;
    EXPECT_EQ(v.agree_px, 0) << x_mm;
    EXPECT_EQ(v.side_px, 0) << x_mm;
    EXPECT_EQ(v.agreement(), 0.0f) << x_mm;
  }
}

// A pixel without a reading (a sensor's shadow, a specular hole) is neither for nor against a
// pose: counted apart, neither agreeing nor free space nor in front.
TEST(Verification, PixelsWithoutAReadingAreCountedApart) {
  const PipeModel& model = preset_model("u");
  const Mesh welded = weld_vertices(model.mesh, model.tube_diameter_mm / 8);
  const Winding winding = closed_winding(model.mesh);
  Intrinsics k;
  k.width = 640, k.height = 480, k.fx = k.fy = 570, k.cx = 320, k.cy = 240;
  Pose pose = Pose::Identity();
  pose.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(20, -10, 900);
  Image<float> depth(k.width, k.height, 0.0f), scratch(k.width, k.height, 0.0f);
  ProjectedMesh projected;
  projected.reserve(welded);
  const PixelBox box = render_depth_in_box(welded, pose, k, &depth, &projected, winding);
  ASSERT_FALSE(box.empty());
  const auto check = [&] {
    return verify_pose(welded, winding, pose, depth, k, 7, 5, 0, &scratch, &projected);
  };
  const Verification whole = check();
  ASSERT_GT(whole.model_px, 1000);
  EXPECT_EQ(whole.agree_px, whole.model_px);
  EXPECT_EQ(whole.unread_px, 0);
  // The sensor reads nothing on the left third of the pipe.
  const int cut = box.x0 + (box.x1 - box.x0) / 3;
  for (int y = box.y0; y <= box.y1; ++y)
    for (int x = box.x0; x <= cut; ++x) depth.at(x, y) = 0;
  const Verification part = check();
  EXPECT_EQ(part.model_px, whole.model_px);
  EXPECT_GT(part.unread_px, whole.model_px / 10);
  EXPECT_EQ(part.agree_px + part.unread_px, part.model_px);
  EXPECT_EQ(part.free_space_px + part.occluded_px, 0);
  EXPECT_FLOAT_EQ(part.agreement() + part.unread(), 1.0f);
}

}  // namespace
}  // namespace pipeloc
