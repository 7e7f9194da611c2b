// II-A and II-B on the locator: the banded Z-buffer and the candidate regions.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "locate/locator.hpp"
#include "locate_fixtures.hpp"

namespace pipeloc {
namespace {

// The locator builds its Z-buffer and fills its holes in row bands on its threads; one band on
// one thread must give the same buffer, cell for cell.
TEST(ZBufferBuild, RowBandsOnThreadsGiveTheSameBufferAsOneBand) {
  const PipeModel& model = preset_model("sbend");
  const SimulatedScene s = pile_of(model, 12, 5);
  LocateConfig cfg;
  cfg.threads = 2;
  cfg.remove_speckles = false;  // both buffers of the frame as it is
  Locator loc(model, cfg, s.camera.intrinsics);
  loc.locate(s.depth_mm, s.camera);
  ZBuffer one;
  reserve_zbuffer(&one, cfg.zbuffer_max_side_mm, cfg.zbuffer_pixel_mm);
  ZBufferPoints pts;
  reserve_zbuffer_points(&pts, s.depth_mm.width, s.depth_mm.height, 1);
  HoleList holes;
  holes.reserve(one);
  EXPECT_GT(build_zbuffer(s.depth_mm, s.camera.intrinsics, bin_to_camera(s.camera), &pts, &one), 0);
  const LocateConfig& used = loc.config();  // the derived thresholds in effect for that frame
  const int passes = int(std::lround(used.hole_fill_mm / 2 / used.zbuffer_pixel_mm));
  ASSERT_GT(passes, 0);
  fill_small_holes(&one, passes, float(used.continuity_step_max_mm), &holes);
  const ZBuffer& banded = loc.zbuffer();
  ASSERT_EQ(one.width, banded.width);
  ASSERT_EQ(one.height, banded.height);
  EXPECT_EQ(one.origin_x_mm, banded.origin_x_mm);
  EXPECT_EQ(one.origin_y_mm, banded.origin_y_mm);
  int valid = 0, differ = 0;
  for (int j = 0; j < one.height; ++j)
    for (int i = 0; i < one.width; ++i) {
      const float a = one.z.at(i, j), b = banded.z.at(i, j);
      valid += !std::isnan(a);
      differ += std::isnan(a) != std::isnan(b) || (!std::isnan(a) && a != b);
    }
  EXPECT_GT(valid, one.width * one.height / 2);
  EXPECT_EQ(differ, 0);
}

// For each pipe of the scene, how many of the given Z-buffer cells lie within tol_mm of its surface.
std::vector<int> pipe_votes(const Locator& loc, const SimulatedScene& s, const int* cells, int n,
                            float tol_mm) {
  std::vector<int> votes(s.model_to_world.size(), 0);
  const ZBuffer& zb = loc.zbuffer();
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d pt = zb.point(cells[k] % zb.z.width, cells[k] / zb.z.width).cast<double>();
    for (std::size_t g = 0; g < votes.size(); ++g) {
      const Eigen::Vector3f q = (s.model_to_world[g].inverse() * pt).cast<float>();
      const LocatorModel::Sample* smp = loc.locator_model().nearest_sample(q);
      votes[g] += smp && (smp->p - q).norm() < tol_mm;
    }
  }
  return votes;
}

// The pipe most of the cells voted for.
std::size_t most_voted(const std::vector<int>& votes) {
  return std::size_t(std::max_element(votes.begin(), votes.end()) - votes.begin());
}

// How many candidate regions the localizer with cfg grows on each pipe of the scene (each region
// attributed to the pipe most of its cells lie on).
std::vector<int> regions_per_pipe(const PipeModel& model, const LocateConfig& cfg, const SimulatedScene& s) {
  Locator loc(model, cfg, s.camera.intrinsics);
  loc.locate(s.depth_mm, s.camera);
  const auto& rb = loc.regions();
  std::vector<int> per_pipe(s.model_to_world.size(), 0);
  for (const auto& cand : rb.candidates) {
    const std::vector<int> votes = pipe_votes(loc, s, &rb.region_cells[std::size_t(cand.cells_begin)],
                                              cand.cells_end - cand.cells_begin, 3.0f);
    ++per_pipe[most_voted(votes)];
  }
  return per_pipe;
}

// Piles of 25 thin short elbows (8.4 mm tube, 25 mm long, as 04-elbow of the zoo), seen by the
// active-stereo sensor from 0.63-0.73 m: plane fits over 3 pixel footprints of noise turn its
// normals by up to about 0.4 rad, so the cells beside a core tilt away from it by a small majority
// only. Kept where a majority tilts away (convexity_min_share 0.5), more of the top pipes get a
// candidate region than where 0.6 had to. Measured: 68 of 68 top pipes, 65 with 0.6.
TEST(Segmentation, AThinElbowsNoisyTopIsConvex) {
  const PipeModel model = thin_elbow();
  LocateConfig strict;
  strict.convexity_min_share = 0.6;  // the bound before
  const LocateConfig cfg;
  int tops = 0, with_strict = 0, with_default = 0, lost = 0;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const SimulatedScene s = thin_elbow_pile(model, seed);
    const std::vector<int> a = regions_per_pipe(model, strict, s), b = regions_per_pipe(model, cfg, s);
    for (std::size_t g = 0; g < a.size(); ++g) {
      if (!s.info[g].top) continue;
      ++tops, with_strict += a[g] > 0, with_default += b[g] > 0, lost += a[g] > 0 && b[g] == 0;
    }
  }
  std::printf("thin elbows: %d top pipes, with a candidate %d (0.6) / %d (default), lost %d\n", tops,
              with_strict, with_default, lost);
  EXPECT_GT(with_default, with_strict);
  EXPECT_EQ(lost, 0);
}

TEST(Segmentation, CandidateCoresLieOnTopPipes) {
  const PipeModel& model = preset_model("u");
  const SimulatedScene s = pile_of(model, 12, 21);
  LocateConfig cfg;
  Locator loc(model, cfg, s.camera.intrinsics);
  const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
  const auto& rb = loc.regions();
  // The cores tried again last (retry_claimed_cores) are a second chance, not the ranking's choice.
  const std::size_t ranked = rb.candidates.size() - std::size_t(out.regions.retried_claimed);
  ASSERT_GE(ranked, 1u);
  // Each core cell is attributed to the pipe whose surface it lies on; a candidate's core must be
  // mostly one pipe, and the candidates tried first pipes little covered by others.
  // (A core straddling two pipes that touch along their tops, where the valley split does not
  // separate them, happens: at most one candidate in ten. A covered pipe's region is a candidate
  // too, judged by the verification, but ranked after the open ones: at least 70 % of the first
  // half lie on top. Measured: 6 of the first 7 of 13; 9 of all 13, 8 of 11 when 0.6 of a core's
  // ring had to tilt away.)
  const std::size_t first_half = (ranked + 1) / 2;
  int on_top = 0, mixed = 0;
  for (std::size_t c = 0; c < ranked; ++c) {
    const auto& cand = rb.candidates[c];
    const std::vector<int> votes = pipe_votes(loc, s, &rb.core_cells[std::size_t(cand.core_begin)],
                                              cand.core_end - cand.core_begin, 3.0f);
    const std::size_t best = most_voted(votes);
    const int core = cand.core_end - cand.core_begin;
    mixed += votes[best] <= core * 7 / 10;
    on_top += c < first_half && s.info[best].occ_by_pipes <= 0.15;
  }
  EXPECT_LE(mixed, std::max(1, int(ranked) / 10));
  EXPECT_GE(on_top * 10, int(first_half) * 7);
}

// Beyond the paper: candidates are tried by core area times the share of the core not under
// another pipe (50 coils of the zoo: ranked by area alone, 42 of 144 candidates tried lay on top).
// A strip 6 cells wide at 20 mm with a strip across it at 40 mm: the cells of the lower strip
// within a diameter (10 mm) of the upper one, 12 of its 94 columns, lie under it; none of the
// upper one's do, nor any of a strip across only 4 mm higher (less than D/2).
TEST(Segmentation, ACoreBesideAPipeLyingAcrossItIsUnderIt) {
  for (const float across_z : {40.0f, 24.0f}) {
    const ZBuffer zb = synthetic_zbuffer(100, [&](double x, double y) {
      return x >= 40 && x <= 45 ? across_z : y >= 27 && y <= 32 ? 20.0f : 0.0f;
    });
    std::vector<int> lower, upper;
    for (int j = 0; j < zb.height; ++j)
      for (int i = 0; i < zb.width; ++i) {
        if (i >= 40 && i <= 45)
          upper.push_back(zb.index(i, j));
        else if (j >= 27 && j <= 32)
          lower.push_back(zb.index(i, j));
      }
    ASSERT_EQ(lower.size(), 94u * 6u);
    const float expected = across_z > 20 + 5 ? 12.0f * 6.0f / float(lower.size()) : 0.0f;
    EXPECT_NEAR(share_under_others(zb, lower.data(), int(lower.size()), 10.0f), expected, 0.02f) << across_z;
    EXPECT_EQ(share_under_others(zb, upper.data(), int(upper.size()), 10.0f), 0.0f) << across_z;
  }
}

// A pipe whose top strip falls into several cores grows several regions; one lying mostly in an
// earlier candidate's region is not tried again. Over simulated piles, each candidate region is
// attributed to the pipe most of its cells lie on: the rule must leave fewer pipes tried twice and
// every pipe tried that was tried without it.
TEST(Segmentation, APipeBrokenIntoPiecesIsTriedOnce) {
  const PipeModel& model = preset_model("sbend");
  LocateConfig loose;
  loose.region_max_claimed_share = 1;  // every region grown is a candidate
  const LocateConfig cfg;
  int repeats_loose = 0, repeats = 0, pipes_loose = 0, pipes = 0, lost = 0;
  for (unsigned seed = 40; seed < 44; ++seed) {
    const SimulatedScene s = pile_of(model, 14, seed);
    const std::vector<int> a = regions_per_pipe(model, loose, s), b = regions_per_pipe(model, cfg, s);
    for (std::size_t g = 0; g < a.size(); ++g) {
      repeats_loose += std::max(0, a[g] - 1), repeats += std::max(0, b[g] - 1);
      pipes_loose += a[g] > 0, pipes += b[g] > 0, lost += a[g] > 0 && b[g] == 0;
    }
  }
  std::printf("pipes tried %d / %d, extra tries of a pipe %d / %d (every region / the rule), lost %d\n",
              pipes_loose, pipes, repeats_loose, repeats, lost);
  EXPECT_GT(repeats_loose, 0) << "the piles should hold pipes whose strip falls into pieces";
  EXPECT_LT(repeats, repeats_loose);
  EXPECT_EQ(lost, 0);
}

// Beyond the paper: two straight pipes lying side by side on the floor, touching, one half a
// length along the other, seen through the sensor model. Plane fits straddling the V between them
// give upward normals, so the paper's cores join the two tops into one core too long to be a pipe,
// and neither is tried. Split along the valley, each pipe gets a core of its own in some frames
// (the valley is not always found whole; where it is not, the core is kept whole), and no piece
// of the floor becomes a candidate.
TEST(Segmentation, TouchingPipesSideBySideGetACoreEach) {
  const PipeModel model = pipe_of("S200", 20, "straight");
  const double r = 10;
  const auto lying_at = [&](double x, double y) { return lying_straight(model, 0, x, y, r + 0.5); };
  // Over several frames (camera placement and sensor noise drawn anew): in how many does each of
  // the two pipes get a candidate whose core lies mostly on it.
  LocateConfig paper;
  paper.core_valley_turn = 0;  // the paper's cores
  const LocateConfig cfg;
  constexpr int kFrames = 8;
  int both_paper = 0, both_split = 0, off_pipe = 0;
  for (int frame = 0; frame < kFrames; ++frame) {
    std::mt19937 rng(unsigned(100 + frame));
    SceneParams params;
    const SimulatedScene s =
        render_scene(model, {lying_at(-50, -r - 0.1), lying_at(50, r + 0.1)}, params, rng);
    const auto pipes_with_a_core = [&](const LocateConfig& c) {
      Locator loc(model, c, s.camera.intrinsics);
      loc.locate(s.depth_mm, s.camera);
      const auto& rb = loc.regions();
      bool on[2] = {false, false};
      for (const auto& cand : rb.candidates) {
        const int cells = cand.core_end - cand.core_begin;
        if (cells == 0) continue;  // a leftover region: no core of its own
        const std::vector<int> votes =
            pipe_votes(loc, s, &rb.core_cells[std::size_t(cand.core_begin)], cells, 3.0f);
        const std::size_t best = most_voted(votes);
        if (votes[best] > cells * 7 / 10)
          on[best] = true;
        else if (votes[0] + votes[1] <= cells * 7 / 10)  // (a core kept whole lies on both)
          ++off_pipe;
      }
      return int(on[0]) + int(on[1]);
    };
    both_paper += pipes_with_a_core(paper) == 2;
    both_split += pipes_with_a_core(cfg) == 2;
  }
  std::printf("frames with a core on each pipe: paper %d of %d, split %d of %d\n", both_paper, kFrames,
              both_split, kFrames);
  // Measured: the paper 0 of 8, split 4 of 8.
  EXPECT_LE(both_paper, kFrames / 4) << "the two tops should mostly join into a core too long";
  EXPECT_GE(both_split, both_paper + kFrames / 4);
  EXPECT_EQ(off_pipe, 0) << "a candidate core not on a pipe (the floor split into pieces)";
}

// Beyond the paper: two short tubes (16.7 mm, 69 mm long, as 09-S-sym of the zoo) side by side,
// touching, one resting 1.4 radii higher (on something beneath). Their cores stay apart, but the
// region grown from the higher one reaches down over the lower one's core, which the paper then
// never tries (3 of 20 cores in a 09-S-sym image). Tried again after all the others
// (retry_claimed_cores), the lower pipe gets a candidate of its own in some frames (most such
// regions are too flat on the side of the higher pipe to pass as convex).
TEST(Segmentation, ACoreUnderANeighboursRegionIsTriedLast) {
  const PipeModel model = pipe_of("S69", 16.7, "short");
  const double r = 16.7 / 2;
  LocateConfig once;
  once.retry_claimed_cores = false;
  const LocateConfig cfg;
  constexpr int kFrames = 8;
  int both_once = 0, both = 0, claimed = 0, retried = 0;
  for (int frame = 0; frame < kFrames; ++frame) {
    std::mt19937 rng(unsigned(200 + frame));
    SceneParams params;
    const SimulatedScene s = render_scene(
        model, {lying_straight(model, 0, 0, -r - 0.1, 2.4 * r + 0.5), lying_straight(model, 0, 0, r + 0.1, r + 0.5)},
        params, rng);
    const auto pipes_with_a_core = [&](const LocateConfig& c) {
      Locator loc(model, c, s.camera.intrinsics);
      const RegionStats& stats = loc.locate(s.depth_mm, s.camera).regions;
      claimed += stats.claimed, retried += stats.retried_claimed;
      const auto& rb = loc.regions();
      bool on[2] = {false, false};
      for (const auto& cand : rb.candidates) {
        const int core = cand.core_end - cand.core_begin;
        const std::vector<int> votes =
            pipe_votes(loc, s, &rb.core_cells[std::size_t(cand.core_begin)], core, 3.0f);
        const std::size_t best = most_voted(votes);
        on[best] = on[best] || votes[best] > core * 7 / 10;
      }
      return int(on[0]) + int(on[1]);
    };
    both_once += pipes_with_a_core(once) == 2;
    both += pipes_with_a_core(cfg) == 2;
  }
  std::printf("frames with a candidate core on each pipe: once %d of %d, tried again %d (cores claimed %d, "
              "tried again as candidates %d)\n",
              both_once, kFrames, both, claimed, retried);
  EXPECT_GT(claimed, 0) << "the higher pipe's region should reach over the other's core";
  EXPECT_GT(both, both_once);
}

// Beyond the paper: two short tubes (16.7 mm, 69 mm long, as 09-S-sym of the zoo) lying end to
// end on the floor, touching. Their tops make one top strip with no valley between them: one core
// too long for a pipe that does not split. The paper drops it and neither pipe is tried; kept
// whole (core_whole_max_extent_of_l), it is a candidate, and the ridge fit takes a pipe out of it.
TEST(Segmentation, PipesEndToEndGetACandidateFromACoreKeptWhole) {
  const PipeModel model = pipe_of("S69", 16.7, "short");
  const double r = 16.7 / 2, half = 69.0 / 2;
  LocateConfig dropped;
  dropped.core_whole_max_extent_of_l = 0;
  const LocateConfig cfg;
  // Candidates whose core lies on the two pipes (most of its cells on one or the other).
  const auto on_pipes = [&](const SimulatedScene& s, const LocateConfig& c, int* whole) {
    Locator loc(model, c, s.camera.intrinsics);
    *whole += loc.locate(s.depth_mm, s.camera).regions.whole_long_cores;
    const auto& rb = loc.regions();
    int n = 0;
    for (const auto& cand : rb.candidates) {
      const int cells = cand.core_end - cand.core_begin;
      const std::vector<int> votes =
          pipe_votes(loc, s, &rb.core_cells[std::size_t(cand.core_begin)], cells, 3.0f);
      n += votes[0] + votes[1] > cells * 7 / 10;
    }
    return n;
  };
  int dropped_candidates = 0, whole_candidates = 0, whole_dropped = 0, whole = 0;
  constexpr int kFrames = 4;
  const std::vector<Pose> end_to_end = {lying_straight(model, 0, -half - 0.1, 0, r + 0.5),
                                        lying_straight(model, 0, half + 0.1, 0, r + 0.5)};
  for (int frame = 0; frame < kFrames; ++frame) {
    const SimulatedScene s = scene_of(model, end_to_end, unsigned(700 + frame));
    dropped_candidates += on_pipes(s, dropped, &whole_dropped);
    whole_candidates += on_pipes(s, cfg, &whole);
  }
  std::printf(
      "candidates on pipes end to end: core dropped %d, kept whole %d in %d frames (cores kept whole %d)\n",
      dropped_candidates, whole_candidates, kFrames, whole);
  EXPECT_EQ(whole_dropped, 0);
  EXPECT_EQ(dropped_candidates, 0) << "the two tops should make one core too long, not split";
  EXPECT_GE(whole_candidates, kFrames);
}

// Beyond the paper: the region of a core kept whole holds both pipes lying end to end, and its
// fit takes one. What that pose leaves of the region unexplained is a candidate of its own, and
// the second pipe is found too; with leftover_regions off, one of them is.
TEST(Segmentation, TheSecondOfTwoPipesEndToEndIsFoundInWhatTheFirstLeft) {
  const PipeModel model = pipe_of("S69", 16.7, "short");
  const double r = 16.7 / 2, half = 69.0 / 2;
  LocateConfig paper_regions;
  paper_regions.leftover_regions = false;
  const LocateConfig cfg;
  const std::vector<Pose> end_to_end = {lying_straight(model, 0, -half - 0.1, 0, r + 0.5),
                                        lying_straight(model, 0, half + 0.1, 0, r + 0.5)};
  // How many of the two pipes an estimate lies on (nearer it than the other, less than L/2 off:
  // two straight tubes touching end to end do not show where one ends, and their poses slide a
  // little); how many leftover candidates.
  const auto found = [&](const SimulatedScene& s, const LocateConfig& c, int* leftover) {
    Locator loc(model, c, s.camera.intrinsics);
    const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
    *leftover += out.regions.leftover;
    bool on[2] = {false, false};
    for (const PipeEstimate& e : out.estimates) {
      const double err[2] = {pose_error_with_turns(model, e.model_to_cam, s.model_to_cam(0)),
                             pose_error_with_turns(model, e.model_to_cam, s.model_to_cam(1))};
      const int g = err[0] < err[1] ? 0 : 1;
      on[g] = on[g] || err[g] < half;
    }
    return int(on[0]) + int(on[1]);
  };
  int with = 0, without = 0, leftover = 0, leftover_off = 0;
  constexpr int kFrames = 4;
  for (int frame = 0; frame < kFrames; ++frame) {
    const SimulatedScene s = scene_of(model, end_to_end, unsigned(700 + frame));
    with += found(s, cfg, &leftover);
    without += found(s, paper_regions, &leftover_off);
  }
  std::printf("pipes end to end found: %d with leftover regions (%d of them), %d without, of %d\n", with,
              leftover, without, 2 * kFrames);
  EXPECT_EQ(leftover_off, 0);
  EXPECT_GE(leftover, kFrames - 1);
  EXPECT_EQ(with, 2 * kFrames);
  EXPECT_LE(without, kFrames);
}

// Beyond the paper: a pipe lying across another cuts the lower one's top strip in two, each
// piece too short for 0.7 L; a dropout across the ridge does the same. The piece continuing a
// region across the gap (same direction, same height, nothing lower between) is joined to it,
// and the pipe is found; without the join it is not a candidate.
TEST(Segmentation, APipeCutAcrossItsRidgeIsJoinedAndFound) {
  const PipeModel model = pipe_of("S400", 20, "straight");
  const double r = 10;
  LocateConfig unjoined;
  unjoined.region_join_gap_of_d = 0;
  const LocateConfig cfg;
  // The lower pipe's region: a candidate with most of its cells on pipe 0, longer than 0.7 L.
  const auto lower_found = [&](const SimulatedScene& s, const LocateConfig& c) {
    Locator loc(model, c, s.camera.intrinsics);
    const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
    for (const PipeEstimate& e : out.estimates)
      if (pose_error_with_turns(model, e.model_to_cam, s.model_to_cam(0)) < 5) return true;
    return false;
  };
  int crossed = 0, crossed_unjoined = 0, holed = 0, holed_unjoined = 0;
  constexpr int kFrames = 3;
  for (int frame = 0; frame < kFrames; ++frame) {
    std::mt19937 rng(unsigned(300 + frame));
    SceneParams params;
    // Pipe 1 lies across the middle of pipe 0, at 60 degrees, on top of it.
    const SimulatedScene across = render_scene(
        model, {lying_straight(model, 0, 0, 0, r + 0.5), lying_straight(model, 60, 0, 0, 3 * r + 1)}, params,
        rng);
    crossed += lower_found(across, cfg);
    crossed_unjoined += lower_found(across, unjoined);
    // Pipe 0 alone, no reading over 2 D across its middle (a glint, a dropout).
    std::mt19937 rng2(unsigned(400 + frame));
    SimulatedScene alone = render_scene(model, {lying_straight(model, 0, 0, 0, r + 0.5)}, params, rng2);
    const Eigen::Vector3d mid = alone.model_to_cam(0) * model.centroid.cast<double>();
    const double half_px = 2 * r * alone.camera.intrinsics.fx / mid.z();
    const double cx = alone.camera.intrinsics.project(mid).x();
    for (int y = 0; y < alone.depth_mm.height; ++y)
      for (int x = 0; x < alone.depth_mm.width; ++x)
        if (std::abs(x - cx) < half_px) alone.depth_mm.at(x, y) = 0;
    holed += lower_found(alone, cfg);
    holed_unjoined += lower_found(alone, unjoined);
  }
  std::printf("lower pipe found: crossed %d (unjoined %d), holed %d (unjoined %d) of %d\n", crossed,
              crossed_unjoined, holed, holed_unjoined, kFrames);
  // Measured: 3 and 3 of 3 joined; 0 and 0 without the join.
  EXPECT_EQ(crossed, kFrames);
  EXPECT_EQ(holed, kFrames);
  EXPECT_LE(crossed_unjoined, 1);
  EXPECT_LE(holed_unjoined, 1);
}

// Beyond the paper: a region shorter than a * L is not dropped but tried after the long ones,
// its fit and the verification judging it. An S-bend alone, no reading within D of its ridge a
// quarter along its centreline (a glint), the joins off: its longer piece falls short of 0.7 L,
// and the pipe is found only where short regions are tried.
TEST(Segmentation, ARegionTooShortIsTriedAfterTheLongOnes) {
  const PipeModel& model = preset_model("sbend");
  LocateConfig tried;
  tried.region_join_gap_of_d = 0;
  LocateConfig dropped = tried;
  dropped.short_region_min_extent_of_l = dropped.region_min_extent_of_l;  // the paper's cut
  int found_tried = 0, found_dropped = 0, short_candidates = 0;
  constexpr int kFrames = 4;
  for (int frame = 0; frame < kFrames; ++frame) {
    SimulatedScene s = pile_of(model, 1, unsigned(500 + frame));
    Locator probe(model, tried, s.camera.intrinsics);
    const auto& line = probe.locator_model().centreline_points;
    const Eigen::Vector3d at = s.model_to_cam(0) * line[(line.size() - 1) / 4].cast<double>();
    const double radius_px = probe.locator_model().tube_d_mm * s.camera.intrinsics.fx / at.z();
    const Eigen::Vector2d uv = s.camera.intrinsics.project(at);
    for (int y = 0; y < s.depth_mm.height; ++y)
      for (int x = 0; x < s.depth_mm.width; ++x)
        if ((Eigen::Vector2d(x, y) - uv).norm() < radius_px) s.depth_mm.at(x, y) = 0;
    const auto found = [&](const LocateConfig& c, int* shorts) {
      Locator loc(model, c, s.camera.intrinsics);
      const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
      if (shorts) *shorts += out.regions.short_candidates;
      for (const PipeEstimate& e : out.estimates)
        if (pose_error_with_turns(model, e.model_to_cam, s.model_to_cam(0)) < 5) return true;
      return false;
    };
    found_tried += found(tried, &short_candidates);
    found_dropped += found(dropped, nullptr);
  }
  std::printf("found: short regions tried %d (%d short candidates), dropped %d, of %d\n", found_tried,
              short_candidates, found_dropped, kFrames);
  // Measured: 3 of 4 tried (9 of 10 over frames 500-509), 0 dropped. Cut at 0.35 of the
  // centreline, the pieces are too short to place the S: 0 of 3 either way.
  EXPECT_GE(found_tried, kFrames - 1);
  EXPECT_GE(short_candidates, kFrames - 1);
  EXPECT_EQ(found_dropped, 0);
}

// Beyond the paper: growth held to about a diameter from the core keeps a region on its pipe; the
// paper's unlimited growth runs on over touching pipes, and such a region is dropped or mixed.
// Measured on piles: how many candidate regions, and the share of a region's cells that lie on the
// pipe most of them lie on.
double mean_region_purity(const PipeModel& model, const SimulatedScene& s, const LocateConfig& cfg,
                          int* regions) {
  Locator loc(model, cfg, s.camera.intrinsics);
  loc.locate(s.depth_mm, s.camera);
  const auto& rb = loc.regions();
  double sum = 0;
  for (const auto& cand : rb.candidates) {
    const std::vector<int> votes = pipe_votes(loc, s, &rb.region_cells[std::size_t(cand.cells_begin)],
                                              cand.cells_end - cand.cells_begin, 6.0f);
    sum += double(*std::max_element(votes.begin(), votes.end())) / double(cand.cells_end - cand.cells_begin);
  }
  *regions = int(rb.candidates.size());
  return rb.candidates.empty() ? 0 : sum / double(rb.candidates.size());
}

TEST(Segmentation, HeldGrowthKeepsRegionsOnTheirPipe) {
  const PipeModel& model = preset_model("sbend");
  LocateConfig held, unlimited;
  unlimited.region_max_reach_of_d = 100;
  // The regions as grown: no leftover of a region is tried again (it would take back a pipe from
  // a region grown over two).
  held.leftover_regions = unlimited.leftover_regions = false;
  double p_held = 0, p_unlimited = 0;
  int n_held = 0, n_unlimited = 0;
  for (const unsigned seed : {6u, 7u, 8u}) {
    const SimulatedScene s = pile_of(model, 20, seed);
    int h = 0, u = 0;
    p_held += mean_region_purity(model, s, held, &h) / 3;
    p_unlimited += mean_region_purity(model, s, unlimited, &u) / 3;
    n_held += h, n_unlimited += u;
  }
  // Measured: 25 regions of purity 0.80 held, against 20 of 0.77 unlimited (regions that spread
  // over touching pipes are dropped as leaks). Cells within 6 mm of a pipe's surface count as on
  // it; the rest are the sensor's noise, the floor and the pipe beneath.
  ASSERT_GE(n_held, 9);
  EXPECT_GT(p_held, 0.7);
  EXPECT_GE(p_held, p_unlimited);
  EXPECT_GT(n_held, n_unlimited);
}

// Beyond the paper: a thin tube on the floor whose top strip runs into the floor over upward
// cells (here a ramp at one end; in the zoo, noise turning normals on its sides upward) joins the
// floor's core, far too large to be a pipe. Its top stands clear above the plane that core lies
// in and is taken off it as a core of its own, which grows into a candidate (before: none).
// The candidate regions of a synthetic Z-buffer with `cfg` (the default config unless given;
// normals over a 5 mm window), for a pipe of diameter d and extent l.
RegionStats regions_of(const ZBuffer& zb, double d, double l, RegionBuffers* rb,
                       const LocateConfig& cfg = LocateConfig()) {
  NormalMap nm;
  reserve_normals(&nm, zb);
  compute_normals(zb, 5, 10, &nm);
  reserve_regions(rb, zb, cfg, float(d), float(l));
  mark_upward_rows(zb, nm, cfg, 0, zb.height, rb);
  return extract_candidate_regions(zb, nm, cfg, float(d), float(l), rb);
}

TEST(Segmentation, AThinTubeJoinedToTheFloorGetsACoreOfItsOwn) {
  constexpr double d = 8.7, r = d / 2, length = 180, axis_y = 150, x0 = 60, ramp = 20;
  const auto tube_top = [&](double y) {
    const double dy = y - axis_y;
    return std::abs(dy) <= r ? r + std::sqrt(r * r - dy * dy) : 0.0;
  };
  const ZBuffer zb = synthetic_zbuffer(300, [&](double x, double y) {
    if (x >= x0 && x <= x0 + length) return float(tube_top(y));
    if (x >= x0 - ramp && x < x0) return float(tube_top(y) * (x - (x0 - ramp)) / ramp);
    return 0.0f;
  });
  RegionBuffers rb;
  const RegionStats stats = regions_of(zb, d, length, &rb);
  EXPECT_EQ(stats.raised_cores, 1);
  ASSERT_EQ(stats.candidates, 1);
  const CandidateRegion& c = rb.candidates[0];
  EXPECT_NEAR(c.core_centroid.y(), axis_y, 1.0);
  EXPECT_GT(c.core_centroid.z(), 0.85 * d);
  EXPECT_GT(c.core_centroid.x(), x0);
  EXPECT_LT(c.core_centroid.x(), x0 + length);
}

// A pipe's top cut by holes into pieces a diameter long (glints, a sensor's dropouts): each
// piece's upward strip, 0.7 D wide, covers about 0.6 D^2. Under the default core area (0.75 D^2)
// no piece is a core and the pipe gets no candidate; with core_min_area_of_d2 = 0.5 the pieces
// are cores, joined across the holes into candidates on the pipe (the key's use where crossings
// and dropouts cut tops short; measured on the zoo, not made the default: docs/experiments.md).
TEST(Segmentation, ATopCutIntoPiecesADiameterLongIsFoundWithSmallerCores) {
  constexpr double d = 20, r = d / 2, length = 160, axis_y = 100, x0 = 30, piece = d, hole = 0.6 * d;
  const auto tube_top = [&](double y) {
    const double dy = y - axis_y;
    return std::abs(dy) <= r ? r + std::sqrt(r * r - dy * dy) : 0.0;
  };
  const ZBuffer zb = synthetic_zbuffer(220, [&](double x, double y) {
    if (x < x0 || x > x0 + length) return 0.0f;
    const bool in_hole = std::fmod(x - x0, piece + hole) >= piece;
    if (in_hole && std::abs(y - axis_y) <= r) return std::numeric_limits<float>::quiet_NaN();
    return float(tube_top(y));
  });
  const auto on_the_pipe = [&](const RegionBuffers& rb) {
    int n = 0;
    for (const CandidateRegion& c : rb.candidates)
      n += std::abs(c.core_centroid.y() - axis_y) < 2 && c.core_centroid.z() > 0.85 * d;
    return n;
  };
  RegionBuffers rb;
  const RegionStats stats = regions_of(zb, d, length, &rb);
  EXPECT_EQ(stats.cores_kept, 0);
  EXPECT_EQ(on_the_pipe(rb), 0);
  LocateConfig small_cores;
  small_cores.core_min_area_of_d2 = 0.5;
  RegionBuffers rb_small;
  const RegionStats small = regions_of(zb, d, length, &rb_small, small_cores);
  EXPECT_GE(small.joined, 1);
  EXPECT_GE(on_the_pipe(rb_small), 1);
}

// A thin half ring lying on the floor, where the floor reads 0.3 D higher than the tube's bottom
// (noise, blended rim pixels: 15-arc of the zoo, an 11.5 mm tube at 0.84 m): growth down to
// 0.8 D below the top runs onto the floor beside the tube, over more cells than three times
// L x D (a leak: no candidate). The region is grown again down to the tube's equator only, after
// the other cores, and stays on the tube.
TEST(Segmentation, AThinPipeWhoseRegionLeaksOntoTheFloorIsGrownToItsEquator) {
  constexpr double d = 11.5, r = d / 2, ring = 85, cx = 150, cy = 100, floor_z = 0.3 * d;
  const ZBuffer zb = synthetic_zbuffer(300, [&](double x, double y) {
    const double off = std::hypot(x - cx, y - cy) - ring;
    if (y >= cy && std::abs(off) <= r) return float(std::max(floor_z, r + std::sqrt(r * r - off * off)));
    return float(floor_z);
  });
  RegionBuffers rb;
  const RegionStats stats = regions_of(zb, d, 2 * ring + d, &rb);
  EXPECT_EQ(stats.leaked, 0);
  EXPECT_EQ(stats.regrown_after_leak, 1);
  ASSERT_EQ(stats.candidates, 1);
  const CandidateRegion& c = rb.candidates[0];
  int off_tube = 0;
  for (int k = c.cells_begin; k < c.cells_end; ++k)
    off_tube += zb.z.pixels[std::size_t(rb.region_cells[std::size_t(k)])] < r;
  EXPECT_EQ(off_tube, 0) << "of " << c.cells_end - c.cells_begin << " region cells";
}

// The growth's visit marks and the regions' claims count up frame by frame; a deployed cell runs
// for weeks, longer than an int counts. When the values run out the marks are cleared: the same
// frame gives the same candidates as with fresh buffers.
TEST(Segmentation, MarksThatRunOutAreClearedNotOverflowed) {
  constexpr double d = 20, r = d / 2, length = 200;
  const auto tube_top = [&](double y, double axis_y) {
    const double dy = y - axis_y;
    return std::abs(dy) <= r ? r + std::sqrt(r * r - dy * dy) : 0.0;
  };
  const ZBuffer zb = synthetic_zbuffer(300, [&](double x, double y) {
    if (x < 40 || x > 40 + length) return 0.0f;
    return float(std::max(tube_top(y, 80), tube_top(y, 200)));
  });
  const LocateConfig cfg;
  NormalMap nm;
  reserve_normals(&nm, zb);
  compute_normals(zb, 5, 10, &nm);
  const auto candidates = [&](int used) {
    RegionBuffers rb;
    reserve_regions(&rb, zb, cfg, float(d), float(length));
    rb.stamp_value = rb.claim_value = used;
    std::vector<std::vector<int>> out;
    for (int frame = 0; frame < 3; ++frame) {  // the counters run out within these three
      mark_upward_rows(zb, nm, cfg, 0, zb.height, &rb);
      extract_candidate_regions(zb, nm, cfg, float(d), float(length), &rb);
      for (const CandidateRegion& c : rb.candidates)
        out.emplace_back(&rb.region_cells[std::size_t(c.cells_begin)],
                         &rb.region_cells[std::size_t(c.cells_end)]);
    }
    return out;
  };
  const auto fresh = candidates(0);
  ASSERT_EQ(fresh.size(), 6u);  // both tubes, three times
  EXPECT_EQ(candidates(std::numeric_limits<int>::max() - 3), fresh);
}

}  // namespace
}  // namespace pipeloc
