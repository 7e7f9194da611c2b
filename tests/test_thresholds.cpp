// Thresholds derived from the model and from the noise measured in the frame.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "locate/candidate.hpp"
#include "locate/thresholds.hpp"

namespace pipeloc {
namespace {

// A tilted plane at about `depth_mm` with Gaussian noise, a step edge across it and holes.
Image<float> noisy_plane(double depth_mm, double sigma_mm, unsigned seed) {
  Image<float> img(320, 240, 0.0f);
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_mm);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int j = 0; j < img.height; ++j)
    for (int i = 0; i < img.width; ++i) {
      if (u(rng) < 0.05) continue;                        // dropouts
      const double edge = i > 200 ? -80.0 : 0.0;          // a pipe's side: a depth edge
      img.at(i, j) = float(depth_mm + 0.3 * i - 0.2 * j + edge + noise(rng));
    }
  return img;
}

TEST(DepthNoise, MeasuredFromTheFrameWhateverTheSlopeAndEdges) {
  NoiseHistograms h;
  for (const double sigma : {0.5, 1.0, 2.0, 3.0}) {
    const DepthNoise n = measure_depth_noise(noisy_plane(800, sigma, 7), &h);
    EXPECT_NEAR(n.sigma_mm, sigma, 0.1 * sigma + 0.05) << sigma;
    EXPECT_GT(n.depth_mm, 720) << sigma;  // between the plane's nearest and farthest parts
    EXPECT_LT(n.depth_mm, 900) << sigma;
    EXPECT_GT(n.samples, 10000);
  }
  // A frame with hardly any valid pixels: the fallback, not a guess from a handful.
  Image<float> empty(320, 240, 0.0f);
  empty.at(10, 10) = 900;
  const DepthNoise none = measure_depth_noise(empty, &h);
  EXPECT_EQ(none.samples, 0);
  EXPECT_GT(none.sigma_mm, 0);
}

TEST(Thresholds, FollowTheTubeAndTheNoiseUnlessGiven) {
  LocateConfig user;  // every derived key at 0 (the noise-dependent ones have fixed defaults)
  user.continuity_step_max_mm = user.verify_tolerance_mm = user.refine_inlier_mm = 0;
  user.hole_fill_mm = user.normal_window_mm = 0;
  Intrinsics k;
  const LocateConfig thin = with_model_thresholds(user, 10), thick = with_model_thresholds(user, 40);
  EXPECT_LT(thin.hole_fill_mm, thick.hole_fill_mm);
  EXPECT_NEAR(thick.hole_fill_mm / thin.hole_fill_mm, 4.0, 1e-6);
  LocateConfig quiet = thin, noisy = thin;
  set_frame_thresholds(user, 10, DepthNoise{0.5f, 600, 100000}, k, &quiet);
  set_frame_thresholds(user, 10, DepthNoise{2.5f, 1200, 100000}, k, &noisy);
  EXPECT_LT(quiet.continuity_step_max_mm, noisy.continuity_step_max_mm);
  EXPECT_LT(quiet.verify_tolerance_mm, noisy.verify_tolerance_mm);
  EXPECT_LT(quiet.refine_inlier_mm, noisy.refine_inlier_mm);
  // Far away a pixel covers more: the plane-fit window never shrinks under 2.5 footprints.
  EXPECT_GE(noisy.normal_window_mm, 2.5 * 1200 / k.fx - 1e-9);
  // The paper's tubes at 1 m with the Kinect-class noise (measured: 2.37 mm) keep the values they
  // were developed with.
  LocateConfig paper = with_model_thresholds(user, 18);
  set_frame_thresholds(user, 18, DepthNoise{2.37f, 1000, 100000}, k, &paper);
  EXPECT_NEAR(paper.continuity_step_max_mm, 8, 0.5);
  EXPECT_NEAR(paper.verify_tolerance_mm, 7, 0.5);
  EXPECT_NEAR(paper.refine_inlier_mm, 4, 0.5);
  EXPECT_NEAR(paper.normal_window_mm, 6.3, 0.1);
  // A thin tube: 0.35 D would be 3 cells, whose plane fits are mostly noise; the window grows to
  // what the noise needs (sqrt(8 sigma c)), and so with the noise.
  LocateConfig thin_quiet = with_model_thresholds(user, 8.7f), thin_noisy = thin_quiet;
  set_frame_thresholds(user, 8.7f, DepthNoise{0.3f, 745, 100000}, k, &thin_quiet);
  set_frame_thresholds(user, 8.7f, DepthNoise{1.75f, 745, 100000}, k, &thin_noisy);
  EXPECT_LT(thin_quiet.normal_window_mm, 3.5);  // 3 cells: the footprints bound it
  EXPECT_NEAR(thin_noisy.normal_window_mm, std::sqrt(8 * 1.75 * 745 / k.fx), 1e-3);
  EXPECT_GT(thin_noisy.normal_window_mm, 4.0);
  // A value given is used as given, unless raise_to_noise raises it to what the noise needs.
  LocateConfig pinned = user;
  pinned.verify_tolerance_mm = 5;
  pinned.hole_fill_mm = 3;
  LocateConfig raised = with_model_thresholds(pinned, 40);
  set_frame_thresholds(pinned, 40, DepthNoise{3.0f, 1000, 100000}, k, &raised);
  EXPECT_EQ(raised.verify_tolerance_mm, 9);  // 3 sigma
  EXPECT_EQ(raised.hole_fill_mm, 3);
  set_frame_thresholds(pinned, 40, DepthNoise{1.0f, 1000, 100000}, k, &raised);
  EXPECT_EQ(raised.verify_tolerance_mm, 5);
  pinned.raise_to_noise = false;
  LocateConfig in_effect = with_model_thresholds(pinned, 40);
  set_frame_thresholds(pinned, 40, DepthNoise{3.0f, 1000, 100000}, k, &in_effect);
  EXPECT_EQ(in_effect.verify_tolerance_mm, 5);
  EXPECT_EQ(in_effect.hole_fill_mm, 3);
  // The pick's check of the tube's relief (pick_min_relief_sigmas) reads the noise as measured,
  // beyond the cap of the thresholds' own, and has the frame's noise measured even where every
  // other key is given.
  set_frame_thresholds(pinned, 40, DepthNoise{6.0f, 1000, 100000}, k, &in_effect);
  EXPECT_EQ(in_effect.frame_noise_mm, 6.0);
  EXPECT_LT(in_effect.frame_sigma_mm, 6.0);
  LocateConfig given = pinned;
  given.continuity_step_max_mm = 8, given.refine_inlier_mm = 4, given.normal_window_mm = 7;
  EXPECT_TRUE(derives_from_frame(given));
  given.pick_min_relief_sigmas = 0;
  EXPECT_FALSE(derives_from_frame(given));
}

// R_th is 0.35 D unless the frame's noise needs more: a 12 mm tube under 4 mm of noise (an
// active-stereo sensor at 1.2 m) has right ridge fits 5-6.5 mm from its ridge.
TEST(Thresholds, RidgeResidualBoundFollowsTheNoiseOfThinTubes) {
  LocateConfig cfg;
  set_frame_thresholds(cfg, 12, DepthNoise{4.0f, 1150, 100000}, Intrinsics{}, &cfg);
  EXPECT_NEAR(residual_max_mm(cfg, 12), 1.8 * 4.0, 1e-5);
  set_frame_thresholds(cfg, 12, DepthNoise{1.0f, 600, 100000}, Intrinsics{}, &cfg);
  EXPECT_NEAR(residual_max_mm(cfg, 12), 0.35 * 12, 1e-5);
  LocateConfig fixed;
  fixed.raise_to_noise = false;
  set_frame_thresholds(fixed, 12, DepthNoise{4.0f, 1150, 100000}, Intrinsics{}, &fixed);
  EXPECT_NEAR(residual_max_mm(fixed, 12), 0.35 * 12, 1e-5);
}

}  // namespace
}  // namespace pipeloc
