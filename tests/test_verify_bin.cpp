// Verification that knows the bin: no pose below the floor, and a smooth blob is not a pipe.
#include <gtest/gtest.h>

#include <cmath>

#include "locate/locator.hpp"
#include "model/make_pipe.hpp"
#include "model/pipe_model.hpp"

namespace pipeloc {
namespace {

constexpr double kCameraHeightMm = 900;
constexpr double kTubeMm = 20;

// A camera straight above the origin of a floor at z = 0, and a straight tube of kTubeMm along the
// world x axis with its axis at height axis_z_mm; `surround_z_mm` is the height of the flat
// surface beside it (the floor: 0; a blob's flank: the axis height, so that nothing drops away).
struct Scene {
  CameraInfo camera;
  Image<float> depth;
};
Scene straight_tube_scene(double axis_z_mm, double surround_z_mm) {
  Scene s;
  const Intrinsics& k = s.camera.intrinsics;
  Pose w2c = Pose::Identity();
  w2c.linear() = Eigen::Vector3d(1, -1, -1).asDiagonal();
  w2c.translation() = Eigen::Vector3d(0, 0, kCameraHeightMm);
  s.camera.world_to_cam = w2c;
  s.depth.resize(k.width, k.height, 0.0f);
  const double r = kTubeMm / 2, half_length = 75;
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      // The ray in the world frame from the camera at (0, 0, H); its camera depth is the parameter t.
      const Eigen::Vector3d d((u - k.cx) / k.fx, -(v - k.cy) / k.fy, -1.0);
      // The flat surface beside the tube, 2.5 D either side of it; the floor beyond.
      double t = kCameraHeightMm - surround_z_mm;
      if (std::abs(t * d.y()) > 2.5 * kTubeMm || std::abs(t * d.x()) > half_length) t = kCameraHeightMm;
      // The tube: (y(t))^2 + (z(t) - axis_z)^2 = r^2.
      const double oz = kCameraHeightMm - axis_z_mm;
      const double a = d.y() * d.y() + d.z() * d.z(), b = 2 * oz * d.z(), c = oz * oz - r * r;
      const double disc = b * b - 4 * a * c;
      if (disc >= 0) {
        const double hit = (-b - std::sqrt(disc)) / (2 * a);
        if (hit > 0 && std::abs(hit * d.x()) <= half_length) t = std::min(t, hit);
      }
      s.depth.at(u, v) = float(t);
    }
  return s;
}

const PipeModel& straight_tube() {
  static const PipeModel model = [] {
    PipeSpec spec;
    spec.diameter_mm = kTubeMm;
    spec.segments = parse_centreline("S150");
    return derive_pipe_model(make_pipe(spec), "straight");
  }();
  return model;
}

int pickable(const LocateOutput& out) {
  int n = 0;
  for (const PipeEstimate& e : out.estimates) n += e.pickable;
  return n;
}

TEST(BinAwareVerification, APipeOnTheFloorIsPickedAndTheSameTopOnASmoothBlobIsNot) {
  const PipeModel& model = straight_tube();
  LocateConfig cfg;
  const Scene on_floor = straight_tube_scene(kTubeMm / 2, 0);
  Locator loc(model, cfg, on_floor.camera.intrinsics);
  EXPECT_EQ(pickable(loc.locate(on_floor.depth, on_floor.camera)), 1);
  // The same top, its flanks going on at the axis' height: a smooth blob, not a pipe.
  const Scene blob = straight_tube_scene(kTubeMm / 2, kTubeMm / 2);
  EXPECT_EQ(pickable(loc.locate(blob.depth, blob.camera)), 0);
}

TEST(BinAwareVerification, NoPoseBelowTheFloor) {
  const PipeModel& model = straight_tube();
  const Scene on_floor = straight_tube_scene(kTubeMm / 2, 0);
  LocateConfig cfg;
  Locator loc(model, cfg, on_floor.camera.intrinsics);
  const LocateOutput& out = loc.locate(on_floor.depth, on_floor.camera);
  EXPECT_NEAR(out.lowest_surface_z_mm, 0, 1.5);  // the floor, seen around the pipe
  ASSERT_FALSE(out.estimates.empty());
  const Pose lying = out.estimates[0].model_to_bin;
  const float below = out.lowest_surface_z_mm - 0.25f * float(kTubeMm);
  EXPECT_LT(share_below(model.mesh, lying, below), 0.05);
  Pose sunk = lying;  // the same pipe a diameter lower: under the floor
  sunk.translation().z() -= kTubeMm;
  EXPECT_GT(share_below(model.mesh, sunk, below), 0.9);
}

}  // namespace
}  // namespace pipeloc
