// IV-B: nearest points, pose distances, the ridge ICP and its starts.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <random>

#include "locate/locator.hpp"
#include "locate_fixtures.hpp"

namespace pipeloc {
namespace {

// Against brute force: the first of the closest points, on sets of 0 to 13 points (every tail
// after the groups of four), drawn on a coarse grid so that ties are common.
TEST(PointColumns, NearestIsTheFirstOfTheClosestAsBruteForce) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> grid(-3, 3), near(-1, 1);
  PointColumns columns;
  columns.reserve(16);
  int ties = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const int n = trial % 14;
    std::vector<Eigen::Vector3f> pts;
    for (int k = 0; k < n; ++k) pts.emplace_back(float(near(rng)), float(near(rng)), 0.5f * float(near(rng)));
    ASSERT_TRUE(columns.assign(pts.data(), n));
    const Eigen::Vector3f q(float(grid(rng)) + 0.5f, float(grid(rng)), 0.25f * float(grid(rng)));
    int want = -1, at_least = 0;
    float want_d2 = 1e30f;
    for (int k = 0; k < n; ++k) {
      const float d2 = (pts[std::size_t(k)] - q).squaredNorm();
      if (d2 < want_d2) want_d2 = d2, want = k;
    }
    for (int k = 0; k < n; ++k) at_least += (pts[std::size_t(k)] - q).squaredNorm() == want_d2;
    ties += at_least > 1;
    float got_d2 = 0;
    EXPECT_EQ(columns.nearest(q, &got_d2), want) << "trial " << trial;
    if (want >= 0) {
      EXPECT_EQ(got_d2, want_d2) << "trial " << trial;
    }
  }
  EXPECT_GT(ties, 20);  // the tie-break was put to the test
}

// Both ways from one pass: each answer is nearest()'s from that side, ties to the first included.
TEST(PointColumns, NearestBothWaysIsNearestFromEachSide) {
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> near(-1, 1);
  const auto draw = [&](int n) {
    std::vector<Eigen::Vector3f> pts;
    for (int k = 0; k < n; ++k) pts.emplace_back(float(near(rng)), float(near(rng)), 0.5f * float(near(rng)));
    return pts;
  };
  PointColumns b_columns, a_columns;
  b_columns.reserve(16);
  a_columns.reserve(16);
  for (int trial = 0; trial < 300; ++trial) {
    const int na = trial % 11, nb = (trial / 11) % 14;
    const std::vector<Eigen::Vector3f> a = draw(na), b = draw(nb);
    ASSERT_TRUE(b_columns.assign(b.data(), nb));
    ASSERT_TRUE(a_columns.assign(a.data(), na));
    std::vector<int> a_to(16), b_to(16);
    std::vector<float> a_d2(16), b_d2(16);
    b_columns.nearest_both_ways(a.data(), na, a_to.data(), a_d2.data(), b_to.data(), b_d2.data());
    for (int i = 0; i < na; ++i) {
      float d2 = 0;
      EXPECT_EQ(a_to[std::size_t(i)], b_columns.nearest(a[std::size_t(i)], &d2)) << "trial " << trial;
      EXPECT_EQ(a_d2[std::size_t(i)], d2) << "trial " << trial;
    }
    for (int j = 0; j < nb; ++j) {
      float d2 = 0;
      EXPECT_EQ(b_to[std::size_t(j)], a_columns.nearest(b[std::size_t(j)], &d2)) << "trial " << trial;
      if (na > 0) {
        EXPECT_EQ(b_d2[std::size_t(j)], d2) << "trial " << trial;
      }
    }
  }
}

// Within a radius: up to it the same partner at the same distance as the scan of all pairs, beyond
// it -1 and 1e30. Sets of 0 to 300 points on a coarse lattice (ties common) spread along a line as a
// ridge is, radii from a tenth of a step to past the set's extent (slabs of a few points to all of
// them); a point far outside the set and a point that is not a number included.
TEST(PointColumns, NearestBothWaysWithinIsNearestBothWaysUpToTheRadius) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> across(-2, 2);
  const auto draw = [&](int n, float step) {
    std::vector<Eigen::Vector3f> pts;
    for (int k = 0; k < n; ++k)
      pts.emplace_back(step * float(k / 3 + across(rng)), step * float(across(rng)),
                       0.5f * step * float(across(rng)));
    return pts;
  };
  const float radii[] = {0.1f, 1.0f, 2.0f, 2.5f, 7.0f, 1e3f};
  PointColumns b_columns, all_pairs;
  b_columns.reserve(300);
  all_pairs.reserve(300);
  std::vector<int> a_to(300), b_to(300), a_want(300), b_want(300);
  std::vector<float> a_d2(300), b_d2(300), a_want_d2(300), b_want_d2(300);
  int within = 0, beyond = 0;
  for (int trial = 0; trial < 240; ++trial) {
    const int na = (trial * 37) % 301, nb = (trial * 53) % 301;
    const float step = trial % 2 ? 1.0f : 3.7f;
    std::vector<Eigen::Vector3f> a = draw(na, step);
    std::vector<Eigen::Vector3f> b = draw(nb, step);
    if (na > 1) a[1] = Eigen::Vector3f(1e9f, 0, 0);          // far beyond the set
    if (nb > 2 && trial % 3 == 0) b[2].x() = std::nanf("");  // never anyone's partner, and none of its own
    ASSERT_TRUE(b_columns.assign(b.data(), nb));
    ASSERT_TRUE(all_pairs.assign(b.data(), nb));
    const float radius = step * radii[trial % 6];
    b_columns.nearest_both_ways_within(a.data(), na, radius, a_to.data(), a_d2.data(), b_to.data(),
                                       b_d2.data());
    all_pairs.nearest_both_ways(a.data(), na, a_want.data(), a_want_d2.data(), b_want.data(),
                                b_want_d2.data());
    const auto expect_same = [&](int got, float got_d2, int want, float want_d2, const char* side, int k) {
      if (want >= 0 && want_d2 <= radius * radius) {
        ++within;
        EXPECT_EQ(got, want) << side << k << " trial " << trial;
        EXPECT_EQ(got_d2, want_d2) << side << k << " trial " << trial;
      } else {
        ++beyond;
        EXPECT_EQ(got, -1) << side << k << " trial " << trial;
        EXPECT_EQ(got_d2, 1e30f) << side << k << " trial " << trial;
      }
    };
    for (int i = 0; i < na; ++i)
      expect_same(a_to[std::size_t(i)], a_d2[std::size_t(i)], a_want[std::size_t(i)],
                  a_want_d2[std::size_t(i)], "a", i);
    for (int j = 0; j < nb; ++j)
      expect_same(b_to[std::size_t(j)], b_d2[std::size_t(j)], b_want[std::size_t(j)],
                  b_want_d2[std::size_t(j)], "b", j);
  }
  EXPECT_GT(within, 10000);
  EXPECT_GT(beyond, 1000);
}

// A bound only cuts short what lies beyond it: up to the bound the distance is the exact one, and
// beyond it the value returned lies beyond it too (models with and without symmetries).
TEST(PoseDistance, ExactUpToTheBoundAndBeyondItPastIt) {
  LocateConfig cfg;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1, 1);
  for (const char* name : {"sbend", "torus"}) {
    const LocatorModel lm = prepare_locator_model(preset_model(name), 8, cfg);
    int below = 0, beyond = 0;
    for (int trial = 0; trial < 400; ++trial) {
      Pose a = Pose::Identity(), b = Pose::Identity();
      a.linear() = Eigen::AngleAxisd(u(rng) * M_PI, Eigen::Vector3d(u(rng), u(rng), 1).normalized())
                       .toRotationMatrix();
      a.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng)) * 100;
      const double scale = std::pow(10.0, 2 * u(rng) - 1);  // small and large moves
      b.linear() =
          Eigen::AngleAxisd(0.05 * scale * u(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix() * a.linear();
      b.translation() = a.translation() + Eigen::Vector3d(u(rng), u(rng), u(rng)) * 3 * scale;
      const float exact = pose_distance_mm(lm, a, b);
      for (const float bound : {1.0f, 5.0f, 10.0f, 50.0f}) {
        const float cut = pose_distance_mm(lm, a, b, bound);
        if (exact <= bound) {
          EXPECT_EQ(cut, exact) << name << " trial " << trial << " bound " << bound;
          ++below;
        } else {
          EXPECT_GT(cut, bound) << name << " trial " << trial << " bound " << bound;
          ++beyond;
        }
      }
    }
    EXPECT_GT(below, 200) << name;
    EXPECT_GT(beyond, 200) << name;
  }
}

// Beyond the paper: a hypothesis is a rival of the best only where the two share the tube. The
// same pose shares all of it, the pose moved a diameter along its first leg a part, the pose moved two
// diameters beside it (a neighbouring pipe) none.
TEST(PoseDistance, SharedTubeIsTheShareOfTheCentrelineWhereTheOtherPoseHasIt) {
  LocateConfig cfg;
  const LocatorModel lm = prepare_locator_model(preset_model("sbend"), 8, cfg);
  const auto& c = lm.centreline_points;
  ASSERT_GE(c.size(), 16u);
  const float d = lm.tube_d_mm;
  Pose a = Pose::Identity();
  a.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -0.2, 1).normalized()).toRotationMatrix();
  a.translation() = Eigen::Vector3d(40, -25, 880);
  EXPECT_FLOAT_EQ(shared_tube(lm, a, a), 1.0f);
  // Moved a diameter along its first leg: that leg stays in the tube, the bends leave it.
  Pose slid = a;
  slid.translation() += a.linear() * ((c[1] - c[0]).normalized() * d).cast<double>();
  const float slid_share = shared_tube(lm, slid, a);
  EXPECT_GE(slid_share, kRivalMinSharedTube);
  EXPECT_LT(slid_share, 1.0f);
  // Beside it: the whole centreline moved two diameters off its own plane.
  const Eigen::Vector3f normal = (c[c.size() / 4] - c[0]).cross(c[3 * c.size() / 4] - c[0]).normalized();
  Pose beside = a;
  beside.translation() += a.linear() * (2 * d * normal).cast<double>();
  EXPECT_EQ(shared_tube(lm, beside, a), 0.0f);
  EXPECT_LT(shared_tube(lm, beside, a), kRivalMinSharedTube);
}

// Beyond the paper: two regions' estimates that read one pipe two ways. A J bend's pose reaching
// out of the view and the same slid 3 D along its long leg share its tube (more than duplicates
// are apart): confirmed about as well, one pipe read two ways; both wholly in the view, or one
// clearly better, not; beside it, a neighbour.
TEST(PoseDistance, TwoEstimatesSharingTheTubeFarApartReadOnePipeTwoWays) {
  LocateConfig cfg;
  const LocatorModel lm = prepare_locator_model(pipe_of("S200,B90r40,S100", 20), 8, cfg);
  const auto& c = lm.centreline_points;
  ASSERT_GE(c.size(), 16u);
  const float d = lm.tube_d_mm;
  PipeEstimate a;
  a.model_to_bin.translation() = Eigen::Vector3d(10, 20, 30);
  a.check.model_px = a.check.agree_px = 1000;
  PipeEstimate slid = a;
  slid.model_to_bin.translation() += ((c[1] - c[0]).normalized() * 3 * d).cast<double>();
  slid.check.agree_px = 970;
  EXPECT_FALSE(read_two_ways(lm, a, slid, cfg));  // both wholly in the view
  a.check.outside_view = 0.3f;
  EXPECT_TRUE(read_two_ways(lm, a, slid, cfg));
  EXPECT_TRUE(read_two_ways(lm, slid, a, cfg));
  slid.check.agree_px = 900;  // beyond ambiguity_quality_margin
  EXPECT_FALSE(read_two_ways(lm, a, slid, cfg));
  PipeEstimate near = a;  // a duplicate: merged, not two readings
  near.model_to_bin.translation() += ((c[1] - c[0]).normalized() * d).cast<double>();
  EXPECT_FALSE(read_two_ways(lm, a, near, cfg));
  const Eigen::Vector3f normal = (c[c.size() / 4] - c[0]).cross(c[3 * c.size() / 4] - c[0]).normalized();
  PipeEstimate beside = a;  // further than duplicates, sharing none of the tube
  beside.model_to_bin.translation() += (3 * d * normal).cast<double>();
  EXPECT_FALSE(read_two_ways(lm, a, beside, cfg));
}

// Beyond the paper: of one pipe's two readings wholly in the view (a bend and its half-turn twin,
// the legs swapped: the tube in one place, the ends a leg's difference apart), the one whose ends
// the image shows worse is refuted; where the ends do not tell, one reaches out of the view, the
// image confirms one clearly better, or the two share less than half of the tube (two pipes end to
// end), neither is.
TEST(PoseDistance, OfTwoReadingsInTheViewTheEndsRefuteTheOneTheyShowWorse) {
  LocateConfig cfg;
  const PipeModel model = pipe_of("S85,B-134r188,S104", 23.3, "bend");
  ASSERT_EQ(model.near_symmetries.size(), 1u);
  const LocatorModel lm = prepare_locator_model(model, 8, cfg);
  PipeEstimate a;
  a.model_to_bin.translation() = Eigen::Vector3d(10, 20, 30);
  a.check.model_px = 1000, a.check.agree_px = 970;
  a.check.ends_pinned = a.check.ends_seen_ending = 2;
  PipeEstimate twin = a;  // agreeing a little better, one end shown
  twin.model_to_bin = a.model_to_bin * model.near_symmetries[0];
  twin.check.agree_px = 980;
  twin.check.ends_pinned = twin.check.ends_seen_ending = 1;
  EXPECT_EQ(reading_its_ends_refute(lm, a, twin, cfg), 1);
  EXPECT_EQ(reading_its_ends_refute(lm, twin, a, cfg), 0);
  twin.check.ends_pinned = twin.check.ends_seen_ending = 2;
  twin.check.ends_continued = 1;  // the tube goes on beyond one end
  EXPECT_EQ(reading_its_ends_refute(lm, a, twin, cfg), 1);
  twin.check.ends_continued = 0;  // the ends do not tell
  EXPECT_EQ(reading_its_ends_refute(lm, a, twin, cfg), -1);
  twin.check.ends_pinned = twin.check.ends_seen_ending = 1;
  twin.check.outside_view = 0.1f;  // what tells them apart may lie out of the view
  EXPECT_EQ(reading_its_ends_refute(lm, a, twin, cfg), -1);
  twin.check.outside_view = 0;
  twin.check.agree_px = 900;  // the image confirms a clearly better: no two readings
  EXPECT_EQ(reading_its_ends_refute(lm, a, twin, cfg), -1);
  twin.check.agree_px = 980;
  PipeEstimate after = twin;  // end to end with a: a pipe of its own
  const auto& c = lm.centreline_points;
  after.model_to_bin.translation() += (a.model_to_bin.linear() * (c.back() - c.front()).cast<double>()) * 0.8;
  EXPECT_EQ(reading_its_ends_refute(lm, a, after, cfg), -1);
  cfg.pin_slides_by_ends = false;  // the ends not read
  EXPECT_EQ(reading_its_ends_refute(lm, a, twin, cfg), -1);
}

// Beyond the paper: of one pipe's two readings by two regions, the one the image confirms clearly
// worse is the one not to pick, whatever its ends show and in or out of the view (an arc read slid
// round itself, one end shown, beside its right reading withheld as sliding: 14-arc of the zoo);
// where the image confirms them about as well, the ends judge (above), and two pipes end to end or
// one pipe's duplicates are no two readings.
TEST(PoseDistance, OfTwoReadingsOfOnePipeTheOneConfirmedClearlyWorseIsNamed) {
  LocateConfig cfg;
  const LocatorModel lm = prepare_locator_model(pipe_of("B120r150", 20, "arc"), 8, cfg);
  const auto& c = lm.centreline_points;
  ASSERT_GE(c.size(), 16u);
  const float d = lm.tube_d_mm;
  PipeEstimate right;
  right.model_to_bin.translation() = Eigen::Vector3d(10, 20, 30);
  right.check.model_px = 1000, right.check.agree_px = 905;
  right.check.ends_pinned = 1, right.check.ends_continued = 1;
  // The arc's centre and normal, from three points of its centreline.
  const Eigen::Vector3d p0 = c.front().cast<double>(), a = c[c.size() / 2].cast<double>() - p0,
                        b = c.back().cast<double>() - p0, n = a.cross(b);
  const Eigen::Vector3d centre =
      p0 + (a.squaredNorm() * b - b.squaredNorm() * a).cross(n) / (2 * n.squaredNorm());
  PipeEstimate slid = right;  // 0.3 rad round the arc's centre: 45 mm along itself, over 2 D
  slid.model_to_bin = right.model_to_bin * Eigen::Translation3d(centre) *
                      Eigen::AngleAxisd(0.3, n.normalized()) * Eigen::Translation3d(-centre);
  slid.check.agree_px = 800;
  slid.check.ends_pinned = slid.check.ends_seen_ending = 1, slid.check.ends_continued = 0;
  EXPECT_EQ(reading_read_worse(lm, right, slid, cfg), 1);
  EXPECT_EQ(reading_read_worse(lm, slid, right, cfg), 0);
  slid.check.outside_view = 0.3f;  // out of the view too
  EXPECT_EQ(reading_read_worse(lm, right, slid, cfg), 1);
  slid.check.agree_px = 900;  // about as well: the ends judge, not this rule
  EXPECT_EQ(reading_read_worse(lm, right, slid, cfg), -1);
  slid.check.agree_px = 800;
  PipeEstimate near = right;  // a duplicate, not a second reading
  near.model_to_bin.translation() += ((c[1] - c[0]).normalized() * 0.5 * d).cast<double>();
  near.check.agree_px = 800;
  EXPECT_EQ(reading_read_worse(lm, right, near, cfg), -1);
  PipeEstimate after = right;  // end to end with it, confirmed clearly worse: a pipe of its own
  after.model_to_bin.translation() +=
      (right.model_to_bin.linear() * (c.back() - c.front()).cast<double>()) * 0.9;
  after.check.agree_px = 800;
  EXPECT_EQ(reading_read_worse(lm, right, after, cfg), -1);
}

// Beyond the paper: the turns judged about a pipe's own length. An elbow that a quarter turn moves
// mostly off itself has three quarter turns about the principal axis of its centreline, which each keep the
// centreline's centroid and axis in place and four of which are no turn; a straight tube (the same pick
// turned) and an arc (placed by its ends along itself) have none. Where a quarter turn lands most of the pipe
// on itself (a short bend hardly bent), its turn is hardly told by where its surface lies: seven eighth
// turns, also for such a bend that slides along itself.
TEST(LocatorModel, TurnsAboutThePipesLengthInEighthsWhereAQuarterLandsItMostlyOnItself) {
  LocateConfig cfg;
  const LocatorModel elbow = prepare_locator_model(pipe_of("S40,B45r20,S30", 10), 8, cfg);
  ASSERT_EQ(elbow.rolls.size(), 3u);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : elbow.centreline_points) centroid += p.cast<double>();
  centroid /= double(elbow.centreline_points.size());
  const double turn[] = {M_PI / 2, M_PI, M_PI / 2};  // a quarter, a half, three quarters (= -1/4)
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_LT((elbow.rolls[k] * centroid - centroid).norm(), 1e-6);
    EXPECT_NEAR(Eigen::AngleAxisd(elbow.rolls[k].linear()).angle(), turn[k], 1e-6);
  }
  EXPECT_TRUE((elbow.rolls[0] * elbow.rolls[2]).matrix().isApprox(Eigen::Matrix4d::Identity(), 1e-9));
  EXPECT_TRUE(prepare_locator_model(pipe_of("S150", 20, "straight"), 8, cfg).rolls.empty());
  EXPECT_TRUE(prepare_locator_model(pipe_of("B180r100", 12), 8, cfg).rolls.empty());
  const LocatorModel short_bend = prepare_locator_model(pipe_of("S5.4,B-45r31.3,S11.3", 10.2), 8, cfg);
  EXPECT_FALSE(short_bend.slides.empty());
  ASSERT_EQ(short_bend.rolls.size(), 7u);
  for (int k = 1; k <= 7; ++k)  // 45 ... 315 degrees: an angle of 45, 90, 135, 180, 135, 90, 45
    EXPECT_NEAR(Eigen::AngleAxisd(short_bend.rolls[std::size_t(k - 1)].linear()).angle(),
                std::min(k, 8 - k) * M_PI / 4, 1e-6);
  const LocatorModel coil =
      prepare_locator_model(pipe_of("B120r55.7,B120r55.7t15.6,B120r55.7t15.6", 22.5), 8, cfg);
  EXPECT_FALSE(coil.slides.empty());
  EXPECT_TRUE(coil.rolls.empty());
}

// IV-B: from the paper's ranges (about the axis up to +-70 degrees, 3 cm along it) the ridge
// ICP with refinement converges on the pipe.
TEST(RidgeIcp, ConvergesFromThePapersRanges) {
  OnePipe s = one_pipe("sbend", 4);
  const PipeModel& model = preset_model("sbend");
  Locator loc(model, s.cfg, s.scene.camera.intrinsics);
  const LocateOutput& out = loc.locate(s.scene.depth_mm, s.scene.camera);
  ASSERT_GE(out.traces.size(), 1u);
  const CandidateTrace& t = out.traces[0];
  ASSERT_GE(t.ridge_count, 10);
  const Pose truth = s.scene.model_to_world[0];
  const Eigen::Vector3d c = truth * model.centroid.cast<double>();
  const Eigen::Vector3d axis(t.axis.axis.x(), t.axis.axis.y(), 0);
  RidgeIcp icp;
  icp.reserve(loc.locator_model(), s.cfg, 2000);
  const Eigen::Vector3f* ridge = &loc.ridge_points()[std::size_t(t.ridge_begin)];
  // The region's points, for the refinement.
  std::vector<Eigen::Vector3f> region;
  const auto& r = loc.regions().candidates[0];
  for (int k = r.cells_begin; k < r.cells_end; ++k) {
    const int cell = loc.regions().region_cells[std::size_t(k)];
    region.push_back(loc.zbuffer().point(cell % loc.zbuffer().z.width, cell / loc.zbuffer().z.width));
  }
  for (const double deg : {-70.0, -35.0, 0.0, 35.0, 70.0}) {
    for (const double shift : {-30.0, 30.0}) {
      const Eigen::AngleAxisd turn(deg * M_PI / 180, axis);
      Pose start = truth;
      start.linear() = turn * truth.linear();
      start.translation() = c + turn * (truth.translation() - c) + axis * shift;
      const RidgeView observed{ridge, t.ridge_count, t.axis.axis, float(s.cfg.ridge_cell_mm)};
      const RidgeFit fit = icp.fit(IcpStart{start}, observed, s.cfg.icp_max_iterations * 2);
      const RefineResult ref =
          refine_on_surface(loc.locator_model(), fit.pose, region.data(), int(region.size()), s.cfg);
      EXPECT_LT(pose_error(model, ref.pose, truth), 5.0) << deg << " deg, " << shift << " mm";
    }
  }
}

// A piece of straight tube seen without its ends fixes neither the slide along its axis nor the
// turn about it: the refinement's normal equations are singular there. It must still correct what
// the points do fix (here a start 1.5 mm too high and tilted) and leave the rest about where it
// started.
TEST(SurfaceRefine, APieceOfStraightTubeWithoutItsEndsStaysPut) {
  const PipeModel model = pipe_of("S400", 20, "straight");
  const LocateConfig cfg;
  const LocatorModel lm = prepare_locator_model(model, 8.0f, cfg);
  const Eigen::Vector3f a0 = lm.centreline_points.front(), a1 = lm.centreline_points.back();
  const Eigen::Vector3f along = (a1 - a0).normalized();
  const Eigen::Vector3f up = along.unitOrthogonal(), side = along.cross(up);
  Pose truth = Pose::Identity();
  truth.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.2, 0.3, 1).normalized()).toRotationMatrix();
  truth.translation() = Eigen::Vector3d(30, -20, 900);
  // The upper half of the tube's surface over its middle 40 %, in the truth's frame.
  std::vector<Eigen::Vector3f> pts;
  const float r = lm.tube_d_mm / 2;
  for (float t = 0.3f; t <= 0.7f; t += 0.005f)
    for (float deg = -80; deg <= 80; deg += 10) {
      const float th = deg * float(M_PI) / 180;
      const Eigen::Vector3f p = a0 + t * (a1 - a0) + r * (std::cos(th) * up + std::sin(th) * side);
      pts.push_back((truth * p.cast<double>()).cast<float>());
    }
  Pose start = truth;
  start.translation() += truth.linear() * (1.5 * up + 10.0 * along).cast<double>();
  start.linear() = truth.linear() * Eigen::AngleAxisd(0.02, side.cast<double>()).toRotationMatrix();
  const RefineResult ref = refine_on_surface(lm, start, pts.data(), int(pts.size()), cfg);
  // Where the refinement put the tube's axis, in the truth's frame.
  const Eigen::Vector3d c = (truth.inverse() * ref.pose * (a0 + 0.5f * (a1 - a0)).cast<double>());
  const Eigen::Vector3d dir = truth.linear().transpose() * ref.pose.linear() * along.cast<double>();
  const Eigen::Vector3d off = c - (a0 + 0.5f * (a1 - a0)).cast<double>();
  const double slide = off.dot(along.cast<double>());
  const double across = (off - slide * along.cast<double>()).norm();
  EXPECT_LT(across, 0.3) << "the height and the side the points fix";
  EXPECT_GT(std::abs(dir.dot(along.cast<double>())), 0.9995) << "the axis' direction the points fix";
  std::printf("slid %.1f mm along the axis (started 10 mm off), %.2f mm across\n", slide, across);
  // Measured: 25.9 mm along (the model's surface samples lean a little), 0.05 across; undamped,
  // 2753 mm along and 54 across.
  EXPECT_LT(std::abs(slide - 10.0), 0.1 * lm.extent_l_mm) << "the slide the points do not fix";
  EXPECT_LT(ref.rms_mm, 0.3f);
}

// A thin elbow lying flat on the floor, seen from 0.7 m above: the sensor reads the tube's upper
// surface and, just beside it, the floor, within the inlier distance of the tube's underside.
// Paired with the nearest surface, those floor readings pull the tube down onto them; paired only
// with surface the camera can see, they do not.
TEST(SurfaceRefine, FloorReadingsBesideAThinTubeDoNotPullItDown) {
  const PipeModel model = pipe_of("S12,B45r25,S6", 8.4);
  const LocateConfig cfg;
  const LocatorModel lm = prepare_locator_model(model, 8.0f, cfg);
  ASSERT_TRUE(lm.slides.empty());
  const float r = lm.tube_d_mm / 2;
  // The bend lies in the model's xy plane; the truth puts it flat on the floor (z = 0, bin frame).
  Pose truth = Pose::Identity();
  truth.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  truth.translation() = Eigen::Vector3d(20, -10, r);
  const Eigen::Vector3f camera(0, 0, 700);
  std::vector<Eigen::Vector3f> pts;
  const std::vector<Eigen::Vector3f>& line = lm.centreline_points;
  for (std::size_t i = 0; i + 1 < line.size(); ++i) {
    const Eigen::Vector3f a = line[i], b = line[i + 1], along = (b - a).normalized();
    const Eigen::Vector3f side = along.cross(Eigen::Vector3f::UnitZ()).normalized();
    for (float t = 0; t < (b - a).norm(); t += 0.5f) {
      // The tube's surface the camera sees, every 10 degrees round ...
      for (int deg = 0; deg < 360; deg += 10) {
        const float th = float(deg) * float(M_PI) / 180;
        const Eigen::Vector3f n = std::cos(th) * Eigen::Vector3f::UnitZ() + std::sin(th) * side;
        const Eigen::Vector3f p = (truth * (a + t * along + r * n).cast<double>()).cast<float>();
        const Eigen::Vector3f nb = (truth.linear() * n.cast<double>()).cast<float>();
        if (nb.dot((camera - p).normalized()) > 0.05f) pts.push_back(p);
      }
      // ... and the floor 0.5-2 mm beyond its silhouette on both sides.
      for (float off = r + 0.5f; off <= r + 2.0f; off += 0.5f)
        for (const float sgn : {-1.0f, 1.0f}) {
          Eigen::Vector3f p = (truth * (a + t * along + sgn * off * side).cast<double>()).cast<float>();
          p.z() = 0;
          pts.push_back(p);
        }
    }
  }
  const auto height_mm = [&](const Pose& p) {
    return float((p * lm.centroid.cast<double>()).z() - (truth * lm.centroid.cast<double>()).z());
  };
  const RefineResult facing = refine_on_surface(lm, truth, pts.data(), int(pts.size()), cfg, camera);
  const RefineResult nearest = refine_on_surface(lm, truth, pts.data(), int(pts.size()), cfg);
  std::printf(
      "refined from the truth: facing the camera %.2f mm off (height %+.2f), nearest surface %.2f mm off "
      "(height %+.2f)\n",
      pose_distance_mm(lm, facing.pose, truth), height_mm(facing.pose),
      pose_distance_mm(lm, nearest.pose, truth), height_mm(nearest.pose));
  // Measured: facing 3.55 mm off, height -0.12 mm; nearest 2.88 mm off, height -0.74 mm (the
  // rest is the turn about the length the top of a short bend hardly fixes).
  EXPECT_LT(std::abs(height_mm(facing.pose)), 0.3f);
  EXPECT_LT(height_mm(nearest.pose), -0.5f) << "the floor readings pull the nearest-surface fit down";
}

// A thin bend on the floor read at a metre with the noise of the zoo's stereo sensor there (2.8 mm
// along each ray, more than half the tube's radius). Paired with the nearest surface sample, a point
// read deeper than the tube's side pairs further down the side and one read nearer further up, and
// the second lies further off the surface than the first: the fit sits nearer the camera. Paired
// where its ray meets the tube, a point lies before or behind its partner by its noise alone.
TEST(SurfaceRefine, AThinTubesNoiseAlongTheRaysDoesNotLiftIt) {
  const PipeModel model = pipe_of("S40,B90r30,S40", 9.0);
  LocateConfig rays;
  rays.refine_ray_pairs = true;
  LocateConfig nearest = rays;
  nearest.refine_ray_pairs = false;
  const LocatorModel lm = prepare_locator_model(model, 8.0f, rays);
  ASSERT_TRUE(lm.slides.empty());
  // Each sample knows the tube's direction there, square to its normal (an end cap's face aside).
  ASSERT_EQ(lm.sample_directions.size(), lm.samples.size());
  std::size_t directed = 0;
  for (std::size_t i = 0; i < lm.samples.size(); ++i) {
    const Eigen::Vector3f& dir = lm.sample_directions[i];
    if (dir.isZero()) continue;
    ++directed;
    EXPECT_NEAR(dir.norm(), 1.0f, 1e-4f);
    EXPECT_NEAR(dir.dot(lm.samples[i].n), 0.0f, 1e-4f);
  }
  EXPECT_GT(directed, lm.samples.size() * 9 / 10);
  Pose truth = Pose::Identity();
  truth.linear() = Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  truth.translation() = Eigen::Vector3d(30, 20, lm.tube_d_mm / 2);
  const Eigen::Vector3f camera(0, 0, 1000);
  std::mt19937 rng(11);
  std::normal_distribution<float> noise(0.0f, 2.8f);
  std::vector<Eigen::Vector3f> pts;
  for (int draw = 0; draw < 3; ++draw)
    for (const auto& smp : lm.samples) {
      const Eigen::Vector3f p = (truth * smp.p.cast<double>()).cast<float>();
      const Eigen::Vector3f n = (truth.linear() * smp.n.cast<double>()).cast<float>();
      const Eigen::Vector3f ray = (p - camera).normalized();
      if (-n.dot(ray) > 0.05f) pts.push_back(p + noise(rng) * ray);
    }
  ASSERT_GT(pts.size(), 500u);
  // How far the fit's centroid lies above the truth's, towards the camera.
  const auto lift_mm = [&](const LocateConfig& cfg) {
    const RefineResult ref = refine_on_surface(lm, truth, pts.data(), int(pts.size()), cfg, camera);
    return float((ref.pose * lm.centroid.cast<double>()).z() - (truth * lm.centroid.cast<double>()).z());
  };
  const float by_rays = lift_mm(rays), by_nearest = lift_mm(nearest);
  std::printf("refined from the truth: lifted %+.2f mm paired along the rays, %+.2f mm with the nearest\n",
              by_rays, by_nearest);
  // Measured: +0.19 mm along the rays in the refinement's last six iterations (+0.08 in all of
  // them, +0.46 in the last three), +1.66 mm with the nearest.
  EXPECT_LT(std::abs(by_rays), 0.25f);
  EXPECT_GT(by_nearest, 0.4f) << "the nearest samples lift a thin tube's fit";
}

// Where the points fix a motion poorly (here a piece of a bend's top: its turn about the bend's
// centre), the normal equations are near singular: undamped, a step of a start 2 mm off moved the
// pose metres (a torus-like ring of the dev set: 58 such steps in one frame). Paired with the
// nearest samples the piece stays within 10 mm; paired along the rays (refine_ray_pairs), where each
// partner lies on a straight cylinder round its sample, nothing holds the piece of the ring where
// it lies along the ring, and it drifts along it by up to some 20 mm (measured 9.4 paired so in
// the refinement's last six iterations, 22.2 in all of them): the damping keeps that to tens of
// millimetres, and the image's judgement of the pose does the rest (docs/experiments.md, "Points
// paired along the camera's rays").
TEST(SurfaceRefine, APieceOfABendRefinedFromNearItsPoseStaysNear) {
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  for (const char* path : {"S20,B200r45,S20", "S30,B120r45t90,B90r45t90,S30"}) {
    const PipeModel model = pipe_of(path, 16);
    LocateConfig nearest;
    nearest.refine_ray_pairs = false;
    LocateConfig rays = nearest;
    rays.refine_ray_pairs = true;
    const LocatorModel lm = prepare_locator_model(model, 8.0f, rays);
    ASSERT_TRUE(lm.slides.empty()) << path;
    Pose truth = Pose::Identity();
    truth.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.1, 0.2, 1).normalized()).toRotationMatrix();
    truth.translation() = Eigen::Vector3d(-40, 25, 30);
    const Eigen::Vector3f camera(0, 0, 1000);
    // The surface the camera sees within 25 mm of the middle of the centreline, 1 mm noise.
    const Eigen::Vector3f middle = lm.centreline_points[lm.centreline_points.size() / 2];
    std::vector<Eigen::Vector3f> pts;
    for (const auto& smp : lm.samples) {
      if ((smp.p - middle).norm() > 25) continue;
      const Eigen::Vector3f p = (truth * smp.p.cast<double>()).cast<float>();
      const Eigen::Vector3f n = (truth.linear() * smp.n.cast<double>()).cast<float>();
      if (n.dot((camera - p).normalized()) > 0.1f) pts.push_back(p + Eigen::Vector3f(0, 0, noise(rng)));
    }
    ASSERT_GT(pts.size(), 50u) << path;
    for (const Eigen::Vector3d& shift : {Eigen::Vector3d(2, 0, 0), Eigen::Vector3d(0, -2, 1)}) {
      Pose start = truth;
      start.translation() += shift;
      const RefineResult ref = refine_on_surface(lm, start, pts.data(), int(pts.size()), nearest, camera);
      const RefineResult by_rays = refine_on_surface(lm, start, pts.data(), int(pts.size()), rays, camera);
      std::printf("%s, start %.1f mm off: refined %.1f mm off (%.1f along the rays)\n", path,
                  pose_distance_mm(lm, start, truth), pose_distance_mm(lm, ref.pose, truth),
                  pose_distance_mm(lm, by_rays.pose, truth));
      EXPECT_LT(pose_distance_mm(lm, ref.pose, truth), 10.0f) << path << " " << shift.transpose();
      EXPECT_LT(pose_distance_mm(lm, by_rays.pose, truth), 40.0f) << path << " " << shift.transpose();
    }
  }
}

// Beyond the paper: a start placed beside the pipe (one leg of the U onto the other) or along it
// is slid back over the observed ridge before ICP. The observed ridge here is a start's own ridge
// placed by a known axis frame; the slide must find that frame again from shifted ones.
TEST(StartSlide, BringsAnOffsetStartBackOverTheObservedRidge) {
  const PipeModel& model = preset_model("u");
  LocateConfig cfg;
  const LocatorModel lm = prepare_locator_model(model, 8.0f, cfg);
  const StartSet starts = prepare_starts(lm, cfg);
  ASSERT_EQ(starts.size(), 2 * cfg.initial_rotations * 6);  // 2 directions x 6 turns x 6 yaws (30 deg)
  ASSERT_GT(lm.slide_across_mm, 2 * lm.tube_d_mm);          // a U is wider than two tubes
  SlideBuffers buf;
  reserve_slide(&buf, lm, 2000, float(cfg.ridge_cell_mm));
  const float d = lm.tube_d_mm;
  Pose truth_frame = Pose::Identity();
  truth_frame.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  truth_frame.translation() = Eigen::Vector3d(120, -40, 900);
  const int s = 0;  // lying flat, not reversed, no yaw offset
  std::vector<Eigen::Vector3f> observed, in_axis;
  const Pose placed = truth_frame * starts.pose[s];
  for (int i = 0; i < starts.ridge_count(s); ++i)
    observed.push_back((placed * starts.ridge(s)[i].cast<double>()).cast<float>());
  ASSERT_GE(observed.size(), 10u);
  buf.observed_top.build(observed.data(), int(observed.size()), starts.cell_mm, d);
  const float widest = std::floor(lm.slide_across_mm / d) * d;  // the furthest step across it takes
  const Eigen::Vector3d along = truth_frame.linear().col(0), across = truth_frame.linear().col(1);
  for (const Eigen::Vector3d& offset :
       {Eigen::Vector3d(across * widest), Eigen::Vector3d(-across * 2 * d), Eigen::Vector3d(along * 2 * d),
        Eigen::Vector3d(-along * 2 * d + across * d)}) {
    Pose frame = truth_frame;
    frame.translation() += offset;  // the measured centre is off by `offset`
    in_axis.clear();
    for (const auto& p : observed) in_axis.push_back((frame.inverse() * p.cast<double>()).cast<float>());
    const SlidStart slid =
        slide_start(lm, starts, s, frame, in_axis.data(), int(in_axis.size()), cfg, &buf, lm.slide_along_mm);
    EXPECT_LT((slid.pose.translation() - placed.translation()).norm(), 0.5 * d) << offset.transpose();
    EXPECT_LT(slid.cost_mm, 0.25f * d) << offset.transpose();
  }
}

// A region reaching the image's edge holds part of a pipe whose centre may lie far along it (07-U
// of the zoo: a leg and half the bend in view). The starts slide along L/4 either way; an offset a
// step beyond it is brought back only when they may slide L/2 (edge_slide_along_of_l).
TEST(StartSlide, FurtherAlongTheAxisWhereTheRidgeReachesTheEdge) {
  const PipeModel& model = preset_model("u");
  LocateConfig cfg;
  const LocatorModel lm = prepare_locator_model(model, 8.0f, cfg);
  const StartSet starts = prepare_starts(lm, cfg);
  SlideBuffers buf;
  reserve_slide(&buf, lm, 2000, float(cfg.ridge_cell_mm));
  const float d = lm.tube_d_mm;
  Pose truth_frame = Pose::Identity();
  truth_frame.translation() = Eigen::Vector3d(-60, 30, 900);
  const int s = 0;
  std::vector<Eigen::Vector3f> observed, in_axis;
  const Pose placed = truth_frame * starts.pose[s];
  for (int i = 0; i < starts.ridge_count(s); ++i)
    observed.push_back((placed * starts.ridge(s)[i].cast<double>()).cast<float>());
  buf.observed_top.build(observed.data(), int(observed.size()), starts.cell_mm, d);
  // One step of the slide's grid (2 D along) beyond the L/4 it reaches.
  const float step = std::max(float(cfg.start_slide_step_of_d) * d, float(cfg.zbuffer_pixel_mm));
  const double offset = (int(lm.slide_along_mm / (2 * step)) + 1) * 2.0 * step;
  ASSERT_LE(offset, cfg.edge_slide_along_of_l * lm.extent_l_mm);
  Pose frame = truth_frame;
  frame.translation() += truth_frame.linear().col(0) * offset;
  for (const auto& p : observed) in_axis.push_back((frame.inverse() * p.cast<double>()).cast<float>());
  const auto off_mm = [&](float along_mm) {
    const SlidStart slid =
        slide_start(lm, starts, s, frame, in_axis.data(), int(in_axis.size()), cfg, &buf, along_mm);
    return (slid.pose.translation() - placed.translation()).norm();
  };
  const double quarter = off_mm(lm.slide_along_mm),
               half = off_mm(float(cfg.edge_slide_along_of_l) * lm.extent_l_mm);
  std::printf("%.0f mm off along the axis: slid L/4 %.0f mm off, L/2 %.0f mm off\n", offset, quarter, half);
  EXPECT_GT(quarter, d);
  EXPECT_LT(half, 0.5 * d);
}

TEST(StartSlide, TopDistanceIsTheHorizontalDistanceUpToItsCap) {
  TopDistance td;
  td.reserve(64);
  const Eigen::Vector3f pts[] = {{0, 0, 5}, {10, 0, 50}};
  td.build(pts, 2, 1.0f, 20.0f);
  EXPECT_NEAR(td.at(5, 0), 5.0f, 0.8f);  // between the two, heights aside
  EXPECT_NEAR(td.at(10, 6), 6.0f, 0.8f);
  EXPECT_FLOAT_EQ(td.at(0, 30), 20.0f);   // beyond the cap
  EXPECT_FLOAT_EQ(td.at(500, 0), 20.0f);  // outside the grid
}

TEST(StartSlide, SeenThroughCountsOnlyPointsAboveAReadingDeeperThanTheTolerance) {
  ZBuffer zb = synthetic_zbuffer(40, [](double i, double) { return i < 20 ? 0.0 : ZBuffer::kEmpty; });
  const Eigen::Vector3f pts[] = {{5, 5, 10},    // 10 mm over the floor: seen through
                                 {6, 5, 5},     // within the tolerance
                                 {7, 5, -3},    // under the surface: hidden, not seen through
                                 {30, 5, 10}};  // no reading there: says nothing
  EXPECT_FLOAT_EQ(seen_through_share(zb, pts, 4, 7.0f), 0.25f);
}

}  // namespace
}  // namespace pipeloc
