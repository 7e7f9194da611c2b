// A depth sensor's stray readings left out before the localizer reads the frame.
#include <gtest/gtest.h>

#include <cstdlib>
#include <random>
#include <vector>

#include "locate/locator.hpp"
#include "locate/speckles.hpp"
#include "locate_fixtures.hpp"

namespace pipeloc {
namespace {

TEST(Speckles, ReadingsBeyondEveryNeighbourGoEdgesAndBlendsStay) {
  // A noisy tilted plane with a pipe's side across it (an 80 mm depth edge), readings blending
  // the two sides on the edge, dropouts, and stray readings nearer and farther than all around.
  Image<float> depth(200, 150, 0.0f);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 2.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int j = 0; j < depth.height; ++j)
    for (int i = 0; i < depth.width; ++i) {
      if (u(rng) < 0.05) continue;
      const double side = i >= 100 ? -80.0 : 0.0;
      depth.at(i, j) = float(900 + 0.3 * i - 0.2 * j + side + noise(rng));
    }
  for (int j = 0; j < depth.height; j += 3) depth.at(100, j) = depth.at(99, j) - 40;  // blends
  const int strays[][2] = {{20, 20}, {50, 70}, {150, 30}, {180, 120}, {0, 0}, {199, 149}};
  for (int k = 0; k < 6; ++k) depth.at(strays[k][0], strays[k][1]) = k % 2 ? 2500.f : 350.f;
  // A reading alone among dropouts says nothing against itself: it stays.
  for (int j = 60; j < 65; ++j)
    for (int i = 30; i < 35; ++i) depth.at(i, j) = 0;
  depth.at(32, 62) = 400;

  Image<float> kept;
  const int removed = remove_speckles(depth, 8.0f, &kept);
  EXPECT_EQ(removed, 6);
  for (const auto& s : strays) EXPECT_EQ(kept.at(s[0], s[1]), 0.0f) << s[0] << "," << s[1];
  EXPECT_EQ(kept.at(32, 62), 400.0f);
  int changed = 0;
  for (std::size_t k = 0; k < depth.pixels.size(); ++k) changed += kept.pixels[k] != depth.pixels[k];
  EXPECT_EQ(changed, 6);
}

TEST(Locator, StrayReadingsOnAPipeAreLeftOutAndThePipeIsPicked) {
  // A stray reading stands in the Z-buffer hundreds of millimetres above the cells around it; in
  // an upward core (on the zoo: a lone 38 mm pipe in a stereo frame) the core's measured length
  // is then the stray's height, and the pipe's core is dropped as longer than the pipe. This
  // preset's cores do not take the strays in: the test checks that the locator leaves them out
  // of what it reads, and that nothing of the pipe goes with them.
  int picked = 0;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    OnePipe p = one_pipe("sbend", seed);
    // On the pipe (label 0 of the clean render): every 50th of its readings, none within 2 pixels
    // of another (two strays side by side support each other: one lies between the other and the
    // pipe).
    Image<float>& depth = p.scene.depth_mm;
    const Image<int>& label = p.scene.clean.label;
    const int w = depth.width;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> share(0.3, 0.8);
    std::vector<std::size_t> strays;
    int on_pipe = 0;
    const auto apart = [&](std::size_t k) {
      for (const std::size_t o : strays)
        if (std::abs(int(k % w) - int(o % w)) <= kSpeckleReachPx &&
            std::abs(int(k / w) - int(o / w)) <= kSpeckleReachPx)
          return false;
      return true;
    };
    for (std::size_t k = 0; k < depth.pixels.size(); ++k)
      if (float& z = depth.pixels[k]; z > 0 && label.pixels[k] == 0 && on_pipe++ % 50 == 0 && apart(k))
        z = float(share(rng) * z), strays.push_back(k);
    Locator loc(preset_model("sbend"), p.cfg, p.scene.camera.intrinsics);
    const LocateOutput& out = loc.locate(p.scene.depth_mm, p.scene.camera);
    // Every stray is among what the locator left out (with the step it used).
    Image<float> kept;
    remove_speckles(depth, float(loc.config().continuity_step_max_mm), &kept);
    int left_in = 0;
    for (const std::size_t k : strays) left_in += kept.pixels[k] > 0;
    EXPECT_EQ(left_in, 0) << "seed " << seed << ", of " << strays.size() << " strays";
    EXPECT_GE(out.speckles, int(strays.size())) << "seed " << seed;
    ASSERT_GE(out.pick(), 0) << "seed " << seed;
    const double err = nearest_pipe_error(preset_model("sbend"),
                                          out.estimates[std::size_t(out.pick())].model_to_cam, p.scene);
    std::printf("seed %u (%d readings left out): pick %.1f mm from the pipe\n", seed, out.speckles, err);
    EXPECT_LT(err, 5.0) << "seed " << seed;
    ++picked;
  }
  EXPECT_EQ(picked, 3);
}

}  // namespace
}  // namespace pipeloc
