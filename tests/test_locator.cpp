// The localizer end to end on simulated frames.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "locate/locator.hpp"
#include "locate_fixtures.hpp"
#include "service/sim_source.hpp"

namespace pipeloc {
namespace {

// Calls f(estimate, scene) for each pickable estimate the default localizer hands out on piles
// of `pipes` of the model (seeds 1..seeds); returns how many there were.
template <typename F>
int for_each_pickable(const PipeModel& model, int pipes, unsigned seeds, F f) {
  int pickable = 0;
  for (unsigned seed = 1; seed <= seeds; ++seed) {
    const SimulatedScene s = pile_of(model, pipes, seed);
    Locator loc(model, LocateConfig{}, s.camera.intrinsics);
    for (const PipeEstimate& e : loc.locate(s.depth_mm, s.camera).estimates) {
      if (!e.pickable) continue;
      ++pickable;
      f(e, s);
    }
  }
  return pickable;
}

TEST(Locator, EndToEndPickIsATopPipe) {
  const PipeModel& model = preset_model("sbend");
  const SimulatedScene s = pile_of(model, 10, 8);
  LocateConfig cfg;
  Locator loc(model, cfg, s.camera.intrinsics);
  const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
  const int pick = out.pick();
  ASSERT_GE(pick, 0);
  double best = 1e9;
  std::size_t g_best = 0;
  for (std::size_t g = 0; g < s.model_to_world.size(); ++g) {
    const double e = pose_error(model, out.estimates[std::size_t(pick)].model_to_cam, s.model_to_cam(g));
    if (e < best) best = e, g_best = g;
  }
  EXPECT_LT(best, 5.0);
  EXPECT_LE(s.info[g_best].occ_by_pipes, 0.15);
}

// The Locator works from its own copy of the config: the caller's may be a temporary, or change
// after construction. The ridge ICP read the caller's, so here it stopped after one iteration.
TEST(Locator, KeepsNoReferenceToTheCallersConfig) {
  const PipeModel& model = preset_model("sbend");
  const SimulatedScene s = pile_of(model, 10, 8);
  LocateConfig cfg;
  Locator kept(model, cfg, s.camera.intrinsics);
  LocateConfig changed = cfg;
  Locator loc(model, changed, s.camera.intrinsics);
  changed.icp_converged_mm = 1e9;
  const LocateOutput expected = kept.locate(s.depth_mm, s.camera);
  const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
  ASSERT_EQ(out.estimates.size(), expected.estimates.size());
  for (std::size_t i = 0; i < out.estimates.size(); ++i)
    EXPECT_TRUE(out.estimates[i].model_to_cam.isApprox(expected.estimates[i].model_to_cam, 1e-9));
}

// A near-symmetric pipe (a half-turn swaps its ends and lands its surface within D/4 of itself): where a
// pile shows only the common surface, the image cannot tell the pose from its twin. No pose handed out as
// pickable may be the twin of a pipe instead of the pipe (106 mm off at the ends): either the right one is
// taken or the estimate loses its confidence. Without the twin judged, 13 of 40 pickable poses on these 12
// piles were twins; with it, when first measured, 1 of 7 (a twin the image confirms better than the pipe's
// own pose, 0.92 against 0.75 agreement).
TEST(Locator, NoPickablePoseIsTheTwinOfANearSymmetricPipe) {
  const PipeModel model = pipe_of("S30,B120r45t90,B90r45t90,S30", 16, "coil");
  ASSERT_GE(model.near_symmetries.size(), 1u);
  int twins_picked = 0;
  const int pickable = for_each_pickable(model, 20, 12, [&](const PipeEstimate& e, const SimulatedScene& s) {
    double at_truth = 1e9, at_twin = 1e9;
    for (std::size_t g = 0; g < s.model_to_world.size(); ++g) {
      at_truth = std::min(at_truth, pose_error(model, e.model_to_cam, s.model_to_cam(g)));
      for (const Pose& twin : model.near_symmetries)
        at_twin = std::min(at_twin, pose_error(model, e.model_to_cam, s.model_to_cam(g) * twin));
    }
    twins_picked += at_truth > 10 && at_twin < 5;
  });
  EXPECT_GE(pickable, 1);
  EXPECT_LE(5 * twins_picked, pickable) << twins_picked << " of " << pickable << " pickable poses are twins";
}

// A straight tube's ridge is a line: a turn about it is the noise's, and rolled the tube off its
// own top (the ridge ICP ended more than D/2 from every ridge point in 6 of 11 regions of a pile
// of 12 short tubes). With that turn left out, the top tubes of piles are found. Six piles: on
// three (24 top tubes) one tube more or less moves the share by 4 %.
TEST(Locator, StraightTubesOnAPileAreFound) {
  const PipeModel model = pipe_of("S85", 22, "straight");
  LocateConfig cfg;
  int top = 0, found = 0;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    const SimulatedScene s = pile_of(model, 12, seed);
    Locator loc(model, cfg, s.camera.intrinsics);
    const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
    for (std::size_t g = 0; g < s.model_to_world.size(); ++g) {
      if (!s.info[g].top) continue;
      ++top;
      bool hit = false;
      for (const PipeEstimate& e : out.estimates)
        hit = hit || pose_error_with_turns(model, e.model_to_cam, s.model_to_cam(g)) < 5;
      found += hit;
    }
  }
  ASSERT_GT(top, 5);
  EXPECT_GE(found, 0.8 * top) << found << " of " << top << " top tubes found";
}

// Beyond the paper: the region of a long pipe holds the top strip of a piece of it, along which a
// leg can slide; refined again on every pixel the pose explains (the whole pipe seen), the pose
// lands closer. A long planar bend (the zoo's 23 mm one, legs of 85 and 104 mm) in six piles of
// ten: the top pipes found within 10 mm are 1.2 mm off on average (MSSD), 2.4 mm without.
TEST(Locator, ALongBendIsPlacedByAllTheImageShowsOfIt) {
  const PipeModel model = pipe_of("S85,B-134r188,S104", 23.3, "bend");
  TopPipesPlaced on, off;
  for (unsigned seed = 1; seed <= 6; ++seed) {
    const SimulatedScene s = pile_of(model, 10, seed);
    for (const bool refine_on_explained : {true, false}) {
      LocateConfig cfg;
      cfg.refine_on_explained = refine_on_explained;
      place_top_pipes(model, s, cfg, refine_on_explained ? &on : &off);
    }
  }
  ASSERT_GT(on.top, 5);
  ASSERT_GT(on.within_10, 5);
  ASSERT_GT(off.within_10, 5);
  EXPECT_GE(on.within_5, off.within_5);
  EXPECT_LT(on.mean_error(), 0.7 * off.mean_error()) << on.mean_error() << " mm against " << off.mean_error();
}

// A short S (16.7 mm tube, 69 mm long, the zoo's 09-S-sym): the image's judgement of its
// hypotheses, a count of pixels within the tolerance, does not tell a turn of 10-30 degrees about
// its length, and the hypothesis it took was often turned so. Polished on all the image shows of
// it, the best reading settles where the points put it: on these 16 piles (238 top pipes placed
// within 10 mm) 222 within 5 mm against 217, the mean error 2.64 mm against 2.74.
TEST(Locator, AShortSIsPolishedWhereItsPointsPutIt) {
  const PipeModel model = pipe_of("S21.4,B51.4r13.4,B-51.4r13.4,S21.4", 16.7, "short S");
  TopPipesPlaced on, off;
  for (unsigned seed = 1; seed <= 16; ++seed) {
    std::mt19937 rng(40 + seed);
    SceneParams p;  // as the zoo's: 25 pipes, the camera 1 m up and tilted up to 25 degrees
    p.pile.pipes = 25;
    p.max_tilt_deg = 25;
    const SimulatedScene s = simulate_scene(model, p, rng);
    for (const bool polish : {true, false}) {
      LocateConfig cfg;
      cfg.polish_best = polish;
      place_top_pipes(model, s, cfg, polish ? &on : &off);
    }
  }
  std::printf("short S: found within 5 mm %d polished, %d not; mean error %.2f / %.2f mm over %d / %d\n", on.within_5,
              off.within_5, on.mean_error(), off.mean_error(), on.within_10, off.within_10);
  ASSERT_GT(on.within_10, 10);
  ASSERT_GT(off.within_10, 10);
  EXPECT_GE(on.within_5, off.within_5);
  EXPECT_LT(on.mean_error(), off.mean_error());
}

// A long bend with legs of 85 and 104 mm: its half-turn twin lies on the same pipe, a leg's
// difference off at the ends. The ridge fits often find the twin first, and the twin refined on
// the region's top strip slid off it; refined on all the pipe the image shows, round by round,
// it lands on the pipe. On these 16 piles 4 of 48 pickable poses were the pipe end for end
// before; now 1 of 47 is (a twin 25 mm off the pipe, under other pipes: agreement 0.78).
TEST(Locator, AnUnequalLeggedBendIsNotHandedOutEndForEnd) {
  const PipeModel model = pipe_of("S85,B-134r188,S104", 23.3, "bend");
  ASSERT_EQ(model.near_symmetries.size(), 1u);
  int wrong = 0;
  const int pickable = for_each_pickable(model, 8, 16, [&](const PipeEstimate& e, const SimulatedScene& s) {
    wrong += nearest_pipe_error(model, e.model_to_cam, s) > 10;
  });
  EXPECT_GE(pickable, 16);
  EXPECT_LE(20 * wrong, pickable) << wrong << " of " << pickable << " pickable poses are more than 10 mm off";
}

// A near-symmetric S alone on the floor (the zoo's 12.3 mm S, legs 9.4 and 14 mm): its twin, the
// legs swapped, is confirmed about as well, its ends a third of D off. The pipe is handed out in
// more than half of the frames (7 of these 12, with the telling pixels read at the noise or not:
// on 480 lone-pipe images that gained 9 picks, docs/experiments.md), and the twin never.
TEST(Locator, ALoneNearSymmetricSIsHandedOutAndNeverItsTwin) {
  const PipeModel model = pipe_of("S9.4,B108.2r14.4,S9.4,B-85.7r15.5,S14", 12.3, "near-symmetric S");
  ASSERT_EQ(model.near_symmetries.size(), 1u);
  int picked = 0, wrong = 0;
  const int frames = 12;
  for (unsigned seed = 1; seed <= unsigned(frames); ++seed) {
    std::mt19937 rng(70 + seed);
    SceneParams p;
    p.pile.pipes = 1;
    p.camera_height_min_mm = 600, p.camera_height_max_mm = 800;
    const SimulatedScene s = simulate_scene(model, p, rng);
    Locator loc(model, LocateConfig{}, s.camera.intrinsics);
    const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
    const int k = out.pick();
    if (k < 0) continue;
    ++picked;
    wrong += nearest_pipe_error(model, out.estimates[std::size_t(k)].model_to_cam, s) > 10;
  }
  std::printf("lone near-symmetric S: picked in %d of %d frames, %d wrong\n", picked, frames, wrong);
  EXPECT_GT(2 * picked, frames);
  EXPECT_EQ(wrong, 0);
}

// An arc slides along itself: where its ends are hidden the image fits the slid pose as well.
// No pose handed out as pickable may lie more than 10 mm from every arc of the pile.
TEST(Locator, NoPickablePoseIsAnArcSlidAlongItself) {
  const PipeModel model = pipe_of("B200r150", 20, "arc");
  int wrong = 0;
  const int pickable = for_each_pickable(model, 10, 4, [&](const PipeEstimate& e, const SimulatedScene& s) {
    wrong += nearest_pipe_error(model, e.model_to_cam, s) > 10;
  });
  EXPECT_GE(pickable, 1);
  EXPECT_EQ(wrong, 0) << wrong << " of " << pickable << " pickable poses are more than 10 mm off";
}

// A thick straight tube reaching out of the view is placed along its axis by its end in view
// alone; the slides judged as rivals are max(10 mm, D/2) apart, and its end probes reach 0.75-1.25
// D. Moved along itself in D/12 steps to where the image confirms the most and sees through the
// least of it, its pose lands within 5 mm in each of six scenes; without place_slides_finely in
// three (36 and 44 mm off along its axis: a held-out zoo's 43 mm tube was handed out so).
TEST(Locator, AThickTubeOutOfTheViewIsPlacedByItsEndInView) {
  const PipeModel model = pipe_of("S700", 40, "thick straight");
  const Intrinsics k;
  int scenes = 0, placed = 0, placed_coarse = 0;
  unsigned seed = 1;
  for (double yaw : {-8.0, 0.0, 8.0})
    for (double y : {-120.0, 100.0}) {
      // Its middle 330 mm right of the view's centre on the floor: a fifth of it out of the view.
      const SimulatedScene s = scene_of(model, {lying_straight(model, yaw, 330, y, 20)}, seed++);
      ++scenes;
      for (bool finely : {true, false}) {
        LocateConfig cfg;
        cfg.place_slides_finely = finely;
        Locator loc(model, cfg, k);
        const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
        bool within = false;
        for (const PipeEstimate& e : out.estimates)
          within = within || pose_error_with_turns(model, e.model_to_cam, s.model_to_cam(0)) < 5;
        (finely ? placed : placed_coarse) += within;
      }
    }
  EXPECT_EQ(placed, scenes) << placed << " of " << scenes << " tubes placed within 5 mm (" << placed_coarse
                            << " without place_slides_finely)";
}

// An arc of 203 degrees with straight legs (547 mm, 26.3 mm tube) 0.8 m under the Kinect-class
// sensor, tilted 13 degrees: many of a pile's arcs reach out of the view, and a pose found along
// one is often slid along it, the tube going on beyond one end. The slid rivals reach 5 steps,
// and, refined, slide back along the top strip. The bin of 15-arc of a held-out zoo (tools/zoo
// --seed 21) stopped at its first frame; followed along the arc to where the image shows its end
// (follow_slides_to_ends), poses there are picks, none wrong (more than 10 mm off).
TEST(Locator, AnArcSlidAlongItselfIsFollowedToItsEndInView) {
  const PipeModel arc = pipe_of("S44.3,B203.3r258.7,S44.3", 26.3, "arc with legs");
  int taken[2] = {0, 0};
  for (int follow = 0; follow < 2; ++follow) {
    SimSourceConfig sim;
    sim.pipes = 25, sim.seed = 2101014, sim.tilt_deg = 12.9;
    sim.camera_height_min_mm = 772, sim.camera_height_max_mm = 872;
    sim.refill = false;
    SimSource source(arc, sim);
    Frame frame;
    frame.depth_mm.resize(source.intrinsics().width, source.intrinsics().height);
    LocateConfig cfg;
    cfg.follow_slides_to_ends = follow == 1;
    for (int cycle = 0; cycle < 4; ++cycle) {  // as the cell clears the bin, up to 4 pipes
      const Clock::time_point t0 = Clock::now();
      ASSERT_EQ(source.grab(t0, t0 + std::chrono::seconds(30), &frame), GrabStatus::ok);
      Locator loc(arc, cfg, frame.camera.intrinsics);
      const PipeEstimate* pick = nullptr;
      for (const PipeEstimate& e : loc.locate(frame.depth_mm, frame.camera).estimates)
        if (e.pickable) {
          pick = &e;
          break;
        }
      if (!pick) break;
      double error_mm = 1e9;
      for (const Pose& p : source.pipes_in_camera())
        error_mm = std::min(error_mm, pose_error(arc, pick->model_to_cam, p));
      std::printf("follow_slides_to_ends %d: a pick %.1f mm from its pipe\n", follow, error_mm);
      ASSERT_LE(error_mm, 10) << "a wrong pick, follow_slides_to_ends " << follow;
      source.picked(pick->model_to_cam);
      ++taken[follow];
    }
  }
  std::printf("pipes taken without / with following: %d / %d\n", taken[0], taken[1]);
  EXPECT_EQ(taken[0], 0);  // measured
  EXPECT_GE(taken[1], 2);  // measured: 2 (the zoo's bin stops there)
}

// Clears a simulated bin as a cell does, for at most `cycles` LOCATEs: each pick is taken from the
// bin, and must be a pipe there (within 10 mm). Returns the pipes taken before no pick is handed out.
int taken_before_the_bin_stops(const PipeModel& model, const SimSourceConfig& sim, int cycles,
                               const LocateConfig& cfg = LocateConfig{}) {
  SimSource source(model, sim);
  Frame frame;
  frame.depth_mm.resize(source.intrinsics().width, source.intrinsics().height);
  Locator loc(model, cfg, source.intrinsics());
  int taken = 0;
  for (int cycle = 0; cycle < cycles; ++cycle) {
    const Clock::time_point t0 = Clock::now();
    if (source.grab(t0, t0 + std::chrono::seconds(30), &frame) != GrabStatus::ok) {
      ADD_FAILURE() << "no frame at cycle " << cycle + 1;
      break;
    }
    const LocateOutput& out = loc.locate(frame.depth_mm, frame.camera);
    if (out.pick() < 0) break;
    const Pose pick = out.estimates[std::size_t(out.pick())].model_to_cam;
    double error_mm = 1e9;
    for (const Pose& p : source.pipes_in_camera())
      error_mm = std::min(error_mm, pose_error_with_turns(model, pick, p));
    std::printf("frame %d: pick %.1f mm from its pipe\n", cycle + 1, error_mm);
    EXPECT_LE(error_mm, 10) << "a wrong pick at frame " << cycle + 1;
    if (error_mm > 10) break;
    source.picked(pick);
    ++taken;
  }
  std::printf("pipes taken before the bin stops: %d\n", taken);
  return taken;
}

// A bin of long gentle arcs (93 degrees of a 507 mm radius, 758 mm of 27.8 mm tube; stereo
// sensor about 1 m up, tilted 25 degrees: 14-arc of a held-out zoo, tools/zoo --seed 20) cleared
// as a cell does. Many arcs' middles run out of the view: from their short regions an arc is
// placed by both its ends seen ending outright. And an arc 3 mm from its pipe, its end pinned under
// a pipe across, is not moved 25 mm round itself to where more of it lies in view but a smaller
// share agrees (that pose was handed out at this bin's frame 7). An arc whose part in view slides
// along it is placed only by an end seen ending outright (pin_part_in_view_by_ends): the bin stops
// two arcs earlier than with an end pinned past a hidden tip, as one in the zoo's bins was pinned
// 40 mm round its arc, past a pipe across its end (docs/experiments.md).
TEST(Locator, ABinOfLongArcsIsClearedByTheirEndsWithoutAWrongPick) {
  SimSourceConfig sim;
  sim.pipes = 30, sim.seed = 2001013, sim.tilt_deg = 24.8, sim.sensor = "stereo";
  sim.camera_height_min_mm = 984, sim.camera_height_max_mm = 1084;
  sim.refill = false;
  EXPECT_GE(taken_before_the_bin_stops(pipe_of("B93.3r507.3", 27.8, "long arc"), sim, 12),
            7);  // measured: 12, every cycle asked
}

// Another bin of those arcs, its pipes' cores read from 0.5 D^2 (core_min_area_of_d2, which
// finds more pieces of cut top strips). At its third frame an arc whose end casts the stereo
// shadow on a pipe below was found 19 mm round itself past that end, over the shadow, where both
// end probes read the pipe below; the fine placement did not move it back, as there its end's
// first probe falls in the shadow and the end is no longer seen ending outright. Seen ending but
// for the shadow counts for the move (judge_ends: ends_ending_past_shadow).
TEST(Locator, AnArcsEndBesideTheSensorsShadowPlacesIt) {
  SimSourceConfig sim;
  sim.pipes = 30, sim.seed = 2003013, sim.tilt_deg = 24.8, sim.sensor = "stereo";
  sim.camera_height_min_mm = 984, sim.camera_height_max_mm = 1084;
  sim.refill = false;
  LocateConfig cfg;
  cfg.core_min_area_of_d2 = 0.5f;
  // measured: 4 in 4 cycles; without the count 2, the third pick 19.3 mm off (a test failure)
  EXPECT_GE(taken_before_the_bin_stops(pipe_of("B93.3r507.3", 27.8, "long arc"), sim, 4, cfg), 3);
}

// A bin of small S bends whose legs differ (57 mm of 9.4 mm tube; Kinect-class sensor about
// 0.95 m up, tilted 12.5 degrees: 11-S-asym of tools/zoo --seed 21, its eighth bin) cleared as a
// cell does. At its fifteenth frame a pose of an S lying 61 mm from every pipe (as the scorer
// measures, the S's exact turns allowed) was the pick; its near twin, refined on the points that
// pose explains, agreed 0.93 and saw through 0.07 of itself, judged worse. Refined on the region
// as well (twins_refined_on_region), the twin agrees 0.96 and sees through 0.04, as well as the
// pose: the S is ambiguous, not handed out.
TEST(Locator, ASmallSsNearTwinIsRefinedOnItsRegionToo) {
  SimSourceConfig sim;
  sim.pipes = 20, sim.seed = 2104510, sim.tilt_deg = 12.5, sim.sensor = "kinect";
  sim.camera_height_min_mm = 911, sim.camera_height_max_mm = 1011;
  sim.refill = false;
  const PipeModel s_bend = pipe_of("S2.4,B52.9r17,S3.4,B-52.1r16.1,S20.3", 9.4, "S");
  // measured: 16 in 16 cycles; without it 14, the fifteenth pick 60.7 mm off (a test failure)
  EXPECT_GE(taken_before_the_bin_stops(s_bend, sim, 16), 15);
}

// A bin of long straight tubes (900 mm of 43 mm tube; Kinect-class sensor 1.2 m up, tilted 25
// degrees, seeing part of the bin: 01-straight of tools/zoo --seed 20) cleared as a cell does.
// Most tubes run out of the view at one end. One is placed by its end in view seen ending, from a
// short region too, and told from a rival slid along it by the pixels where the two differ; not
// by an end pinned only by the probe read further along it, past a sensor's shadow (a tube
// handed out 70 mm short of its end at this bin's frame 6).
TEST(Locator, ABinOfLongTubesIsClearedByTheEndsInView) {
  SimSourceConfig sim;
  sim.pipes = 10, sim.seed = 2001000, sim.tilt_deg = 24.9, sim.sensor = "kinect";
  sim.camera_height_min_mm = 1150, sim.camera_height_max_mm = 1250;
  sim.refill = false;
  EXPECT_GE(taken_before_the_bin_stops(pipe_of("S899.2", 43.4, "long tube"), sim, 10),
            6);  // measured: 6 (1 before)
}

// A coil standing on its edge shows the camera its top arc: turned a third of a turn round its
// helix it shows the same arc (17-coil of the zoo: a pick 112 mm off while clearing). Its rivals
// are slid far along it too, as far as 60 % of its surface stays on itself; an arc's as well. A
// bend whose shape changes along it has none.
TEST(Locator, ACoilIsSlidFarAlongItsHelixToo) {
  const Intrinsics k;
  const PipeModel coil = pipe_of("B120r55.7,B120r55.7t15.6,B120r55.7t15.6,B77.6r55.7t15.6", 22.5, "coil");
  const Locator loc_coil(coil, LocateConfig{}, k);
  const LocatorModel& lm = loc_coil.locator_model();
  ASSERT_GT(lm.slides.size(), lm.short_slides);
  double furthest_deg = 0;
  for (std::size_t i = lm.short_slides; i < lm.slides.size(); ++i)
    furthest_deg =
        std::max(furthest_deg, rotation_angle_deg(Eigen::Matrix3d::Identity(), lm.slides[i].linear()));
  // The coil's centreline is 425 mm long on a 55.7 mm radius: 40 % of it is 170 mm, 175 degrees.
  EXPECT_GT(furthest_deg, 80.0);
  EXPECT_LT(furthest_deg, 180.0);
  const PipeModel arc = pipe_of("B200r150", 20, "arc");
  const Locator loc_arc(arc, LocateConfig{}, k);
  const LocatorModel& lm_arc = loc_arc.locator_model();
  EXPECT_GT(lm_arc.slides.size(), lm_arc.short_slides);
  const PipeModel elbow = pipe_of("S40,B90r20,S40", 12, "elbow");
  const Locator loc_elbow(elbow, LocateConfig{}, k);
  EXPECT_TRUE(loc_elbow.locator_model().slides.empty());
}

// A coil whose right pose lies partly in the stereo sensor's unread pixels agrees less than the
// same coil slid round its helix onto them, whose end the tube goes on beyond. The zoo's 31 mm
// coil (18-coil) got no pick in any image: at its bin's first frame (the sim source as `tools/zoo`
// sets it) the top coil, wholly in view, was found 211 mm round its helix, ambiguous. Its ends place
// it: with slides_placed_first its right pose goes first and is the pick.
TEST(Locator, ACoilIsPlacedByItsEndsWhereTheSensorLeavesItUnread) {
  const PipeModel coil = pipe_of("B120r80.7,B120r80.7t15.5,B120r80.7t15.5,B78.5r80.7t15.5", 31.3, "coil");
  SimSourceConfig sim;
  sim.pipes = 30, sim.seed = 1017, sim.tilt_deg = 15.6;
  sim.camera_height_min_mm = 477, sim.camera_height_max_mm = 577;
  sim.sensor = "stereo", sim.refill = false;
  SimSource source(coil, sim);
  Frame frame;
  frame.depth_mm.resize(source.intrinsics().width, source.intrinsics().height);
  const Clock::time_point t0 = Clock::now();
  ASSERT_EQ(source.grab(t0, t0 + std::chrono::seconds(30), &frame), GrabStatus::ok);
  const std::vector<Pose> pipes = source.pipes_in_camera();
  double pick_error[2] = {-1, -1};  // mm from the nearest pipe; -1: no pick
  for (int on = 0; on < 2; ++on) {
    LocateConfig cfg;
    cfg.slides_placed_first = on == 1;
    Locator loc(coil, cfg, frame.camera.intrinsics);
    for (const PipeEstimate& e : loc.locate(frame.depth_mm, frame.camera).estimates) {
      if (!e.pickable) continue;  // the first pickable estimate is the pick
      pick_error[on] = 1e9;
      for (const Pose& p : pipes)
        pick_error[on] = std::min(pick_error[on], pose_error(coil, e.model_to_cam, p));
      break;
    }
  }
  std::printf("pick error, rule off / on: %.1f / %.1f mm (-1: no pick)\n", pick_error[0], pick_error[1]);
  EXPECT_EQ(pick_error[0], -1);  // measured: no pick
  ASSERT_GE(pick_error[1], 0);
  EXPECT_LT(pick_error[1], 5);  // measured: 1.0 mm
}

// A coil of 1.25 turns turned half about its length lies nearly where it was: the image confirms
// both about as well, and the coil was ambiguous wherever the turn moved the pick more than 5 mm.
// Where the two differ, the pixels show the right one (as a near twin's do). The coil of seed 21's
// 18-coil of the zoo (8.3 mm, 0.43-0.53 m under the stereo sensor), alone on the floor in 12
// frames: more picks with tell_rolls_apart, none wrong either way.
TEST(Locator, ACoilsTurnAboutItsLengthIsToldApartByThePixels) {
  const PipeModel coil = pipe_of("B120r47.9,B120r47.9t18.2,B120r47.9t18.2,B91.3r47.9t18.2", 8.3, "coil");
  int picks[2] = {0, 0}, right[2] = {0, 0};
  for (unsigned seed = 1; seed <= 12; ++seed) {
    std::mt19937 rng(seed);
    const SimulatedScene s = pipes_below_stereo(coil, 1, 429, 529, rng);
    for (int on = 0; on < 2; ++on) {
      LocateConfig cfg;
      cfg.tell_rolls_apart = on == 1;
      Locator loc(coil, cfg, s.camera.intrinsics);
      const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
      if (out.pick() < 0) continue;
      ++picks[on];
      right[on] +=
          pose_error(coil, out.estimates[std::size_t(out.pick())].model_to_cam, s.model_to_cam(0)) < 5;
    }
  }
  std::printf("picks of 12 frames, rule off / on: %d / %d (right %d / %d)\n", picks[0], picks[1], right[0],
              right[1]);
  EXPECT_EQ(right[0], picks[0]);
  EXPECT_EQ(right[1], picks[1]);
  EXPECT_GT(picks[1], picks[0]);
}

// The ends of every pipe are read, not only of those that slide or have a near twin: where the
// tube goes on beyond both ends of a pose, the pipe lies elsewhere. A 3-D bend with neither,
// alone on the floor: its picks show both ends where they are.
TEST(Locator, EveryPipesEndsAreRead) {
  const PipeModel model = pipe_of("S60,B-40r30,S10,B120r25t70,S8", 16, "3-D bend");
  ASSERT_TRUE(model.near_symmetries.empty());
  int pickable = 0, ends_pinned = 0;
  for (unsigned seed = 40; seed < 43; ++seed) {
    const SimulatedScene s = pile_of(model, 1, seed);
    Locator loc(model, LocateConfig{}, s.camera.intrinsics);
    ASSERT_TRUE(loc.locator_model().slides.empty());
    const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
    for (const PipeEstimate& e : out.estimates)
      if (e.pickable) ++pickable, ends_pinned += e.check.ends_pinned;
  }
  std::printf("pickable %d, ends pinned %d\n", pickable, ends_pinned);
  // Measured: 3 picks, 6 ends pinned (none read before: 0).
  EXPECT_GE(pickable, 2);
  EXPECT_GE(ends_pinned, pickable);
}

// A thin pipe mapped onto itself by a half-turn (an S with equal legs, a 10 mm tube): its exact
// symmetry is found, so its twin is the same pick: no pose of it is ambiguous, and it is picked.
// (One frame of the three finds no candidate on it at all: a detection miss, not an ambiguity.)
TEST(Locator, AThinSymmetricPipeIsPickable) {
  const PipeModel model = pipe_of("S40,B90r25,B-90r25,S40", 10, "thin-s");
  ASSERT_EQ(model.symmetries.size(), 1u);
  LocateConfig cfg;
  int right = 0, ambiguous = 0, picked_right = 0;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const SimulatedScene s = pile_of(model, 3, seed);
    Locator loc(model, cfg, s.camera.intrinsics);
    const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
    for (std::size_t k = 0; k < out.estimates.size(); ++k) {
      if (nearest_pipe_error(model, out.estimates[k].model_to_cam, s) >= 5) continue;
      ++right;
      ambiguous += out.estimates[k].ambiguous();
      picked_right += int(k) == out.pick();
    }
  }
  EXPECT_GE(right, 2);
  EXPECT_EQ(ambiguous, 0) << ambiguous << " of " << right << " right poses marked ambiguous";
  EXPECT_GE(picked_right, 2);
}

// Two short straight pipes lying side by side, 0.6 D apart, are two estimates: their poses lie
// within 2 D of each other, but share none of the tube, so neither is the other's duplicate (one
// of them was dropped as such: a top pipe each of the zoo's 04-elbow and 01-straight). Measured:
// both found in 4 of 4 frames; 0 of 4 when every pose within 2 D was a duplicate.
TEST(Locator, TwoPipesSideBySideAreTwoEstimates) {
  const double d = 16.7, r = d / 2;
  const PipeModel model = pipe_of("S69", d, "short");
  const std::vector<Pose> side_by_side = {lying_straight(model, 30, 0, -0.8 * d, r + 0.5),
                                          lying_straight(model, 30, 0, 0.8 * d, r + 0.5)};
  int both = 0;
  constexpr int kFrames = 4;
  for (int frame = 0; frame < kFrames; ++frame) {
    const SimulatedScene s = scene_of(model, side_by_side, unsigned(800 + frame));
    Locator loc(model, LocateConfig{}, s.camera.intrinsics);
    const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
    bool found[2] = {false, false};
    for (const PipeEstimate& e : out.estimates)
      for (std::size_t g = 0; g < 2; ++g)
        found[g] |= pose_error_with_turns(model, e.model_to_cam, s.model_to_cam(g)) < 5;
    std::printf("side by side, frame %d: %zu estimates, pipes found %d %d\n", frame, out.estimates.size(),
                int(found[0]), int(found[1]));
    both += found[0] && found[1];
  }
  EXPECT_GE(both, kFrames - 1);
}

// Specular holes cut a pipe's top strip: a hole across the whole tube, half a diameter long, is
// bridged by the growth (hole_bridge_of_d = 1) and the pipe is found within 5 mm (without the
// bridge: two pieces, each too short for a * L, and no candidate).
TEST(Locator, APipeCutByAHoleAcrossItsRidgeIsFound) {
  const PipeModel& model = preset_model("sbend");
  for (unsigned seed = 1; seed <= 2; ++seed) {
    SimulatedScene s = pile_of(model, 1, seed);
    // The pipe's pixels; the one nearest their mean; the pipe's direction there (the pixels
    // within 1.5 D of it); a band across the pipe there, 0.5 D long along it.
    std::vector<Eigen::Vector2d> px;
    for (int y = 0; y < s.depth_mm.height; ++y)
      for (int x = 0; x < s.depth_mm.width; ++x)
        if (s.clean.label.at(x, y) == 0) px.emplace_back(x, y);
    ASSERT_GT(px.size(), 100u);
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const auto& p : px) mean += p;
    mean /= double(px.size());
    Eigen::Vector2d centre = px[0];
    for (const auto& p : px)
      if ((p - mean).norm() < (centre - mean).norm()) centre = p;
    const double z = s.model_to_cam(0).translation().z();
    const double d_px = model.tube_diameter_mm * s.camera.intrinsics.fx / z;
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
    for (const auto& p : px)
      if ((p - centre).norm() < 1.5 * d_px) cov += (p - centre) * (p - centre).transpose();
    const Eigen::Vector2d along = Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(cov).eigenvectors().col(1);
    const double band_px = 0.5 * d_px;
    int cut = 0;
    for (const auto& p : px)
      if (std::abs((p - centre).dot(along)) <= band_px / 2 && (p - centre).norm() < 1.5 * d_px)
        s.depth_mm.at(int(p.x()), int(p.y())) = 0, ++cut;
    ASSERT_GT(cut, 10);
    LocateConfig cfg;
    cfg.hole_bridge_of_d = 1.0;  // off by default (docs/experiments.md)
    Locator loc(model, cfg, s.camera.intrinsics);
    double best = 1e9;
    const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
    for (const PipeEstimate& e : out.estimates)
      best = std::min(best, pose_error(model, e.model_to_cam, s.model_to_cam(0)));
    EXPECT_LT(best, 5.0) << "seed " << seed << ": " << out.regions.core_regions << " cores, " << out.regions.cores_kept
                         << " kept, " << out.regions.candidates << " candidates, first outcome "
                         << (out.traces.empty() ? "-" : outcome_name(out.traces[0].outcome)) << ", cut " << cut
                         << " px, band " << band_px << " px";
  }
}

// A customer's STL of a real elbow fitting models its bore. Lying alone in the bin, seen from
// 0.45 m as the real RealSense frames of ../shared/field show one (the simulator draws the whole
// hollow mesh), it is picked, never wrongly. Measured: 0.9, 5.0 and 8.2 mm from the truth (the
// same elbow modelled solid: under 5, under 5 and 6.2 mm; a short elbow's accuracy at 0.45 m is
// an open point of its own).
TEST(Locator, ALoneHollowElbowIsPicked) {
  const Mesh mesh = hollow_elbow(41.2, 3.5);
  const PipeModel model = derive_pipe_model(mesh, "hollow elbow");
  PipeModel drawn = model;  // the simulator draws the STL as it is, bore and all
  drawn.mesh = mesh;
  int within_5mm = 0;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    std::mt19937 rng(seed);
    SceneParams p;
    p.pile.pipes = 1;
    p.camera_height_min_mm = p.camera_height_max_mm = 450;
    p.sensor = sensor_model("stereo");
    const SimulatedScene s = simulate_scene(drawn, p, rng);
    Locator loc(model, LocateConfig{}, s.camera.intrinsics);
    const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
    ASSERT_GE(out.pick(), 0) << "seed " << seed;
    const double err = pose_error(model, out.estimates[std::size_t(out.pick())].model_to_cam, s.model_to_cam(0));
    std::printf("hollow elbow, seed %u: pick %.1f mm from the truth\n", seed, err);
    EXPECT_LT(err, 10.0) << "seed " << seed << ": a wrong pick";
    within_5mm += err < 5.0;
  }
  EXPECT_GE(within_5mm, 1);
}

// Beyond the paper: a short thin elbow's right ridge fits often lie just above R_th (its ridge is
// a dozen cells, half of them near an end). Where no fit of a region is under R_th, those under
// 1.5 R_th are judged by the image instead of being dropped: more of its top pipes are found,
// and no pose handed out is wrong.
TEST(Locator, AShortThinElbowJustAboveRthIsJudgedByTheImage) {
  const PipeModel model = thin_elbow();
  LocateConfig hard;
  hard.residual_rescue_of_rth = 1;  // the paper's cut
  int found_hard = 0, found = 0, top = 0, wrong_picks = 0;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    const SimulatedScene s = thin_elbow_pile(model, seed);
    const std::vector<GtInfo> info = visibility_info(model, s);
    const auto top_found = [&](const LocateConfig& cfg) {
      Locator loc(model, cfg, s.camera.intrinsics);
      const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
      int n = 0;
      for (std::size_t g = 0; g < info.size(); ++g) {
        if (!info[g].top) continue;
        bool hit = false;
        for (const PipeEstimate& e : out.estimates) hit = hit || pose_error(model, e.model_to_cam, s.model_to_cam(g)) < 5;
        n += hit;
      }
      if (out.pick() >= 0)
        wrong_picks += nearest_pipe_error(model, out.estimates[std::size_t(out.pick())].model_to_cam, s) > 10;
      return n;
    };
    for (const GtInfo& g : info) top += g.top;
    found_hard += top_found(hard);
    found += top_found(LocateConfig{});
  }
  std::printf("short thin elbow: %d of %d top pipes found with R_th a hard cut, %d judged by the image\n",
              found_hard, top, found);
  // Measured: 218 of 279 with the hard cut, 238 judged by the image.
  EXPECT_GE(found, found_hard + top / 30);
  EXPECT_EQ(wrong_picks, 0);
}

// Beyond the paper: a region whose ridge fits the image does not confirm is searched again, its
// whole top surface matched (retry_surface_cell_of_d). A thin short elbow's region holds a ridge of
// 8-20 points, and its fits end turned or flipped; the surface holds the region's shape. Piles of
// 25 thin elbows (8.4 mm tube, 25 mm long, as 04-elbow of the zoo) under the stereo sensor.
// The second searches come after the pick (locate_to_pick(), then search_again()): they add
// poses, never move a pick the first searches made; where those make none, locate_to_pick() runs
// them first and one of their poses may be the pick (second_search_may_pick), never a wrong one.
TEST(Locator, ARegionTheRidgeFitsMissIsSearchedAgainOnItsSurface) {
  const PipeModel model = thin_elbow();
  LocateConfig once;  // the ridge search alone
  once.retry_surface_cell_of_d = 0;
  LocateConfig reported;  // the second searches' poses reported, never handed out
  reported.retry_surface_cell_of_d = 0.25;
  reported.second_search_may_pick = false;
  LocateConfig again;  // the default: ... handed out where the first searches hand out none
  again.retry_surface_cell_of_d = 0.25;
  int top = 0, found_once = 0, found = 0, lost = 0, wrong_picks = 0, added = 0, picked_again = 0;
  for (unsigned seed = 1; seed <= 12; ++seed) {
    const SimulatedScene s = thin_elbow_pile(model, seed);
    int first_searches_pick = -1;
    Pose first_searches_pose = Pose::Identity();
    const auto found_per_pipe = [&](const LocateConfig& cfg) {
      Locator loc(model, cfg, s.camera.intrinsics);
      const LocateOutput& first = loc.locate_to_pick(s.depth_mm, s.camera);
      const int first_pick = first.pick();
      const Pose first_pick_pose =
          first_pick >= 0 ? first.estimates[std::size_t(first_pick)].model_to_cam : Pose::Identity();
      const bool picked_by_second =
          first_pick >= 0 && first.estimates[std::size_t(first_pick)].searched_again;
      const std::size_t first_estimates = first.estimates.size();
      const LocateOutput& out = loc.search_again();
      EXPECT_GE(out.estimates.size(), first_estimates) << "seed " << seed;
      if (&cfg == &reported) {
        added += int(out.estimates.size() - first_estimates);
        EXPECT_FALSE(picked_by_second) << "seed " << seed;
        first_searches_pick = first_pick, first_searches_pose = first_pick_pose;
      }
      if (&cfg == &again) {
        picked_again += picked_by_second;
        EXPECT_EQ(first_pick >= 0 && !picked_by_second, first_searches_pick >= 0) << "seed " << seed;
        if (first_searches_pick >= 0) {
          EXPECT_TRUE(first_pick_pose.isApprox(first_searches_pose))
              << "seed " << seed << ": a second search's pose took the first searches' pick";
        }
      }
      EXPECT_EQ(out.pick() >= 0, first_pick >= 0) << "seed " << seed;
      if (out.pick() >= 0 && first_pick >= 0) {
        EXPECT_TRUE(out.estimates[std::size_t(out.pick())].model_to_cam.isApprox(first_pick_pose))
            << "seed " << seed << ": the second searches moved the pick";
      }
      std::vector<bool> hit(s.info.size(), false);
      for (std::size_t g = 0; g < s.info.size(); ++g)
        for (const PipeEstimate& e : out.estimates)
          hit[g] = hit[g] || pose_error(model, e.model_to_cam, s.model_to_cam(g)) < 5;
      if (out.pick() >= 0)
        wrong_picks += nearest_pipe_error(model, out.estimates[std::size_t(out.pick())].model_to_cam, s) > 10;
      return hit;
    };
    const std::vector<bool> a = found_per_pipe(once);
    found_per_pipe(reported);
    const std::vector<bool> b = found_per_pipe(again);
    for (std::size_t g = 0; g < s.info.size(); ++g) {
      if (!s.info[g].top) continue;
      ++top, found_once += a[g], found += b[g], lost += a[g] && !b[g];
    }
  }
  std::printf(
      "short thin elbow: %d of %d top pipes found by the ridge search alone, %d searched again (%d lost; "
      "%d poses added after the pick; %d piles picked from a second search)\n",
      found_once, top, found, lost, added, picked_again);
  // Measured: 238 of 279 by the ridge search alone, 251 searched again, none lost.
  EXPECT_GE(found, found_once + top / 50);
  EXPECT_GT(added, 0);
  EXPECT_LE(lost, top / 100);
  EXPECT_EQ(wrong_picks, 0);
}

// ... and where the first searches hand out no pose, a second search's pose the image confirms
// well, its sides seen dropping away, is the pick (second_search_may_pick): a lone thin elbow on
// the bin floor, the last pipe of a bin, whose ridge of a few points the fits miss.
TEST(Locator, ALoneThinElbowTheRidgeFitsMissIsPickedFromItsSecondSearch) {
  const PipeModel model = thin_elbow();
  LocateConfig reported;
  reported.second_search_may_pick = false;
  const LocateConfig by_default;
  int picks_reported = 0, picks = 0, from_second = 0, wrong = 0;
  std::mt19937 rng(11);
  constexpr int kImages = 30;
  for (int image = 0; image < kImages; ++image) {
    // One elbow on the floor, the sensor 0.65-0.72 m up (as 04-elbow of the zoo).
    const SimulatedScene s = pipes_below_stereo(model, 1, 650, 720, rng);
    Locator a(model, reported, s.camera.intrinsics), b(model, by_default, s.camera.intrinsics);
    const LocateOutput& first = a.locate_to_pick(s.depth_mm, s.camera);
    const int pa = first.pick();
    const Pose pose_a = pa >= 0 ? first.estimates[std::size_t(pa)].model_to_cam : Pose::Identity();
    const LocateOutput& out = b.locate_to_pick(s.depth_mm, s.camera);
    const int pb = out.pick();
    picks_reported += pa >= 0, picks += pb >= 0;
    if (pb < 0) continue;
    const PipeEstimate& e = out.estimates[std::size_t(pb)];
    from_second += e.searched_again;
    wrong += nearest_pipe_error(model, e.model_to_cam, s) > 10;
    if (pa >= 0) {
      EXPECT_FALSE(e.searched_again) << "image " << image;
      EXPECT_TRUE(e.model_to_cam.isApprox(pose_a)) << "image " << image << ": the first searches' pick moved";
    }
  }
  std::printf(
      "lone thin elbow: %d of %d picked by the first searches, %d with the second's (%d of theirs, %d "
      "wrong)\n",
      picks_reported, kImages, picks, from_second, wrong);
  // Measured: 24 of 30, then 25 (1 of the second searches'), none wrong.
  EXPECT_EQ(picks, picks_reported + from_second);
  EXPECT_GT(from_second, 0);
  EXPECT_EQ(wrong, 0);
}

// A tube the sensor does not resolve is not handed out: the same thin elbow in piles of two, the
// stereo sensor at the simulator's default height (1.0-1.07 m), where its 4.2 mm radius is 1.3
// sigmas of the noise. Its poses are still reported, marked unresolved; with the check off some
// are handed out (measured on 40 such images: 13 picks, 1 within 5 mm, 2 more than 10 mm off).
TEST(Locator, AThinElbowTheSensorDoesNotResolveIsNotHandedOut) {
  const PipeModel model = thin_elbow();
  const LocateConfig by_default;
  LocateConfig unchecked;
  unchecked.pick_min_relief_sigmas = 0;
  int picks = 0, picks_unchecked = 0, unresolved = 0;
  std::mt19937 rng(7);
  constexpr int kImages = 16;
  for (int image = 0; image < kImages; ++image) {
    const SimulatedScene s = pipes_below_stereo(model, 2, 1000, 1070, rng);
    Locator a(model, by_default, s.camera.intrinsics), b(model, unchecked, s.camera.intrinsics);
    const LocateOutput& out = a.locate_to_pick(s.depth_mm, s.camera);
    picks += out.pick() >= 0;
    for (const PipeEstimate& e : out.estimates) {
      unresolved += e.unresolved;
      if (e.unresolved) {
        EXPECT_LT(e.relief_sigmas, by_default.min_relief(/*straight_tube=*/false).sigmas)
            << "image " << image;
      }
    }
    picks_unchecked += b.locate_to_pick(s.depth_mm, s.camera).pick() >= 0;
  }
  std::printf("thin elbow at 1 m: %d picks of %d images (%d unchecked), %d poses unresolved\n", picks,
              kImages, picks_unchecked, unresolved);
  EXPECT_EQ(picks, 0);
  EXPECT_GT(picks_unchecked, 0) << "nothing would be handed out anyway: the test shows nothing";
  EXPECT_GT(unresolved, 0);
}

// A thin bend whose near twin (the ends swapped) lies within 1.7 mm of it everywhere (the zoo's
// 23-planar of seed 21), in pairs 1.05-1.12 m under the Kinect-class sensor: one pixel covers that
// spread from 0.98 m on. With twin_beyond_resolution_ambiguous every pose found there is ambiguous,
// none handed out; without it some are, though no pixel can tell which end is which.
TEST(Locator, ANearTwinTheCameraDoesNotResolveIsNotHandedOut) {
  const PipeModel model = pipe_of("S14.7,B69.1r56.1,S23.8", 9.1, "thin bend with a near twin");
  ASSERT_EQ(model.near_symmetries.size(), 1u);
  LocateConfig judged;
  judged.twin_beyond_resolution_ambiguous = true;
  LocateConfig unjudged;
  unjudged.twin_beyond_resolution_ambiguous = false;
  int picks = 0, picks_unjudged = 0, wrong_unjudged = 0, found = 0;
  constexpr int kImages = 8;
  for (unsigned image = 0; image < unsigned(kImages); ++image) {
    std::mt19937 rng(40 + image);
    SceneParams p;
    p.pile.pipes = 2;
    p.camera_height_min_mm = 1050, p.camera_height_max_mm = 1120;
    const SimulatedScene s = simulate_scene(model, p, rng);
    ASSERT_LT(twin_resolved_within_mm(model, s.camera.intrinsics.fx, kTwinUnresolvedPixels), 990.0);
    Locator a(model, judged, s.camera.intrinsics), b(model, unjudged, s.camera.intrinsics);
    const LocateOutput& out = a.locate_to_pick(s.depth_mm, s.camera);
    picks += out.pick() >= 0;
    for (const PipeEstimate& e : out.estimates) {
      ++found;
      EXPECT_TRUE(e.ambiguous_why & kAmbiguousTwinUnresolved) << "image " << image;  // ambiguous, and why
    }
    const LocateOutput& out_b = b.locate_to_pick(s.depth_mm, s.camera);
    if (const int k = out_b.pick(); k >= 0) {
      ++picks_unjudged;
      wrong_unjudged += nearest_pipe_error(model, out_b.estimates[std::size_t(k)].model_to_cam, s) > 10;
    }
  }
  std::printf(
      "thin bend with a near twin at 1.1 m: %d picks of %d images (%d without the rule, %d of them wrong), "
      "%d poses\n",
      picks, kImages, picks_unjudged, wrong_unjudged, found);
  EXPECT_EQ(picks, 0);
  EXPECT_GT(found, 0) << "no pose found: the test shows nothing";
  EXPECT_GT(picks_unjudged, 0) << "nothing would be handed out anyway: the test shows nothing";
}

// The service's next command ends the second searches (an interrupt flag): none of them then
// adds a pose, and the first searches' poses stay as they were.
TEST(Locator, SecondSearchesEndWhenInterrupted) {
  const PipeModel model = thin_elbow();
  int added_uninterrupted = 0;
  for (unsigned seed = 1; seed <= 3; ++seed) {
    const SimulatedScene s = thin_elbow_pile(model, seed);
    LocateConfig cfg;
    cfg.retry_surface_cell_of_d = 0.25;
    Locator loc(model, cfg, s.camera.intrinsics);
    const std::size_t first = loc.locate_to_pick(s.depth_mm, s.camera).estimates.size();
    const std::atomic<bool> waiting{true};
    const LocateOutput& out = loc.search_again(&waiting);
    EXPECT_EQ(out.estimates.size(), first) << "seed " << seed;
    EXPECT_EQ(loc.search_again().estimates.size(), first) << "seed " << seed << ": searched again twice";
    loc.locate_to_pick(s.depth_mm, s.camera);
    added_uninterrupted += int(loc.search_again().estimates.size() - first);
  }
  EXPECT_GT(added_uninterrupted, 0) << "no second search added a pose: the test shows nothing";
}

TEST(Locator, EmptyAndInvalidFramesGiveNothingAndDoNotCrash) {
  const PipeModel& model = preset_model("u");
  LocateConfig cfg;
  Intrinsics k;
  Locator loc(model, cfg, k);
  CameraInfo cam;
  cam.intrinsics = k;
  Image<float> depth(k.width, k.height, 0.0f);
  EXPECT_TRUE(loc.locate(depth, cam).estimates.empty());
  depth.fill(std::nanf(""));
  EXPECT_TRUE(loc.locate(depth, cam).estimates.empty());
  depth.fill(1000.0f);  // a flat floor: upward everywhere, but no pipe
  EXPECT_TRUE(loc.locate(depth, cam).estimates.empty());
}

// The PLC's pick: of the pickable poses, the first searches' before the second searches', and of
// each a pose an end of which the image shows ending outright before one it does not (a pose
// pinned only past a hidden tip may lie slid along its pipe), in rank order.
TEST(LocateOutput, APoseSeenEndingOutrightIsHandedOutBeforeOneThatIsNot) {
  const auto estimate = [](bool pickable, int seen_ending, bool searched_again) {
    PipeEstimate e;
    e.pickable = pickable;
    e.check.ends_pinned = e.check.ends_seen_ending = seen_ending;
    e.searched_again = searched_again;
    return e;
  };
  LocateOutput out;
  out.estimates = {estimate(true, 0, false), estimate(false, 2, false), estimate(true, 1, true),
                   estimate(true, 1, false), estimate(true, 2, false)};
  EXPECT_EQ(out.pick(), 3);  // not 0, its ends not seen ending; nor 1, not pickable; nor 2, searched again
  EXPECT_EQ(LocateOutput::hand_out_order(out.estimates[0]), 1);
  EXPECT_EQ(LocateOutput::hand_out_order(out.estimates[1]), -1);
  EXPECT_EQ(LocateOutput::hand_out_order(out.estimates[2]), 2);
  EXPECT_EQ(LocateOutput::hand_out_order(out.estimates[3]), 0);
  out.estimates = {estimate(true, 0, false), estimate(true, 0, false), estimate(true, 1, true)};
  EXPECT_EQ(out.pick(), 0);  // none seen ending: the best of the first searches
  out.estimates = {estimate(false, 0, false), estimate(true, 0, true), estimate(true, 1, true)};
  EXPECT_EQ(out.pick(), 2);  // the first searches hand out none: the second searches', ends first
  out.estimates = {estimate(false, 1, false)};
  EXPECT_EQ(out.pick(), -1);
}

// ... and a pose pinned at both ends, though neither is seen ending outright, is placed by its
// ends as well as one seen ending: handed out in rank order with it. One pinned end is not enough,
// unless it is seen ending but for the sensor's shadow.
TEST(LocateOutput, APosePinnedAtBothEndsIsHandedOutAsOneSeenEnding) {
  const auto estimate = [](int pinned, int seen_ending) {
    PipeEstimate e;
    e.pickable = true;
    e.check.ends_pinned = pinned;
    e.check.ends_seen_ending = seen_ending;
    return e;
  };
  LocateOutput out;
  out.estimates = {estimate(2, 0), estimate(1, 1)};
  EXPECT_EQ(out.pick(), 0);  // the better ranked: both placed by their ends
  EXPECT_EQ(LocateOutput::hand_out_order(out.estimates[0]), 0);
  out.estimates = {estimate(1, 0), estimate(2, 0)};
  EXPECT_EQ(out.pick(), 1);  // one end pinned only: after the pose pinned at both
  EXPECT_EQ(LocateOutput::hand_out_order(out.estimates[0]), 1);
  out.estimates = {estimate(1, 0), estimate(0, 0)};
  EXPECT_EQ(out.pick(), 0);  // neither placed: rank order
  // One end pinned and seen ending but for the sensor's shadow: placed, before a worse-ranked pose
  // seen ending outright.
  out.estimates = {estimate(1, 0), estimate(1, 1)};
  out.estimates[0].check.ends_ending_past_shadow = 1;
  EXPECT_EQ(out.pick(), 0);
  EXPECT_EQ(LocateOutput::hand_out_order(out.estimates[0]), 0);
}

}  // namespace
}  // namespace pipeloc
