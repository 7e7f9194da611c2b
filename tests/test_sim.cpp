#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "model/make_pipe.hpp"
#include "model/neighbors.hpp"
#include "sim/scene.hpp"

namespace pipeloc {
namespace {

PipeModel coarse_model(const char* preset) {
  PipeSpec spec = pipe_preset(preset);
  spec.sides = 16;
  spec.bend_step_deg = 10;
  return derive_pipe_model(make_pipe(spec), preset);
}

SceneParams small_params(int pipes) {
  SceneParams p;
  p.pile.pipes = pipes;
  return p;
}

TEST(Simulator, SameSeedSameScene) {
  const PipeModel model = coarse_model("u");
  std::mt19937 a(42), b(42);
  const SimulatedScene s1 = simulate_scene(model, small_params(8), a);
  const SimulatedScene s2 = simulate_scene(model, small_params(8), b);
  ASSERT_EQ(s1.model_to_world.size(), s2.model_to_world.size());
  EXPECT_EQ(s1.depth_mm.pixels, s2.depth_mm.pixels);
  for (std::size_t i = 0; i < s1.model_to_world.size(); ++i)
    EXPECT_TRUE(s1.model_to_world[i].isApprox(s2.model_to_world[i]));
}

// The noisy image agrees with the noise-free render at the true poses within the noise model:
// on valid pixels of smooth surfaces, within 5 sigma plus one disparity step; for both sensors.
void expect_depth_within_noise_model(const SceneParams& params) {
  const PipeModel model = coarse_model("sbend");
  std::mt19937 rng(3);
  const SimulatedScene s = simulate_scene(model, params, rng);
  const auto& clean = s.clean.z_mm;
  int checked = 0, outside = 0, valid = 0, rendered = 0;
  for (int y = 2; y < clean.height - 2; ++y) {
    for (int x = 2; x < clean.width - 2; ++x) {
      if (clean.at(x, y) > 0) ++rendered;
      const float z = s.depth_mm.at(x, y);
      if (z <= 0) continue;
      ++valid;
      float lo = 1e9f, hi = 0;
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx)
          lo = std::min(lo, clean.at(x + dx, y + dy)), hi = std::max(hi, clean.at(x + dx, y + dy));
      if (lo <= 0 || hi - lo > 3) continue;  // edges: lateral noise may pick the neighbour
      ++checked;
      const double bound = 5 * params.sensor.axial_sigma_mm(clean.at(x, y), params.intrinsics.fx) *
                               2 +  // grazing doubles it at most
                           params.sensor.depth_step_mm(clean.at(x, y), params.intrinsics.fx) +
                           (hi - lo);
      outside += std::abs(z - clean.at(x, y)) > bound;
    }
  }
  EXPECT_GT(checked, 50000);
  EXPECT_LT(double(outside) / checked, 1e-3) << outside << " of " << checked;
  // The sensor loses some pixels (shadows, grazing, glints, dropouts) but not most.
  EXPECT_LT(valid, rendered);
  EXPECT_GT(valid, rendered * 8 / 10);
}

TEST(Simulator, NoisyDepthAgreesWithTruthWithinNoiseModel) {
  expect_depth_within_noise_model(small_params(15));
}

TEST(Simulator, StereoDepthAgreesWithTruthWithinItsNoiseModelFromClose) {
  SceneParams params = small_params(15);
  params.sensor = sensor_model("stereo");
  params.camera_height_min_mm = 450, params.camera_height_max_mm = 550;
  expect_depth_within_noise_model(params);
}

TEST(Simulator, StereoNoiseIsDisparityNoiseOverFocalLengthAndBaseline) {
  const SensorModel stereo = sensor_model("stereo");
  // sigma_z = z^2 0.08 px / (f b), b = 50 mm; depth steps of 1/32 px.
  EXPECT_NEAR(stereo.axial_sigma_mm(1000, 570), 1e6 * 0.08 / (570 * 50), 1e-9);
  EXPECT_NEAR(stereo.depth_step_mm(1000, 570), 1e6 / 32 / (570 * 50), 1e-9);
  EXPECT_EQ(stereo.min_range_mm, 300);
  EXPECT_THROW(sensor_model("tof"), std::invalid_argument);
  // The Kinect-class model is the default one.
  EXPECT_EQ(sensor_model("kinect").axial_sigma_mm(1000, 570), SensorModel{}.axial_sigma_mm(1000, 570));
}

// Pixels at a depth edge reading no depth near them: the stereo matcher's blend of fore- and
// background (lateral noise only moves a reading to a neighbour's depth).
int flying_pixels(const SceneParams& params) {
  const PipeModel model = coarse_model("sbend");
  std::mt19937 rng(5);
  const SimulatedScene s = simulate_scene(model, params, rng);
  const auto& clean = s.clean.z_mm;
  int flying = 0;
  for (int y = 2; y < clean.height - 2; ++y)
    for (int x = 2; x < clean.width - 2; ++x) {
      const float z = s.depth_mm.at(x, y);
      if (z <= 0) continue;
      float nearest = 1e9f;
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) nearest = std::min(nearest, std::abs(clean.at(x + dx, y + dy) - z));
      flying += nearest > 10;
    }
  return flying;
}

TEST(Simulator, StereoSensorHasFlyingPixelsAtDepthEdges) {
  SceneParams kinect = small_params(15), stereo = small_params(15);
  stereo.sensor = sensor_model("stereo");
  const int k = flying_pixels(kinect), s = flying_pixels(stereo);
  EXPECT_GT(s, 300);
  EXPECT_GT(s, 5 * k) << "kinect " << k << ", stereo " << s;
}

// Möller–Trumbore, for the brute-force recount.
double ray_hit(const Eigen::Vector3d& d, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
               const Eigen::Vector3d& c) {
  const Eigen::Vector3d e1 = b - a, e2 = c - a, p = d.cross(e2);
  const double det = e1.dot(p);
  if (std::abs(det) < 1e-12) return -1;
  const Eigen::Vector3d s = -a;
  const double u = s.dot(p) / det;
  if (u < 0 || u > 1) return -1;
  const Eigen::Vector3d q = s.cross(e1);
  const double v = d.dot(q) / det;
  if (v < 0 || u + v > 1) return -1;
  return e2.dot(q) / det;
}

// px_count_all / px_count_visib agree with an independent per-pixel ray cast against every
// triangle of every pipe, on a small image.
TEST(Simulator, VisibilityMatchesBruteForceRayCast) {
  const PipeModel model = coarse_model("u");
  SceneParams params = small_params(7);
  params.intrinsics = {160, 120, 142.6, 142.6, 79.5, 59.5};
  std::mt19937 rng(11);
  const SimulatedScene s = simulate_scene(model, params, rng);
  const int n = int(s.model_to_world.size());
  ASSERT_GE(n, 5);
  std::vector<std::vector<Eigen::Vector3d>> verts(n);
  for (int i = 0; i < n; ++i)
    for (const auto& v : model.mesh.vertices) verts[i].push_back(s.model_to_cam(i) * v.cast<double>());
  std::vector<int> all(n, 0), visib(n, 0);
  for (int y = 0; y < params.intrinsics.height; ++y) {
    for (int x = 0; x < params.intrinsics.width; ++x) {
      const Eigen::Vector3d ray((x - params.intrinsics.cx) / params.intrinsics.fx,
                                (y - params.intrinsics.cy) / params.intrinsics.fy, 1);
      double nearest = 1e18;
      int front = -1;
      for (int i = 0; i < n; ++i) {
        double best = -1;
        for (const auto& f : model.mesh.faces) {
          const double t = ray_hit(ray, verts[i][f[0]], verts[i][f[1]], verts[i][f[2]]);
          if (t > 0 && (best < 0 || t < best)) best = t;
        }
        if (best < 0) continue;
        ++all[i];
        if (best < nearest) nearest = best, front = i;
      }
      if (front >= 0) ++visib[front];
    }
  }
  for (int i = 0; i < n; ++i) {
    const double tol = std::max(3.0, 0.03 * all[i]);  // pixel centres on triangle edges
    EXPECT_NEAR(s.info[i].px_count_all, all[i], tol) << "pipe " << i;
    EXPECT_NEAR(s.info[i].px_count_visib, visib[i], tol) << "pipe " << i;
    const double occ = all[i] ? 1.0 - double(visib[i]) / all[i] : 1.0;
    EXPECT_NEAR(s.info[i].occ_by_pipes, occ, 0.05) << "pipe " << i;
    EXPECT_EQ(s.info[i].top,
              s.info[i].occ_by_pipes <= 0.05 && s.info[i].px_count_valid >= 0.4 * s.info[i].px_count_all);
  }
}

// A pipe reaching out of the view counts its whole silhouette (the BOP toolkit's calc_gt_info
// draws it on a canvas three times the image's size): the same pile seen through the middle third
// of an image has the same px_count_all per pipe, and a pipe cut by the edge is seen less.
TEST(Simulator, APipeReachingOutOfTheViewCountsItsWholeSilhouette) {
  const PipeModel model = coarse_model("u");
  SceneParams wide = small_params(7);
  wide.intrinsics = {480, 360, 400, 400, 239.5, 179.5};
  SceneParams narrow = wide;
  narrow.intrinsics = {160, 120, 400, 400, 79.5, 59.5};
  std::mt19937 a(11), b(11);
  const SimulatedScene whole = simulate_scene(model, wide, a);
  const SimulatedScene cut = simulate_scene(model, narrow, b);
  ASSERT_EQ(whole.info.size(), cut.info.size());
  int reaching_out = 0;
  for (std::size_t i = 0; i < whole.info.size(); ++i) {
    ASSERT_TRUE(whole.model_to_cam(int(i)).isApprox(cut.model_to_cam(int(i))));
    EXPECT_NEAR(cut.info[i].px_count_all, whole.info[i].px_count_all, 2) << "pipe " << i;
    EXPECT_LE(cut.info[i].px_count_visib, whole.info[i].px_count_visib) << "pipe " << i;
    if (cut.info[i].px_count_visib + 20 < whole.info[i].px_count_visib) {
      ++reaching_out;
      EXPECT_LT(cut.info[i].visib_fract, whole.info[i].visib_fract) << "pipe " << i;
    }
  }
  EXPECT_GE(reaching_out, 1);
}

// No pipe passes into another: no surface sample of one lies inside another by more than a
// height-map cell.
TEST(Simulator, PipesDoNotInterpenetrateAndLieAtVariedTilts) {
  const PipeModel model = coarse_model("sbend");
  std::mt19937 rng(5);
  PileParams pile;
  pile.pipes = 14;
  const std::vector<Pose> poses = build_pile(model, pile, rng);
  ASSERT_EQ(int(poses.size()), pile.pipes);
  const float r = model.tube_diameter_mm / 2;
  double deepest = 0;
  for (std::size_t b = 0; b < poses.size(); ++b) {
    std::vector<Eigen::Vector3f> pts, nrm;
    for (std::size_t k = 0; k < model.surface.points.size(); ++k) {
      pts.push_back((poses[b].cast<float>() * model.surface.points[k]));
      nrm.push_back(poses[b].linear().cast<float>() * model.surface.normals[k]);
    }
    KdTree3 tree;
    tree.build(pts.data(), pts.size());
    for (std::size_t a = 0; a < poses.size(); ++a) {
      if (a == b) continue;
      for (std::size_t k = 0; k < model.surface.points.size(); k += 4) {
        const Eigen::Vector3f q = poses[a].cast<float>() * model.surface.points[k];
        int idx;
        float d2;
        tree.nearest(q, &idx, &d2);
        if (d2 > r * r) continue;
        const double depth = -(q - pts[idx]).dot(nrm[idx]);  // > 0: inside pipe b
        deepest = std::max(deepest, depth);
      }
    }
  }
  EXPECT_LT(deepest, 2.0 * pile.cell_mm);
  // The pile is not flat: some pipes rest tilted on others.
  const Eigen::Matrix3d flat = poses[0].linear();
  int tilted = 0;
  for (const auto& p : poses) {
    const Eigen::Vector3d up_in_model = p.linear().transpose() * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d first_up = flat.transpose() * Eigen::Vector3d::UnitZ();
    tilted += std::acos(std::clamp(std::abs(up_in_model.dot(first_up)), 0.0, 1.0)) > 5 * M_PI / 180;
  }
  EXPECT_GE(tilted, 2);
}

TEST(Simulator, BinGrowsWithThePipeSoThatAPileOf50Fits) {
  // The paper's pipes in 20s keep today's bin (the simulated data stays as it was).
  for (const char* preset : {"sbend", "u", "torus"}) {
    PileParams pile;
    const BinSpec bin = bin_for_pile(coarse_model(preset), pile);
    EXPECT_EQ(bin.inner_x_mm, pile.bin.inner_x_mm) << preset;
    EXPECT_EQ(bin.inner_y_mm, pile.bin.inner_y_mm) << preset;
  }
  // A long U of a 30 mm tube: 50 of them fill a larger bin.
  PipeSpec spec;
  spec.diameter_mm = 30;
  spec.sides = 12;
  spec.bend_step_deg = 15;
  spec.segments = parse_centreline("S300,B180r60,S200");
  const PipeModel model = derive_pipe_model(make_pipe(spec), "long-u");
  PileParams pile;
  pile.pipes = 50;
  pile.bin = bin_for_pile(model, pile);
  EXPECT_GT(pile.bin.inner_y_mm, 2 * model.extent_mm);
  EXPECT_NEAR(pile.bin.inner_x_mm / pile.bin.inner_y_mm, 640.0 / 480.0, 0.01);
  std::mt19937 rng(7);
  EXPECT_EQ(int(build_pile(model, pile, rng).size()), 50);
}

// Where a cell's sensor would be mounted for a bin: every camera drawn from the raised heights
// (any tilt up to the most, any azimuth and offset) sees the four inner corners of the rim, and
// so does its projector.
TEST(Simulator, ACameraRaisedToSeeTheBinSeesItsWholeRim) {
  SceneParams params;
  // The paper's bin from the default heights is seen whole already: nothing to raise.
  EXPECT_EQ(lowest_camera_seeing_bin(params), params.camera_height_min_mm);
  // A bin grown for 50 long U's, a camera drawn 0.5-0.6 m up, tilted up to 20 degrees: raised.
  PipeSpec spec;
  spec.diameter_mm = 30;
  spec.sides = 12;
  spec.bend_step_deg = 15;
  spec.segments = parse_centreline("S300,B180r60,S200");
  params.pile.pipes = 50;
  params.pile.bin = bin_for_pile(derive_pipe_model(make_pipe(spec), "long-u"), params.pile);
  params.camera_height_min_mm = 500, params.camera_height_max_mm = 600, params.max_tilt_deg = 20;
  const double lowest = lowest_camera_seeing_bin(params);
  EXPECT_GT(lowest, 1000);
  params.camera_height_max_mm += lowest - params.camera_height_min_mm;
  params.camera_height_min_mm = lowest;
  std::mt19937 rng(3);
  const Intrinsics& k = params.intrinsics;
  const BinSpec& bin = params.pile.bin;
  for (int i = 0; i < 500; ++i) {
    const Pose world_to_cam = draw_camera(params, rng);
    for (double sx : {-0.5, 0.5})
      for (double sy : {-0.5, 0.5})
        for (double beside : {0.0, params.sensor.baseline_mm}) {  // the camera, the projector
          const Eigen::Vector3d corner(sx * bin.inner_x_mm, sy * bin.inner_y_mm, bin.wall_height_mm);
          const Eigen::Vector2d px = k.project(world_to_cam * corner - Eigen::Vector3d(beside, 0, 0));
          EXPECT_TRUE(px.x() >= 0 && px.y() >= 0 && px.x() <= k.width - 1 && px.y() <= k.height - 1)
              << "camera " << i << " misses the rim corner (" << sx << ", " << sy << "): " << px.transpose();
        }
  }
  // ... and 50 mm lower, a camera at the least height sees the rim no more at some tilt.
  params.camera_height_min_mm = params.camera_height_max_mm = lowest - 50;
  EXPECT_GT(lowest_camera_seeing_bin(params), params.camera_height_min_mm);
}

}  // namespace
}  // namespace pipeloc
