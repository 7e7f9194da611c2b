// Verification that knows the bin: no pose below the floor, and a smooth blob is not a pipe.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "locate/candidate.hpp"
#include "locate/locator.hpp"
#include "model/make_pipe.hpp"
#include "model/pipe_model.hpp"
#include "sim/scene.hpp"
#include "sim/sensor.hpp"
#include "locate_fixtures.hpp"

namespace pipeloc {
namespace {

constexpr double kCameraHeightMm = 900;
constexpr double kTubeMm = 20;

// A camera straight above the origin of a floor at z = 0, and a straight tube of tube_mm along the
// world x axis with its axis at height axis_z_mm; `surround_z_mm` is the height of the flat
// surface beside it (the floor: 0; a blob's flank: the axis height, so that nothing drops away).
struct Scene {
  CameraInfo camera;
  Image<float> depth;
};
Scene straight_tube_scene(double axis_z_mm, double surround_z_mm, double tube_mm = kTubeMm) {
  Scene s;
  const Intrinsics& k = s.camera.intrinsics;
  Pose w2c = Pose::Identity();
  w2c.linear() = Eigen::Vector3d(1, -1, -1).asDiagonal();
  w2c.translation() = Eigen::Vector3d(0, 0, kCameraHeightMm);
  s.camera.world_to_cam = w2c;
  s.depth.resize(k.width, k.height, 0.0f);
  const double r = tube_mm / 2, half_length = 75;
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);  // an active-stereo sensor's axial noise at 0.9 m
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      // The ray in the world frame from the camera at (0, 0, H); its camera depth is the parameter t.
      const Eigen::Vector3d d((u - k.cx) / k.fx, -(v - k.cy) / k.fy, -1.0);
      // The flat surface beside the tube, 2.5 D either side of it; the floor beyond.
      double t = kCameraHeightMm - surround_z_mm;
      if (std::abs(t * d.y()) > 2.5 * tube_mm || std::abs(t * d.x()) > half_length) t = kCameraHeightMm;
      // The tube: (y(t))^2 + (z(t) - axis_z)^2 = r^2.
      const double oz = kCameraHeightMm - axis_z_mm;
      const double a = d.y() * d.y() + d.z() * d.z(), b = 2 * oz * d.z(), c = oz * oz - r * r;
      const double disc = b * b - 4 * a * c;
      if (disc >= 0) {
        const double hit = (-b - std::sqrt(disc)) / (2 * a);
        if (hit > 0 && std::abs(hit * d.x()) <= half_length) t = std::min(t, hit);
      }
      s.depth.at(u, v) = float(t + noise(rng));
    }
  return s;
}

PipeModel straight_tube(double tube_mm = kTubeMm) { return pipe_of("S150", tube_mm, "straight"); }

// The model drawn at the true pose: its sides drop away on the floor, and stay level on a blob
// whose flanks go on from its silhouette (decide() rejects a pose over 0.3 level: test_decide).
TEST(BinAwareVerification, APipesSidesDropAwayASmoothBlobsDoNot) {
  const LocatorModel lm = prepare_locator_model(straight_tube(), 8, LocateConfig{});
  const auto verify_at = [&](const Scene& s, double axis_z_mm) {
    // The model's frame: the tube from x = 0 to 150 along its x axis (make_pipe), centred here.
    Pose m2w = Pose::Identity();
    m2w.translation() = Eigen::Vector3d(-75, 0, axis_z_mm);
    const Pose m2c = *s.camera.world_to_cam * m2w;
    Image<float> scratch(s.camera.intrinsics.width, s.camera.intrinsics.height, 0.0f);
    ProjectedMesh projected;
    projected.reserve(lm.verify_mesh);
    return verify_pose(lm.verify_mesh, lm.verify_winding, m2c, s.depth, s.camera.intrinsics, 7.0f,
                       0.25f * float(kTubeMm), 0, &scratch, &projected);
  };
  const Verification on_floor = verify_at(straight_tube_scene(kTubeMm / 2, 0), kTubeMm / 2);
  EXPECT_GT(on_floor.agreement(), 0.9);
  EXPECT_GE(on_floor.side_px, kMinSidePx);
  EXPECT_LT(on_floor.side_level(), 0.1);
  // The blob: flanks a fifth of the tube above its axis, going on level from its silhouette.
  const Verification blob = verify_at(straight_tube_scene(kTubeMm / 2, 0.7 * kTubeMm), kTubeMm / 2);
  EXPECT_GT(blob.agreement(), 0.9);  // the top alone fits as well as a pipe's
  EXPECT_GE(blob.side_px, kMinSidePx);
  EXPECT_GT(blob.side_level(), LocateConfig{}.verify_max_side_level);
}

// The straight tube of straight_tube_scene() lying on the floor, and verify_pose() of the model
// moved along world X by x_mm (the tube from x_mm to x_mm + 150) and across by y_mm.
struct TubeOnFloor {
  LocatorModel lm = prepare_locator_model(straight_tube(), 8, LocateConfig{});
  Scene s = straight_tube_scene(kTubeMm / 2, 0);
  Image<float> scratch{s.camera.intrinsics.width, s.camera.intrinsics.height, 0.0f};
  ProjectedMesh projected;
  TubeOnFloor() { projected.reserve(lm.verify_mesh); }
  Verification at(double x_mm, double y_mm = 0, bool look_for_holes = false, const PixelBox* view = nullptr) {
    Pose m2w = Pose::Identity();
    m2w.translation() = Eigen::Vector3d(x_mm, y_mm, kTubeMm / 2);
    const Pose m2c = *s.camera.world_to_cam * m2w;
    const Intrinsics& k = s.camera.intrinsics;
    return verify_pose(lm.verify_mesh, lm.verify_winding, m2c, s.depth, k, 7.0f, 0.25f * float(kTubeMm), 0,
                       &scratch, &projected, look_for_holes ? hole_side_px(lm, k, m2c) : 0, view);
  }
};

// A pose reaching out of the view: the image checks nothing of the part outside it, which
// verify_pose() gives as the share of the model's vertices outside the image (decide() counts it
// as unseen, like the part under another pipe).
TEST(BinAwareVerification, APoseReachingOutOfTheViewSaysHowMuch) {
  TubeOnFloor t;
  const Intrinsics& k = t.s.camera.intrinsics;
  // The image's right edge on the floor, 900 mm below the camera.
  const double edge_mm = (k.width - 1 - k.cx) / k.fx * kCameraHeightMm;
  EXPECT_EQ(t.at(-75).outside_view, 0.0f);
  EXPECT_NEAR(t.at(edge_mm - 75).outside_view, 0.5, 0.1);
  EXPECT_EQ(t.at(edge_mm + 10).outside_view, 1.0f);  // nearer than the floor, the tube projects farther out
}

// An active sensor reads nothing in a band at the left of its image, where its projector (or its
// second imager) does not see the floor: f b / z wide, b the baseline. read_view() finds it on the
// simulator's frames of both sensors.
TEST(BinAwareVerification, TheViewLeavesOutTheSensorsDeadBand) {
  const PipeModel model = straight_tube();
  for (const char* sensor : {"kinect", "stereo"}) {
    SCOPED_TRACE(sensor);
    std::mt19937 rng(3);
    SceneParams p;
    p.pile.pipes = 8;
    p.sensor = sensor_model(sensor);
    p.camera_height_min_mm = p.camera_height_max_mm = 800;
    const SimulatedScene s = simulate_scene(model, p, rng);
    const Intrinsics& k = s.camera.intrinsics;
    std::vector<int> col_reads, row_reads;
    const PixelBox view = read_view(s.depth_mm, &col_reads, &row_reads);
    const double band_px = k.fx * p.sensor.baseline_mm / 800;
    EXPECT_NEAR(view.x0, band_px, 0.2 * band_px);
    EXPECT_GT(view.x1, k.width / 2);  // (beyond the simulated bin nothing is drawn, nothing read)
    EXPECT_EQ(view.y0, 0);
    EXPECT_GT(view.y1, k.height / 2);
  }
}

// A pose half in such a band: judged on the whole image, the half without readings counts as
// not confirmed (agreement about 0.5, and the pipe would be refused); judged in the view, that
// half is out of the view, as beyond the image's edge, and what is in view agrees.
TEST(BinAwareVerification, APoseInTheDeadBandIsOutOfTheViewNotDisagreeing) {
  TubeOnFloor t;
  const Intrinsics& k = t.s.camera.intrinsics;
  const int band = int(k.cx);  // the tube from x = -75 to 75 mm lies half left of the centre column
  for (int y = 0; y < k.height; ++y)
    for (int x = 0; x < band; ++x) t.s.depth.at(x, y) = 0;
  std::vector<int> col_reads, row_reads;
  const PixelBox view = read_view(t.s.depth, &col_reads, &row_reads);
  EXPECT_EQ(view.x0, band);
  const Verification whole = t.at(-75);
  EXPECT_LT(whole.agreement(), 0.6);
  EXPECT_EQ(whole.outside_view, 0.0f);
  const Verification in_view = t.at(-75, 0, false, &view);
  EXPECT_GT(in_view.agreement(), 0.9);
  EXPECT_NEAR(in_view.outside_view, 0.5, 0.1);
}

// A pose slid 0.3 D past its pipe's end sees the floor through fewer of its pixels than the
// free-space check allows, but all of them in one place: a square a quarter of the tube wide is
// seen through entirely. The true pose and one D/8 to the side (a right pose, refined) see
// through no such square.
TEST(BinAwareVerification, APoseOverhangingItsPipeSeesThroughASquare) {
  TubeOnFloor t;
  EXPECT_FALSE(t.at(-75, 0, true).seen_through_patch);
  EXPECT_FALSE(t.at(-75, kTubeMm / 8, true).seen_through_patch);
  const Verification slid = t.at(-75 + 0.3 * kTubeMm, 0, true);
  EXPECT_LT(slid.inner_free_space(), LocateConfig{}.verify_max_free_space);
  EXPECT_TRUE(slid.seen_through_patch);
}

// A refined pose lies up to a band's width (D/8) to the side of its pipe. The sides are read
// beyond that band: a 40 mm tube 0.9 m away is 25 pixels wide, its band 3 pixels; moved D/8
// across, the sides two pixels beyond its rim would fall on the pipe itself on one side.
TEST(BinAwareVerification, ASidelongPoseReadsItsSidesBeyondItsOwnPipe) {
  const double tube_mm = 40;
  const LocateConfig cfg;
  const LocatorModel lm = prepare_locator_model(straight_tube(tube_mm), 8, cfg);
  const Scene s = straight_tube_scene(tube_mm / 2, 0, tube_mm);
  Pose m2w = Pose::Identity();
  m2w.translation() = Eigen::Vector3d(-75, tube_mm / 8, tube_mm / 2);  // D/8 across
  const Pose m2c = *s.camera.world_to_cam * m2w;
  Image<float> scratch(s.camera.intrinsics.width, s.camera.intrinsics.height, 0.0f);
  ProjectedMesh projected;
  projected.reserve(lm.verify_mesh);
  const int band = free_space_band_px(cfg, lm, s.camera.intrinsics, m2c);
  EXPECT_EQ(band, 3);
  const auto side_level = [&](int b) {
    return verify_pose(lm.verify_mesh, lm.verify_winding, m2c, s.depth, s.camera.intrinsics, 7.0f,
                       float(cfg.side_drop_of_d * tube_mm), b, &scratch, &projected)
        .side_level();
  };
  EXPECT_LT(side_level(band), 0.1);
  EXPECT_GT(side_level(0), 0.3);  // read two pixels beyond the rim: half one side is the pipe
}

// Thin tubes (10 mm, 6 pixels wide at 0.8 m) on a pile seen by the active-stereo sensor, which
// blends fore- and background at depth edges: at their true poses the pixels next to the rim
// see through the model. Judged inside the band, the true poses pass the free-space check;
// moved across by a diameter they see through most of themselves, as with the rim alone (unless
// they land on the neighbouring pipe).
TEST(BinAwareVerification, FreeSpaceIsJudgedInsideTheRimBand) {
  const double tube_mm = 10;
  const LocateConfig cfg;
  const PipeModel model = straight_tube(tube_mm);
  const LocatorModel lm = prepare_locator_model(model, 8, cfg);
  std::mt19937 rng(11);
  SceneParams p;
  p.pile.pipes = 12;
  p.sensor = sensor_model("stereo");
  p.camera_height_min_mm = p.camera_height_max_mm = 800;
  const SimulatedScene s = simulate_scene(model, p, rng);
  Image<float> scratch(s.camera.intrinsics.width, s.camera.intrinsics.height, 0.0f);
  ProjectedMesh projected;
  projected.reserve(lm.verify_mesh);
  const auto free_space = [&](const Pose& m2c, int band) {
    return verify_pose(lm.verify_mesh, lm.verify_winding, m2c, s.depth_mm, s.camera.intrinsics,
                       float(cfg.verify_tolerance_mm), float(cfg.side_drop_of_d) * float(tube_mm), band,
                       &scratch, &projected)
        .inner_free_space();
  };
  int top = 0, pass_rim_only = 0, pass_banded = 0, off_rejected = 0, off_rejected_rim_only = 0;
  for (std::size_t g = 0; g < s.info.size(); ++g) {
    if (!s.info[g].top) continue;
    ++top;
    // A right pick an eighth of a diameter to the side, as the refinement leaves it.
    Pose m2c = s.model_to_cam(g);
    m2c.translation() += m2c.linear() * Eigen::Vector3d(0, tube_mm / 8, 0);
    const int band = free_space_band_px(cfg, lm, s.camera.intrinsics, m2c);
    EXPECT_EQ(band, 1);
    pass_rim_only += free_space(m2c, 0) <= cfg.verify_max_free_space;
    pass_banded += free_space(m2c, band) <= cfg.verify_max_free_space;
    Pose off = s.model_to_cam(g);  // a diameter across the tube
    off.translation() += m2c.linear() * Eigen::Vector3d(0, tube_mm, 0);
    off_rejected += free_space(off, band) > cfg.verify_max_free_space;
    off_rejected_rim_only += free_space(off, 0) > cfg.verify_max_free_space;
  }
  ASSERT_GE(top, 5);
  EXPECT_EQ(pass_banded, top);
  EXPECT_LT(pass_rim_only, top);
  EXPECT_GE(off_rejected, top - 1);
  EXPECT_EQ(off_rejected, off_rejected_rim_only);
}

// An arc slides along itself: away from its ends the slid pose shows the same surface. Lying
// alone on the floor, at its true pose both ends are pinned (the floor lies lower beyond them);
// slid along itself, the tube goes on beyond the end that withdrew; with no reading around its
// ends (out of view, a dropout) nothing pins it, and decide() marks such a pose ambiguous.
TEST(BinAwareVerification, AnArcIsPlacedAlongItselfOnlyByAnEndTheImageShows) {
  const LocateConfig cfg;
  const PipeModel model = pipe_of("B200r80", 16, "arc");
  const LocatorModel lm = prepare_locator_model(model, 8, cfg);
  ASSERT_FALSE(lm.slides.empty());
  std::mt19937 rng(3);
  SceneParams p;
  p.pile.pipes = 1;
  p.camera_height_min_mm = p.camera_height_max_mm = 800;
  SimulatedScene s = simulate_scene(model, p, rng);
  const float d = model.tube_diameter_mm, tol = float(cfg.verify_tolerance_mm);
  const auto ends = [&](const Pose& m2c, const Image<float>& depth) {
    Verification v;
    judge_ends(lm.centreline_points, d, m2c, depth, s.camera.intrinsics, tol, &v);
    return v;
  };
  const Verification truth = ends(s.model_to_cam(0), s.depth_mm);
  EXPECT_EQ(truth.ends_pinned, 2);
  EXPECT_EQ(truth.ends_continued, 0);
  for (const Pose& slide : lm.slides) {
    const Verification slid = ends(s.model_to_cam(0) * slide, s.depth_mm);
    EXPECT_GE(slid.ends_continued, 1);
  }
  // No reading within 2 D of either end of the tube.
  Image<float> hidden = s.depth_mm;
  for (const Eigen::Vector3f& end : {lm.centreline_points.front(), lm.centreline_points.back()}) {
    const Eigen::Vector3d c = s.model_to_cam(0) * end.cast<double>();
    const Eigen::Vector2d px = s.camera.intrinsics.project(c);
    const double r_px = 2 * d * s.camera.intrinsics.fx / c.z();
    for (int y = 0; y < hidden.height; ++y)
      for (int x = 0; x < hidden.width; ++x)
        if ((Eigen::Vector2d(x, y) - px).norm() < r_px) hidden.at(x, y) = 0;
  }
  const Verification unseen = ends(s.model_to_cam(0), hidden);
  EXPECT_EQ(unseen.ends_pinned, 0);
  EXPECT_EQ(unseen.ends_continued, 0);
}

// The straight tube on the floor, its ends read by judge_ends() at the true pose and at poses
// slid along it. Slid less far than the first probe beyond an end reaches, both poses are read
// beyond the same ends of the pipe: each has both ends pinned, so the ends do not tell them apart,
// and ends_tell_apart() says so; ends_shared() counts both ends shared. Slid further, the tube goes
// on beyond one end of the slid pose; slid on by nearly its length, one end is shared.
TEST(BinAwareVerification, EndsTellPosesApartOnlyWhereTheyLieBeyondTheFirstProbe) {
  TubeOnFloor tube;
  const std::vector<Eigen::Vector3f>& line = tube.lm.centreline_points;
  const float d = float(kTubeMm), tol = 7.0f;
  const auto pose_at = [&](double x_mm) {
    Pose m2w = Pose::Identity();
    m2w.translation() = Eigen::Vector3d(x_mm, 0, kTubeMm / 2);
    return Pose(*tube.s.camera.world_to_cam * m2w);
  };
  const auto ends = [&](const Pose& m2c) {
    Verification v;
    judge_ends(line, d, m2c, tube.s.depth, tube.s.camera.intrinsics, tol, &v);
    return v;
  };
  const Pose truth = pose_at(-75);
  EXPECT_EQ(ends(truth).ends_pinned, 2);
  for (const double slid_of_d : {0.3, 0.5}) {
    SCOPED_TRACE(slid_of_d);
    const Pose slid = pose_at(-75 + slid_of_d * kTubeMm);
    EXPECT_EQ(ends(slid).ends_pinned, 2);
    EXPECT_EQ(ends(slid).ends_continued, 0);
    EXPECT_FALSE(ends_tell_apart(line, d, truth, slid));
    EXPECT_EQ(ends_shared(line, d, truth, slid), 2);
  }
  const Pose far_slid = pose_at(-75 + 1.2 * kTubeMm);
  EXPECT_EQ(ends(far_slid).ends_continued, 1);
  EXPECT_TRUE(ends_tell_apart(line, d, truth, far_slid));
  EXPECT_EQ(ends_shared(line, d, truth, far_slid), 0);
  // Slid on by nearly its length, one end lies where the other was: one end shared.
  const double length = (line.back() - line.front()).norm();
  EXPECT_EQ(ends_shared(line, d, truth, pose_at(-75 + length - 0.3 * kTubeMm)), 1);
  // Turned end for end about its middle, the tube's ends lie where they were: nothing to tell.
  Pose turned = truth;
  turned = truth * Eigen::Translation3d(75, 0, 0) * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()) *
           Eigen::Translation3d(-75, 0, 0);
  EXPECT_FALSE(ends_tell_apart(line, d, truth, turned));
  EXPECT_EQ(ends_shared(line, d, truth, turned), 2);
}

// A raised end casts the sensor's shadow on the floor beyond it. Where the first probe beyond the
// tip (0.75 D) falls in it and the second (1.25 D) reads the floor, the end is pinned but not seen
// ending outright; a pose slid a quarter of D past the end, over the shadow, reads both its probes
// on the floor and shows that end ending outright. judge_ends() counts the true end apart, as seen
// ending but for the shadow (place_slides_finely moves a pose back to it: an arc was handed out
// 19 mm past its end so, 14-arc of a held-out zoo, tools/zoo --seed 20).
TEST(BinAwareVerification, AnEndBesideTheSensorsShadowIsSeenEndingButForIt) {
  TubeOnFloor tube;
  const Intrinsics& k = tube.s.camera.intrinsics;
  const Pose& w2c = *tube.s.camera.world_to_cam;
  const std::vector<Eigen::Vector3f>& line = tube.lm.centreline_points;
  // The shadow: nothing read from 0.5 to 1.0 D beyond the tip (the centreline's last point, 7 mm
  // inside the tube's end at x = 75 mm), across the tube's line.
  const double tip_x = -75 + double(std::max(line.front().x(), line.back().x()));
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u) {
      const Eigen::Vector3d floor =
          w2c.inverse() * Eigen::Vector3d((u - k.cx) / k.fx * kCameraHeightMm,
                                          (v - k.cy) / k.fy * kCameraHeightMm, kCameraHeightMm);
      if (floor.x() > tip_x + 0.5 * kTubeMm && floor.x() < tip_x + 1.0 * kTubeMm &&
          std::abs(floor.y()) < kTubeMm)
        tube.s.depth.at(u, v) = 0;
    }
  const auto ends = [&](double x_mm) {
    Pose m2w = Pose::Identity();
    m2w.translation() = Eigen::Vector3d(x_mm, 0, kTubeMm / 2);
    Verification v;
    judge_ends(line, float(kTubeMm), w2c * m2w, tube.s.depth, k, 7.0f, &v);
    return v;
  };
  const Verification truth = ends(-75);
  EXPECT_EQ(truth.ends_pinned, 2);
  EXPECT_EQ(truth.ends_seen_ending, 1);  // the end without a shadow
  EXPECT_EQ(truth.ends_ending_past_shadow, 1);
  const Verification slid = ends(-75 + 0.25 * kTubeMm);
  EXPECT_EQ(slid.ends_pinned, 2);
  EXPECT_EQ(slid.ends_seen_ending, 2);  // both probes past the slid end read the floor
  EXPECT_EQ(slid.ends_ending_past_shadow, 0);
}

// An end whose tip lies outside the sensor's view (beyond the image, or in the band an active
// sensor does not read) is counted as such: no image can show it ending (decide() does not ask
// for it where both ends lie there), and what lies beyond it neither pins it nor shows it going on
// (a coil's loop at the image's edge was pinned so, 82 mm from its pipe: 18-coil of seed 21). So
// is an end whose tip lies just inside the view, the way on beyond it outside: what lies there
// does not count either.
TEST(BinAwareVerification, AnEndTheViewDoesNotShowBeyondIsCountedOutOfIt) {
  TubeOnFloor tube;
  const Intrinsics& k = tube.s.camera.intrinsics;
  const std::vector<Eigen::Vector3f>& line = tube.lm.centreline_points;
  Pose m2w = Pose::Identity();
  m2w.translation() = Eigen::Vector3d(-75, 0, kTubeMm / 2);
  const Pose m2c = *tube.s.camera.world_to_cam * m2w;
  const auto ends = [&](const PixelBox* view) {
    Verification v;
    judge_ends(line, float(kTubeMm), m2c, tube.s.depth, k, 7.0f, &v, EndReading{}, view);
    return v;
  };
  const double x_a = k.project(m2c * line.front().cast<double>()).x();
  const double x_b = k.project(m2c * line.back().cast<double>()).x();
  const int left = int(std::floor(std::min(x_a, x_b))), right = int(std::ceil(std::max(x_a, x_b)));
  EXPECT_EQ(ends(nullptr).ends_out_of_view, 0);
  EXPECT_EQ(ends(nullptr).ends_pinned, 2);
  const PixelBox past_one{left + 2, 0, k.width - 1, k.height - 1};
  EXPECT_EQ(ends(&past_one).ends_out_of_view, 1);
  EXPECT_EQ(ends(&past_one).ends_pinned, 1);
  // The nearer probe beyond the tip (0.75 D, about 10 px here) falls outside a view whose edge lies
  // a pixel beyond the tip, not outside one whose edge lies 16 px beyond it.
  const PixelBox tip_inside{left - 1, 0, k.width - 1, k.height - 1};
  EXPECT_EQ(ends(&tip_inside).ends_out_of_view, 1);
  EXPECT_EQ(ends(&tip_inside).ends_pinned, 1);
  const PixelBox past_probes{left - 16, 0, k.width - 1, k.height - 1};
  EXPECT_EQ(ends(&past_probes).ends_out_of_view, 0);
  EXPECT_EQ(ends(&past_probes).ends_pinned, 2);
  const PixelBox between{left + 2, 0, right - 2, k.height - 1};
  EXPECT_EQ(ends(&between).ends_out_of_view, 2);
  EXPECT_EQ(ends(&between).ends_pinned, 0);
  EXPECT_EQ(ends(&between).ends_continued, 0);
}

// A pose reaching out of the view is placed along its pipe by its part in view. An arc's loop
// running out of the view looks the same slid along the arc (judge_part_in_view): only an end the
// image shows places it. The bend of an L in view places it; so does the view holding all of it
// (the model's own slides judge that).
TEST(BinAwareVerification, APartInViewThatSlidesAlongThePipeIsToldFromABendInView) {
  const LocateConfig cfg;
  const double d = 20;
  Intrinsics k;
  k.width = 640, k.height = 480, k.fx = k.fy = 570, k.cx = 320, k.cy = 240;
  const PixelBox left_half{0, 0, k.width / 2 - 1, k.height - 1};
  const auto slides_in = [&](const std::string& path, const PixelBox* view) {
    const LocatorModel lm = prepare_locator_model(pipe_of(path, d, path), 8, cfg);
    const std::vector<Eigen::Vector3f>& line = lm.centreline_points;
    // Its centreline's middle point on the optical axis, 950 mm away.
    Pose pose = Pose::Identity();
    pose.translation() = Eigen::Vector3d(0, 0, 950) - line[line.size() / 2].cast<double>();
    Verification v;
    judge_part_in_view(line, lm.centreline_step_mm, float(d), float(d), pose, k, &v, view);
    return v.part_in_view_slides;
  };
  EXPECT_TRUE(slides_in("B200r80", &left_half));
  EXPECT_FALSE(slides_in("B200r80", nullptr));
  EXPECT_FALSE(slides_in("S80,B90r30,S80", &left_half));
}

// Of an S whose two bends nearly match (the zoo's 11-S-asym of seed 22, in units of D), one bend in
// view could be either (other_parts_in_view): the motion found takes the bend in view onto the
// other one. An L's one bend has no other part it could be; nor has a pose wholly in the view.
TEST(BinAwareVerification, AnSsOtherBendIsAnotherPartItsBendInViewCouldBe) {
  const LocateConfig cfg;
  Intrinsics k;
  k.width = 640, k.height = 480, k.fx = k.fy = 570, k.cx = 320, k.cy = 240;
  const auto in_d = [](double d, std::initializer_list<double> v) {
    std::vector<double> out;
    for (const double x : v) out.push_back(x * d);
    return out;
  };
  for (const double d : {10.0, 40.0}) {
    const std::vector<double> s = in_d(d, {3.23, 3.78, 0.28, 3.84, 3.11}), l = in_d(d, {2, 4, 12});
    const std::string s_bend = "S" + std::to_string(s[0]) + ",B116r" + std::to_string(s[1]) + ",S" +
                               std::to_string(s[2]) + ",B-106r" + std::to_string(s[3]) + ",S" +
                               std::to_string(s[4]);
    const std::string l_bend =
        "S" + std::to_string(l[0]) + ",B90r" + std::to_string(l[1]) + ",S" + std::to_string(l[2]);
    // The pipe's middle 900 mm ahead; the view holds the first 45 % of its centreline.
    const auto other_parts = [&](const std::string& path, bool cut, std::vector<Pose>* motions) {
      const LocatorModel lm = prepare_locator_model(pipe_of(path, d, path), 8, cfg);
      const std::vector<Eigen::Vector3f>& line = lm.centreline_points;
      Pose pose = Pose::Identity();
      pose.translation() = Eigen::Vector3d(0, 0, 900) - line[line.size() / 2].cast<double>();
      const double x_cut = k.project(pose * line[line.size() * 45 / 100].cast<double>()).x();
      const double x_first = k.project(pose * line.front().cast<double>()).x();
      PixelBox view{0, 0, k.width - 1, k.height - 1};
      if (x_first < x_cut)
        view.x1 = int(x_cut);
      else
        view.x0 = int(x_cut);
      motions->assign(2, Pose::Identity());
      const int n = other_parts_in_view(line, lm.centreline_step_mm, float(d), float(d), 0.25f * float(d),
                                        pose, k, cut ? &view : nullptr, motions->data(), 2);
      motions->resize(std::size_t(n));
      return line;
    };
    std::vector<Pose> motions;
    const std::vector<Eigen::Vector3f> line = other_parts(s_bend, true, &motions);
    ASSERT_GE(motions.size(), 1u) << d;
    // The first bend's middle moves more than 2 D, onto the second half of the centreline.
    const Eigen::Vector3d first_bend = line[line.size() * 33 / 100].cast<double>();
    const Eigen::Vector3d moved = motions[0] * first_bend;
    double nearest = 1e9;
    for (std::size_t i = line.size() / 2; i < line.size(); ++i)
      nearest = std::min(nearest, (moved - line[i].cast<double>()).norm());
    EXPECT_LT(nearest, 0.25 * d) << d;
    EXPECT_GT((moved - first_bend).norm(), 2 * d) << d;
    other_parts(s_bend, false, &motions);
    EXPECT_TRUE(motions.empty()) << d;
    other_parts(l_bend, true, &motions);
    EXPECT_TRUE(motions.empty()) << d;
  }
}

// On a simulated bin (floor at z = 0) the floor is found, a pipe's pose lies on it, and the same
// pose four diameters lower lies under it.
// A bend with legs of 85 and 104 mm and its near twin (turned end for end: its legs swapped).
// Where the image shows the pipe's ends, the pixels where the two renders differ speak for the
// pipe, hardly for the twin; where the sensor has no reading there, nothing tells them apart.
TEST(BinAwareVerification, ANearTwinIsToldApartByThePixelsWhereTheyDiffer) {
  const PipeModel model = pipe_of("S85,B-134r188,S104", 23.3, "bend");
  ASSERT_EQ(model.near_symmetries.size(), 1u);
  const Mesh mesh = weld_vertices(model.mesh, model.tube_diameter_mm / 8);
  Intrinsics k;
  k.width = 640, k.height = 480, k.fx = k.fy = 570, k.cx = 320, k.cy = 240;
  Pose pipe = Pose::Identity();
  pipe.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pipe.translation() = Eigen::Vector3d(0, 0, 950);
  const Pose twin = pipe * model.near_symmetries[0];
  ProjectedMesh projected;
  projected.reserve(mesh);
  Image<float> at_pipe(k.width, k.height, 0.0f), at_twin(k.width, k.height, 0.0f);
  const PixelBox box_pipe = render_depth_in_box(mesh, pipe, k, &at_pipe, &projected);
  const PixelBox box_twin = render_depth_in_box(mesh, twin, k, &at_twin, &projected);
  // The sensor: the pipe on a floor 1 m away, 1 mm of noise.
  Image<float> depth(k.width, k.height, 1000.0f);
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, 1.0f);
  for (int y = 0; y < k.height; ++y)
    for (int x = 0; x < k.width; ++x) {
      const bool on_pipe = x >= box_pipe.x0 && x <= box_pipe.x1 && y >= box_pipe.y0 && y <= box_pipe.y1 &&
                           at_pipe.at(x, y) > 0;
      depth.at(x, y) = (on_pipe ? at_pipe.at(x, y) : 1000.0f) + noise(rng);
    }
  const float tol = 5;
  const TellingPixels seen = tell_apart(at_pipe, box_pipe, at_twin, box_twin, depth, tol);
  EXPECT_GE(seen.for_a, kMinTellingPx);
  EXPECT_LE(kTellingRatio * seen.for_b, seen.for_a)
      << seen.for_a << " for the pipe, " << seen.for_b << " for its twin";
  const TellingPixels swapped = tell_apart(at_twin, box_twin, at_pipe, box_pipe, depth, tol);
  EXPECT_EQ(swapped.for_a, seen.for_b);
  EXPECT_EQ(swapped.for_b, seen.for_a);
  // No reading where the two differ (a dropout, the ends under a shadow): nothing tells them apart.
  for (int y = 0; y < k.height; ++y)
    for (int x = 0; x < k.width; ++x) {
      const float zp =
          x >= box_pipe.x0 && x <= box_pipe.x1 && y >= box_pipe.y0 && y <= box_pipe.y1 ? at_pipe.at(x, y) : 0;
      const float zt =
          x >= box_twin.x0 && x <= box_twin.x1 && y >= box_twin.y0 && y <= box_twin.y1 ? at_twin.at(x, y) : 0;
      if ((zp > 0) != (zt > 0) || std::abs(zp - zt) > tol) depth.at(x, y) = 0;
    }
  const TellingPixels hidden = tell_apart(at_pipe, box_pipe, at_twin, box_twin, depth, tol);
  EXPECT_EQ(hidden.for_a + hidden.for_b, 0);
}

// The same bend alone on a floor, a pipe lying across one of its ends 20 mm above the tube. The
// floor beyond that end reads as the image showing the pipe end there, unless the end must show
// its tip (a near twin overshooting the pipe's end under such a pipe was taken for the pipe).
TEST(BinAwareVerification, AnEndHiddenUnderAPipeAcrossIsNotShownEnding) {
  const LocateConfig cfg;
  const PipeModel model = pipe_of("S85,B-134r188,S104", 23.3, "bend");
  const LocatorModel lm = prepare_locator_model(model, 8, cfg);
  ASSERT_TRUE(lm.slides.empty());
  const float d = model.tube_diameter_mm, tol = float(cfg.verify_tolerance_mm);
  Intrinsics k;
  k.width = 640, k.height = 480, k.fx = k.fy = 570, k.cx = 320, k.cy = 240;
  Pose pipe = Pose::Identity();
  pipe.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  pipe.translation() = Eigen::Vector3d(0, 0, 950);
  ProjectedMesh projected;
  projected.reserve(model.mesh);
  Image<float> at_pipe(k.width, k.height, 0.0f);
  const PixelBox box = render_depth_in_box(model.mesh, pipe, k, &at_pipe, &projected);
  // The sensor: the floor 1 m away, the pipe, and within a diameter of one end (in the image) the
  // pipe across.
  const Eigen::Vector3d end = pipe * lm.centreline_points.back().cast<double>();
  const Eigen::Vector2d end_px = k.project(end);
  const double cover_px = d * k.fx / end.z();
  const auto with_cover = [&](bool covered) {
    Image<float> depth(k.width, k.height, 1000.0f);
    for (int y = 0; y < k.height; ++y)
      for (int x = 0; x < k.width; ++x) {
        if (x >= box.x0 && x <= box.x1 && y >= box.y0 && y <= box.y1 && at_pipe.at(x, y) > 0)
          depth.at(x, y) = at_pipe.at(x, y);
        if (covered && (Eigen::Vector2d(x, y) - end_px).norm() < cover_px)
          depth.at(x, y) = float(end.z() - d / 2 - 20);
      }
    return depth;
  };
  const auto ends = [&](const Image<float>& depth, bool tip_must_show) {
    Verification v;
    EndReading how;
    how.tip_must_show = tip_must_show;
    judge_ends(lm.centreline_points, d, pipe, depth, k, tol, &v, how);
    return v;
  };
  const Image<float> open = with_cover(false), covered = with_cover(true);
  EXPECT_EQ(ends(open, false).ends_pinned, 2);
  EXPECT_EQ(ends(open, true).ends_pinned, 2);      // both tips seen: both ends shown
  EXPECT_EQ(ends(covered, false).ends_pinned, 2);  // the floor beyond the hidden end
  EXPECT_EQ(ends(covered, true).ends_pinned, 1);
  // Seen ending outright (what tells a sliding pipe from its slid rival): only where the tip shows.
  EXPECT_EQ(ends(open, false).ends_seen_ending, 2);
  EXPECT_EQ(ends(covered, false).ends_seen_ending, 1);
  EXPECT_EQ(ends(covered, true).ends_seen_ending, 1);
}

// A 640 x 480 camera, f 570 px, its principal point in the middle.
Intrinsics camera_640() {
  Intrinsics k;
  k.width = 640, k.height = 480, k.fx = k.fy = 570, k.cx = 320, k.cy = 240;
  return k;
}

// A pose putting a straight tube's centreline, from its first point on, across the image and away
// from the camera at `slant` to the image, from a high end 120 mm left of the image's centre and
// 300 mm along the slant above `low_z` (where a 300 mm tube's low tip lies).
Pose slanting_away(const std::vector<Eigen::Vector3f>& centreline, double slant, double low_z) {
  const Eigen::Vector3d down_the_leg(std::cos(slant), 0, std::sin(slant));
  const Eigen::Vector3d along = (centreline.back() - centreline.front()).normalized().cast<double>();
  Pose pose = Pose::Identity();
  pose.linear() = Eigen::Quaterniond::FromTwoVectors(along, down_the_leg).toRotationMatrix();
  pose.translation() = Eigen::Vector3d(-120, 0, low_z - 300 * std::sin(slant)) -
                       pose.linear() * centreline.front().cast<double>();
  return pose;
}

// The depth image of `pipe` at `pose` over a floor floor_z away.
Image<float> over_floor(const PipeModel& pipe, const Pose& pose, const Intrinsics& k, float floor_z) {
  ProjectedMesh projected;
  projected.reserve(pipe.mesh);
  Image<float> drawn(k.width, k.height, 0.0f);
  const PixelBox box = render_depth_in_box(pipe.mesh, pose, k, &drawn, &projected);
  Image<float> depth(k.width, k.height, floor_z);
  for (int y = box.y0; y <= box.y1; ++y)
    for (int x = box.x0; x <= box.x1; ++x)
      if (drawn.at(x, y) > 0) depth.at(x, y) = std::min(drawn.at(x, y), depth.at(x, y));
  return depth;
}

// A 300 mm tube D thick slanting away from the camera (slanting_away), over a floor floor_z away:
// its centreline and pose, the image of it alone, and the image of a tube twice as long from the
// same first point (beyond the low end it goes on).
struct SlantedTubeScenes {
  std::vector<Eigen::Vector3f> line;
  Pose pose;
  Image<float> alone, going_on;
};
SlantedTubeScenes slanted_tube_scenes(double d, double slant, double low_z, float floor_z,
                                      const Intrinsics& k) {
  const LocateConfig cfg;
  const PipeModel tube = pipe_of("S300", d, "tube"), longer = pipe_of("S600", d, "longer tube");
  SlantedTubeScenes s;
  s.line = prepare_locator_model(tube, 8, cfg).centreline_points;
  s.pose = slanting_away(s.line, slant, low_z);
  s.alone = over_floor(tube, s.pose, k, floor_z);
  const LocatorModel lm_longer = prepare_locator_model(longer, 8, cfg);
  s.going_on = over_floor(longer, slanting_away(lm_longer.centreline_points, slant, low_z), k, floor_z);
  return s;
}

// The tip of an end the tube reaches at a slant to the image (a 3-D pipe's leg coming down to the
// floor, 50 degrees) shows the camera its surface D / 2 over the cosine of the slant from the
// centreline: read D / 2 from it, the tube's own top in front hides the tip, and the end the
// image shows ending is not shown (ends_read_slanted). A tube going on beyond such an end is not
// pinned by reading it so.
TEST(BinAwareVerification, ASlantedTubesTipIsShownWhereItsSurfaceFacesTheCamera) {
  const double d = 40;
  const float tol = float(LocateConfig().verify_tolerance_mm);
  const Intrinsics k = camera_640();
  // The floor 1005 mm away, the tube's low tip 40 mm over it.
  const SlantedTubeScenes s = slanted_tube_scenes(d, 50 * EIGEN_PI / 180, 965, 1005.0f, k);
  const auto ends = [&](const Image<float>& depth, bool slanted) {
    Verification v;
    EndReading how;
    how.tip_must_show = true;
    how.slanted = slanted;
    judge_ends(s.line, float(d), s.pose, depth, k, tol, &v, how);
    return v;
  };
  // The high end shown ending either way; the low one only where read slanted.
  EXPECT_EQ(ends(s.alone, false).ends_pinned, 1);
  EXPECT_EQ(ends(s.alone, true).ends_pinned, 2);
  EXPECT_EQ(ends(s.alone, true).ends_continued, 0);
  // A tube twice as long from the same first point: beyond the low end it goes on.
  EXPECT_EQ(ends(s.going_on, false).ends_pinned, 1);
  EXPECT_EQ(ends(s.going_on, true).ends_pinned, 1);
}

// A tip slanting steeply away from the camera (70 degrees to the image, 200 mm over the floor)
// hides what lies just beyond it behind its own end: both probes see the tube's own end in front
// of where a tube going on would show, and read nothing. Read past its own tube
// (EndReading::past_itself; the locator reads so the ends of a pipe that does not slide), the
// floor there pins the end; a tube going on beyond it does not.
TEST(BinAwareVerification, ATipSlantingAwayIsReadPastItsOwnTube) {
  const double d = 40;
  const float tol = float(LocateConfig().verify_tolerance_mm);
  const Intrinsics k = camera_640();
  // The low tip 805 mm away, the floor 1005 mm.
  const SlantedTubeScenes s = slanted_tube_scenes(d, 70 * EIGEN_PI / 180, 805, 1005.0f, k);
  const auto ends = [&](const Image<float>& depth, bool past_itself) {
    Verification v;
    EndReading how;
    how.slanted = true;
    how.past_itself = past_itself;
    judge_ends(s.line, float(d), s.pose, depth, k, tol, &v, how);
    return v;
  };
  // The high end is pinned either way; the low one only read past its own tube.
  EXPECT_EQ(ends(s.alone, false).ends_pinned, 1);
  EXPECT_EQ(ends(s.alone, true).ends_pinned, 2);
  EXPECT_EQ(ends(s.alone, true).ends_continued, 0);
  // A tube twice as long from the same first point goes on beyond the low end: read past the
  // pose's own tube, the low end is not pinned.
  EXPECT_EQ(ends(s.going_on, true).ends_pinned, 1);
}

// A pipe that slides along itself is placed by its ends alone. Where nothing is read just beyond
// an end (a coil's end tucked in the shadow of its own next turn), the image is read 2 D further
// along the bend (ends_read_further): the floor there pins the end; the tube going on round the
// bend (the pipe is longer than the pose: a pose slid along it) shows it continued, where a probe
// on the straight line would have left the tube (0.8 D off it on this bend of 2.5 D) and met the
// floor.
TEST(BinAwareVerification, AnEndWithNothingReadJustBeyondIsReadFurtherAlongItsBend) {
  const LocateConfig cfg;
  const double d = 20;
  const PipeModel arc = pipe_of("B200r50", d, "arc"), longer = pipe_of("B300r50", d, "longer arc");
  const LocatorModel lm = prepare_locator_model(arc, 8, cfg),
                     lm_longer = prepare_locator_model(longer, 8, cfg);
  ASSERT_FALSE(lm.slides.empty());
  const std::vector<Eigen::Vector3f>& line = lm.centreline_points;
  // The arc's end the longer one goes on beyond: not near either end of the longer one.
  const auto near_an_end = [&](const Eigen::Vector3f& p) {
    return (p - lm_longer.centreline_points.front()).norm() < d ||
           (p - lm_longer.centreline_points.back()).norm() < d;
  };
  ASSERT_NE(near_an_end(line.front()), near_an_end(line.back()));
  const Eigen::Vector3f far_end = near_an_end(line.front()) ? line.back() : line.front();
  const Eigen::Vector3f inside = near_an_end(line.front()) ? line[line.size() - 4] : line[3];
  const float tol = float(cfg.verify_tolerance_mm);
  Intrinsics k;
  k.width = 640, k.height = 480, k.fx = k.fy = 570, k.cx = 320, k.cy = 240;
  Pose pose = Pose::Identity();
  pose.translation() = Eigen::Vector3d(0, 0, 950);
  // The sensor: the floor 1 m away, the pipe (the arc, or the longer arc it is part of), and no
  // reading within D/2 of the point a diameter beyond the far end on the line out of the tube.
  const Eigen::Vector3d tip = pose * far_end.cast<double>();
  const Eigen::Vector3d out = pose.linear() * (far_end - inside).normalized().cast<double>();
  const Eigen::Vector2d shadow_px = k.project(tip + d * out);
  const double shadow_radius_px = 0.5 * d * k.fx / tip.z();
  const auto scene = [&](const PipeModel& pipe) {
    ProjectedMesh projected;
    projected.reserve(pipe.mesh);
    Image<float> drawn(k.width, k.height, 0.0f);
    const PixelBox box = render_depth_in_box(pipe.mesh, pose, k, &drawn, &projected);
    Image<float> depth(k.width, k.height, 1000.0f);
    for (int y = 0; y < k.height; ++y)
      for (int x = 0; x < k.width; ++x) {
        if (x >= box.x0 && x <= box.x1 && y >= box.y0 && y <= box.y1 && drawn.at(x, y) > 0)
          depth.at(x, y) = drawn.at(x, y);
        if ((Eigen::Vector2d(x, y) - shadow_px).norm() < shadow_radius_px) depth.at(x, y) = 0;
      }
    return depth;
  };
  const auto ends = [&](const Image<float>& depth, bool read_further) {
    Verification v;
    EndReading how;
    how.read_further = read_further;
    judge_ends(line, float(d), pose, depth, k, tol, &v, how);
    return v;
  };
  const Image<float> alone = scene(arc), going_on = scene(longer);
  // The pipe is the arc: the near end pinned by the floor beyond; the far end read only further on.
  EXPECT_EQ(ends(alone, false).ends_pinned, 1);
  EXPECT_EQ(ends(alone, false).ends_continued, 0);
  EXPECT_EQ(ends(alone, true).ends_pinned, 2);
  EXPECT_EQ(ends(alone, true).ends_continued, 0);
  EXPECT_EQ(ends(alone, true).ends_seen_ending, 1);  // read further only: not seen ending outright
  // The pipe goes on round the bend beyond the far end: shown continued, not pinned.
  EXPECT_EQ(ends(going_on, false).ends_pinned, 1);
  EXPECT_EQ(ends(going_on, false).ends_continued, 0);
  EXPECT_EQ(ends(going_on, true).ends_pinned, 1);
  EXPECT_EQ(ends(going_on, true).ends_continued, 1);
}

TEST(BinAwareVerification, NoPoseBelowTheFloor) {
  const PipeModel& model = preset_model("sbend");
  const SimulatedScene s = pile_of(model, 3, 4);
  Locator loc(model, LocateConfig{}, s.camera.intrinsics);
  const LocateOutput& out = loc.locate(s.depth_mm, s.camera);
  EXPECT_NEAR(out.lowest_surface_z_mm, 0, 5);  // noise takes the 2nd percentile a little deeper
  ASSERT_FALSE(out.estimates.empty());
  const float d = model.tube_diameter_mm;
  const float below = out.lowest_surface_z_mm - kBelowFloorOfD * d;
  for (const PipeEstimate& e : out.estimates) {
    EXPECT_LT(share_below(model.mesh, e.model_to_bin, below), kMaxShareBelowFloor);
    EXPECT_EQ(e.check.below_floor, share_below(loc.locator_model().verify_mesh, e.model_to_bin, below));
    Pose sunk = e.model_to_bin;
    sunk.translation().z() -= 4 * d;  // under the floor whatever it lay on
    EXPECT_GT(share_below(model.mesh, sunk, below), 0.9);
  }
}

}  // namespace
}  // namespace pipeloc
