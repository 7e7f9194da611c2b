// Commissioning: the bin frame (calibrate-bin) and the hand-eye transform (calibrate-hand-eye) on
// frames the simulator makes, against the poses it used.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include "calib/bin_frame.hpp"
#include "calib/hand_eye.hpp"
#include "calib/sphere_fit.hpp"
#include "calib/stations.hpp"
#include "config/config_file.hpp"
#include "io/bop.hpp"
#include "io/png.hpp"
#include "locate/zbuffer.hpp"
#include "model/make_pipe.hpp"
#include "plc/robot_pose.hpp"
#include "sim/scene.hpp"
#include "test_util.hpp"

namespace pipeloc {
namespace {

constexpr double kDeg = M_PI / 180.0;

PipeModel coarse_model(const char* preset) {
  PipeSpec spec = pipe_preset(preset);
  spec.sides = 16;
  spec.bend_step_deg = 10;
  return derive_pipe_model(make_pipe(spec), preset);
}

// A camera `height_mm` above the floor looking at `look_at`, tilted by tilt_deg towards azimuth_deg
// (as draw_camera does, with the angles given).
Pose camera_at(double height_mm, double tilt_deg, double azimuth_deg, const Eigen::Vector3d& look_at) {
  const double tilt = tilt_deg * kDeg, az = azimuth_deg * kDeg;
  const Eigen::Vector3d down(std::sin(tilt) * std::cos(az), std::sin(tilt) * std::sin(az), -std::cos(tilt));
  const Eigen::Vector3d centre = look_at - down * (height_mm / std::cos(tilt));
  const Eigen::Vector3d x = (Eigen::Vector3d::UnitX() - down * down.x()).normalized();
  Eigen::Matrix3d cam_to_world;
  cam_to_world << x, down.cross(x), down;
  Pose w2c = Pose::Identity();
  w2c.linear() = cam_to_world.transpose();
  w2c.translation() = -cam_to_world.transpose() * centre;
  return w2c;
}

// The sensor's frame of a bin holding `pile`, seen from world_to_cam.
Image<float> bin_frame(const PipeModel& model, const std::vector<Pose>& pile, const Pose& world_to_cam,
                       const SceneParams& params, std::mt19937& rng) {
  DepthTarget camera, projector;
  render_views(model, pile, world_to_cam, params, &camera, &projector);
  return apply_sensor_model(camera, projector, params.intrinsics, params.sensor, int(pile.size()), rng);
}

struct BinCase {
  double tilt_deg, azimuth_deg;
  int pipes;
};

// Floor normal within 0.5 deg and each wall's inner face within 5 mm of the truth, on bins seen
// at tilts up to 30 degrees, empty and with pipes.
TEST(CalibrateBin, FindsFloorAndWallsOfSimulatedBins) {
  const PipeModel model = coarse_model("sbend");
  const BinCase cases[] = {{30, 0, 0},    {0, 0, 0},    {0, 0, 15},    {12, 40, 10},
                           {20, 200, 15}, {30, 90, 10}, {30, 135, 15}, {30, 250, 20}};
  int seed = 11;
  for (const BinCase& c : cases) {
    SCOPED_TRACE("tilt " + std::to_string(c.tilt_deg) + " azimuth " + std::to_string(c.azimuth_deg) +
                 " pipes " + std::to_string(c.pipes));
    std::mt19937 rng(seed++);
    SceneParams params;
    params.pile.pipes = c.pipes;
    const std::vector<Pose> pile = c.pipes ? build_pile(model, params.pile, rng) : std::vector<Pose>{};
    const Pose truth = camera_at(1030, c.tilt_deg, c.azimuth_deg, Eigen::Vector3d(12, -8, 0));
    const Image<float> depth = bin_frame(model, pile, truth, params, rng);
    const BinCalib calib = calibrate_bin(depth, params.intrinsics);
    ASSERT_TRUE(calib.ok) << calib.error;
    const double normal_deg =
        std::acos(std::clamp(truth.linear().col(2).dot(calib.world_to_cam.linear().col(2)), -1.0, 1.0)) /
        kDeg;
    EXPECT_LT(normal_deg, 0.5);
    EXPECT_GT(calib.floor_share, 0.3);
    EXPECT_LT(calib.floor_rms_mm, 4.0);
    // Each wall's inner face, sampled near both of its ends, in the true world frame.
    const Pose est_to_true = truth.inverse() * calib.world_to_cam;
    const BinSpec bin = params.pile.bin;
    const double hx = calib.interior_x_mm / 2, hy = calib.interior_y_mm / 2;
    double worst_wall_mm = 0;
    for (double s : {-1.0, 1.0})
      for (double along : {-0.8, 0.8}) {
        const Eigen::Vector3d on_x_wall = est_to_true * Eigen::Vector3d(s * hx, along * hy, 0);
        const Eigen::Vector3d on_y_wall = est_to_true * Eigen::Vector3d(along * hx, s * hy, 0);
        EXPECT_NEAR(std::abs(on_x_wall.x()), bin.inner_x_mm / 2, 5.0) << "x wall " << s << " at " << along;
        EXPECT_NEAR(std::abs(on_y_wall.y()), bin.inner_y_mm / 2, 5.0) << "y wall " << s << " at " << along;
        EXPECT_NEAR(on_x_wall.z(), 0, 3.0);
        worst_wall_mm = std::max({worst_wall_mm, std::abs(std::abs(on_x_wall.x()) - bin.inner_x_mm / 2),
                                  std::abs(std::abs(on_y_wall.y()) - bin.inner_y_mm / 2)});
      }
    std::printf(
        "calibrate-bin: tilt %4.1f deg azimuth %5.1f deg, %2d pipes: normal %.3f deg, worst wall %.2f mm, "
        "floor %.1f %% inliers, %.2f mm RMS\n",
        c.tilt_deg, c.azimuth_deg, c.pipes, normal_deg, worst_wall_mm, 100 * calib.floor_share,
        calib.floor_rms_mm);
    EXPECT_NEAR(calib.roi_max_mm[0], hx - 5, 1e-9);
    EXPECT_NEAR(calib.roi_min_mm[1], -(hy - 5), 1e-9);
  }
}

// A camera 0.45 m above a bin twice as wide as it sees: not four walls in view, and the bin is
// refused naming --floor-only; with it, the floor's frame alone (normal within 0.5 deg, the camera
// at its true height) and no region of interest in the TOML.
TEST(CalibrateBin, ACameraSeeingPartOfTheBinGivesTheFloorAlone) {
  const PipeModel model = coarse_model("sbend");
  std::mt19937 rng(17);
  SceneParams params;
  params.pile.pipes = 10;
  params.pile.bin.inner_x_mm *= 2;
  params.pile.bin.inner_y_mm *= 2;
  const std::vector<Pose> pile = build_pile(model, params.pile, rng);
  const Pose truth = camera_at(450, 10, 30, Eigen::Vector3d(40, -20, 0));
  const Image<float> depth = bin_frame(model, pile, truth, params, rng);
  const BinCalib walls = calibrate_bin(depth, params.intrinsics);
  ASSERT_FALSE(walls.ok);
  EXPECT_NE(walls.error.find("--floor-only"), std::string::npos) << walls.error;
  BinCalibParams floor_only;
  floor_only.floor_only = true;
  const BinCalib calib = calibrate_bin(depth, params.intrinsics, floor_only);
  ASSERT_TRUE(calib.ok) << calib.error;
  EXPECT_FALSE(calib.walls);
  const double normal_deg =
      std::acos(std::clamp(truth.linear().col(2).dot(calib.world_to_cam.linear().col(2)), -1.0, 1.0)) / kDeg;
  EXPECT_LT(normal_deg, 0.5);
  // The camera's height above the floor: the same in both frames.
  EXPECT_NEAR(calib.world_to_cam.inverse().translation().z(), truth.inverse().translation().z(), 3.0);
  const std::string toml = bin_calib_toml(calib);
  EXPECT_NE(toml.find("world_to_cam"), std::string::npos);
  EXPECT_EQ(toml.find("roi_min_mm"), std::string::npos) << toml;
}

TEST(CalibrateBin, RandomDepthsHaveNoFloor) {
  const Intrinsics k;
  Image<float> depth(k.width, k.height, 0.0f);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> any(600, 2500);
  for (float& d : depth.pixels) d = any(rng);
  const BinCalib calib = calibrate_bin(depth, k);
  EXPECT_FALSE(calib.ok);
  EXPECT_NE(calib.error.find("no floor plane"), std::string::npos) << calib.error;
  const BinCalib empty = calibrate_bin(Image<float>(k.width, k.height, 0.0f), k);
  EXPECT_FALSE(empty.ok);
  EXPECT_NE(empty.error.find("valid depth pixels"), std::string::npos) << empty.error;
}

// A floor crossed by two raised bars: their edges are found as walls whose inner faces cross, and
// the bin is refused instead of given an interior of negative size.
TEST(CalibrateBin, WallsThatLeaveNoInteriorAreRefused) {
  const Intrinsics k;
  Image<float> depth(k.width, k.height, 1000.0f);
  for (int v = 0; v < k.height; ++v)
    for (int u = 0; u < k.width; ++u)
      if ((v > 225 && v < 255) || (u > 305 && u < 335)) depth.at(u, v) = 940;
  const BinCalib calib = calibrate_bin(depth, k);
  EXPECT_FALSE(calib.ok);
  EXPECT_NE(calib.error.find("leave no interior"), std::string::npos) << calib.error;
}

TEST(CalibrateBin, TomlLoadsAsConfig) {
  const PipeModel model = coarse_model("sbend");
  std::mt19937 rng(2);
  SceneParams params;
  const Pose truth = camera_at(1000, 15, 60, Eigen::Vector3d::Zero());
  const BinCalib calib = calibrate_bin(bin_frame(model, {}, truth, params, rng), params.intrinsics);
  ASSERT_TRUE(calib.ok) << calib.error;
  test::TempDir dir;
  test::write_text(dir.file("c.toml"), bin_calib_toml(calib));
  const AppConfig cfg = load_config(dir.file("c.toml"));
  ASSERT_EQ(cfg.source.openni2.world_to_cam.size(), 16u);
  const Pose loaded = pose_from_matrix_rowmajor(cfg.source.openni2.world_to_cam.data());
  EXPECT_LT((loaded.matrix() - calib.world_to_cam.matrix()).cwiseAbs().maxCoeff(), 0.01);
  EXPECT_TRUE(cfg.locate.roi.on());
  EXPECT_NEAR(cfg.locate.roi.max_x_mm, calib.roi_max_mm[0], 0.06);
  EXPECT_NEAR(cfg.locate.roi.min_y_mm, calib.roi_min_mm[1], 0.06);
}

TEST(RegionOfInterest, ConfigKeysAreCheckedAtStartUp) {
  test::TempDir dir;
  auto error_of = [&](const std::string& text) -> std::string {
    test::write_text(dir.file("r.toml"), text);
    try {
      load_config(dir.file("r.toml"));
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of("[locate]\nroi_min_mm = [-300, -200]\n").find("locate.roi_max_mm"), std::string::npos);
  EXPECT_NE(
      error_of("[locate]\nroi_min_mm = [300, -200]\nroi_max_mm = [-300, 200]\n").find("locate.roi_min_mm"),
      std::string::npos);
  EXPECT_NE(error_of("[locate]\nroi_max_mm = [300]\nroi_min_mm = [-3, -2]\n").find("locate.roi_max_mm"),
            std::string::npos);
  EXPECT_EQ(error_of("[locate]\nroi_min_mm = [-300, -200]\nroi_max_mm = [300, 200]\n"), "");
  EXPECT_FALSE(default_config().locate.roi.on());
}

// Points outside the region never enter the Z-buffer; without one, every valid pixel does.
TEST(RegionOfInterest, PointsOutsideNeverEnterTheZBuffer) {
  const PipeModel model = coarse_model("sbend");
  std::mt19937 rng(4);
  SceneParams params;
  params.pile.pipes = 10;
  const std::vector<Pose> pile = build_pile(model, params.pile, rng);
  CameraInfo cam;
  cam.intrinsics = params.intrinsics;
  cam.world_to_cam = camera_at(1000, 20, 30, Eigen::Vector3d::Zero());
  const Image<float> depth = bin_frame(model, pile, *cam.world_to_cam, params, rng);
  ZBufferPoints all, clipped;
  reserve_zbuffer_points(&all, depth.width, depth.height, 1);
  reserve_zbuffer_points(&clipped, depth.width, depth.height, 1);
  const Pose b2c = bin_to_camera(cam);
  zbuffer_points_rows(depth, cam.intrinsics, b2c, 1.0, 0, depth.height, 0, &all);
  const RegionOfInterest roi{-315, -235, 315, 235};
  zbuffer_points_rows(depth, cam.intrinsics, b2c, 1.0, 0, depth.height, 0, &clipped, roi);
  int inside = 0, outside = 0, entered_outside = 0, lost_inside = 0;
  for (std::size_t i = 0; i < all.p.size(); ++i) {
    if (all.p[i].w() < 0) {
      EXPECT_LT(clipped.p[i].w(), 0);
      continue;
    }
    const bool in = std::abs(all.p[i].x()) <= 315 && std::abs(all.p[i].y()) <= 235;
    (in ? inside : outside) += 1;
    if (in)
      lost_inside += clipped.p[i].w() < 0 || clipped.p[i] != all.p[i];
    else
      entered_outside += clipped.p[i].w() >= 0;
  }
  EXPECT_GT(outside, 5000);  // the walls' tops and faces
  EXPECT_GT(inside, 50000);
  EXPECT_EQ(entered_outside, 0);
  EXPECT_EQ(lost_inside, 0);
  EXPECT_LE(clipped.band[0].hi_x, 315.0f);
  EXPECT_GE(clipped.band[0].lo_y, -235.0f);
}

// --- hand-eye ---

Mesh uv_sphere(double r, int slices, int stacks) {
  Mesh m;
  for (int i = 0; i <= stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      const double th = M_PI * i / stacks, ph = 2 * M_PI * j / slices;
      m.vertices.emplace_back(float(r * std::sin(th) * std::cos(ph)), float(r * std::sin(th) * std::sin(ph)),
                              float(r * std::cos(th)));
    }
  for (int i = 0; i < stacks; ++i)
    for (int j = 0; j < slices; ++j) {
      const int a = i * slices + j, b = i * slices + (j + 1) % slices, c = a + slices, d = b + slices;
      m.faces.push_back({a, c, b});
      m.faces.push_back({b, c, d});
    }
  return m;
}

// The sensor's frame of the sphere at centre_cam (camera frame), the bin floor 1050 mm below.
Image<float> sphere_frame(const Mesh& sphere, const Eigen::Vector3d& centre_cam, std::mt19937& rng) {
  SceneParams params;
  const Pose w2c = camera_at(1050, 0, 0, Eigen::Vector3d::Zero());
  const Mesh bin = make_bin_mesh(params.pile.bin);
  DepthTarget camera, projector;
  for (int view = 0; view < 2; ++view) {
    DepthTarget* t = view ? &projector : &camera;
    const Eigen::Vector3d shift(view ? -params.sensor.baseline_mm : 0, 0, 0);
    t->reset(params.intrinsics.width, params.intrinsics.height);
    Pose bin_pose = w2c;
    bin_pose.translation() += shift;
    render_perspective(bin, bin_pose, params.intrinsics, 1, t);
    Pose s = Pose::Identity();
    s.translation() = centre_cam + shift;
    render_perspective(sphere, s, params.intrinsics, 0, t);
  }
  return apply_sensor_model(camera, projector, params.intrinsics, params.sensor, 1, rng);
}

TEST(CalibrateHandEye, FindsTheSphereInADepthFrame) {
  const double r = 30;
  const Mesh sphere = uv_sphere(r, 96, 48);
  std::mt19937 rng(7);
  SphereFitParams params;
  params.radius_mm = r;
  for (const Eigen::Vector3d& c :
       {Eigen::Vector3d(0, 0, 800), Eigen::Vector3d(-180, 120, 950), Eigen::Vector3d(220, -90, 700)}) {
    const SphereFit fit = find_sphere(sphere_frame(sphere, c, rng), Intrinsics{}, params);
    ASSERT_TRUE(fit.ok) << c.transpose();
    EXPECT_GT(fit.inliers, 0.6 * fit.expected_px);
    EXPECT_LT((fit.centre_mm - c).norm(), 1.0) << c.transpose() << " found " << fit.centre_mm.transpose();
    std::printf("sphere at %.0f mm: centre off by %.2f mm, %d of %d px on the cap, %.2f mm RMS\n", c.z(),
                (fit.centre_mm - c).norm(), fit.inliers, fit.expected_px, fit.rms_mm);
  }
  // Only the floor: no sphere.
  SceneParams sp;
  DepthTarget camera, projector;
  const Pose w2c = camera_at(1050, 0, 0, Eigen::Vector3d::Zero());
  render_views(coarse_model("u"), {}, w2c, sp, &camera, &projector);
  const Image<float> floor = apply_sensor_model(camera, projector, sp.intrinsics, sp.sensor, 0, rng);
  const SphereFit none = find_sphere(floor, sp.intrinsics, params);
  EXPECT_FALSE(none.ok) << none.centre_mm.transpose() << " " << none.inliers << " of " << none.expected_px;
}

// Six stations seen through the sensor model: robot_from_camera within 0.2 degrees, and points in
// the working volume mapped within 1 mm of where the true transform puts them.
TEST(CalibrateHandEye, SolvesRobotFromCameraFromSixStations) {
  const double r = 30;
  const Mesh sphere = uv_sphere(r, 96, 48);
  Pose truth = Pose::Identity();
  truth.linear() = (Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()) *
                    Eigen::AngleAxisd(0.2, Eigen::Vector3d(0.3, 1, 0.1).normalized()))
                       .toRotationMatrix();
  truth.translation() = Eigen::Vector3d(820, -140, 1380);
  const Eigen::Vector3d stations[] = {{-200, -150, 750}, {210, -140, 820}, {190, 160, 900}, {-180, 170, 850},
                                      {0, 0, 950},       {60, -60, 700},   {-100, 40, 880}};
  std::mt19937 rng(9);
  SphereFitParams params;
  params.radius_mm = r;
  std::vector<Eigen::Vector3d> cam, robot;
  for (const Eigen::Vector3d& s : stations) {
    const SphereFit fit = find_sphere(sphere_frame(sphere, s, rng), Intrinsics{}, params);
    ASSERT_TRUE(fit.ok);
    cam.push_back(fit.centre_mm);
    robot.push_back(truth * s);
  }
  const std::vector<Eigen::Vector3d> cam6(cam.begin(), cam.begin() + 6),
      robot6(robot.begin(), robot.begin() + 6);
  const HandEyeResult he = solve_hand_eye(cam6, robot6);
  ASSERT_TRUE(he.ok) << he.error;
  EXPECT_LT(rotation_angle_deg(he.robot_from_camera.linear(), truth.linear()), 0.2);
  double worst_mm = 0;
  for (double x : {-320.0, 320.0})
    for (double y : {-240.0, 240.0})
      for (double z : {700.0, 1050.0})
        worst_mm = std::max(
            worst_mm,
            (he.robot_from_camera * Eigen::Vector3d(x, y, z) - truth * Eigen::Vector3d(x, y, z)).norm());
  EXPECT_LT(worst_mm, 1.0);
  EXPECT_LT(he.rms_mm, 1.0);
  std::printf(
      "hand-eye, 6 stations: rotation off by %.3f deg, camera origin by %.2f mm, bin corners by %.2f mm "
      "at most, residual %.2f mm RMS\n",
      rotation_angle_deg(he.robot_from_camera.linear(), truth.linear()),
      (he.robot_from_camera.translation() - truth.translation()).norm(), worst_mm, he.rms_mm);
  for (bool o : he.outlier) EXPECT_FALSE(o);

  // A pendant reading typed wrong by 15 mm: flagged, left out, the rest still within bounds.
  robot[3].y() += 15;
  const HandEyeResult bad = solve_hand_eye(cam, robot);
  ASSERT_TRUE(bad.ok);
  for (std::size_t i = 0; i < bad.outlier.size(); ++i) EXPECT_EQ(bad.outlier[i], i == 3) << i;
  EXPECT_EQ(bad.used, 6);
  EXPECT_LT(rotation_angle_deg(bad.robot_from_camera.linear(), truth.linear()), 0.2);
}

// The station file as the integrator writes it (half the stations as the sphere's position, half
// as flange poses with the sphere's offset), with the frames as 16-bit PNGs: the command's path.
TEST(CalibrateHandEye, StationFileToTransform) {
  const double r = 25;
  const Mesh sphere = uv_sphere(r, 96, 48);
  Pose truth = Pose::Identity();
  truth.linear() = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()).toRotationMatrix();
  truth.translation() = Eigen::Vector3d(700, 50, 1500);
  const Eigen::Vector3d offset(0, 0, 180);  // sphere centre in the flange frame
  const Eigen::Vector3d stations[] = {{-200, -150, 760}, {210, -140, 820}, {190, 160, 900},
                                      {-180, 170, 850},  {0, 0, 950},      {60, -60, 700}};
  test::TempDir dir;
  CameraInfo cam;
  cam.depth_scale = 0.1;
  write_json(dir.file("camera.json"), Json{{"0", camera_to_json(cam)}});
  std::string toml =
      "sphere_radius_mm = 25\ncamera = \"camera.json\"\neuler = \"ZYX\"\n"
      "sphere_in_flange_mm = [0, 0, 180]\n";
  std::mt19937 rng(21);
  for (int i = 0; i < 6; ++i) {
    const std::string png = "station" + std::to_string(i) + ".png";
    write_depth_png(dir.file(png), to_raw_depth(sphere_frame(sphere, stations[i], rng), cam.depth_scale));
    const Eigen::Vector3d in_robot = truth * stations[i];
    char line[256];
    if (i % 2 == 0) {
      std::snprintf(line, sizeof line, "[[station]]\ndepth = \"%s\"\ntcp_mm = [%.2f, %.2f, %.2f]\n",
                    png.c_str(), in_robot.x(), in_robot.y(), in_robot.z());
    } else {  // a flange pose turned some way, the sphere 180 mm along its z
      const std::array<double, 3> rxyz{170.0 - 5 * i, 10.0 * i, -30.0 + 12 * i};
      const Eigen::Matrix3d rot = rotation_from_euler_deg(rxyz, EulerConvention::zyx);
      const Eigen::Vector3d flange = in_robot - rot * offset;
      std::snprintf(
          line, sizeof line,
          "[[station]]\ndepth = \"%s\"\nflange_xyz_mm = [%.2f, %.2f, %.2f]\nflange_rxyz_deg = [%.3f, "
          "%.3f, %.3f]\n",
          png.c_str(), flange.x(), flange.y(), flange.z(), rxyz[0], rxyz[1], rxyz[2]);
    }
    toml += line;
  }
  test::write_text(dir.file("stations.toml"), toml);
  const StationFile file = read_stations(dir.file("stations.toml"));
  ASSERT_EQ(file.stations.size(), 6u);
  const CameraInfo read_cam = read_scene_camera(file.camera).begin()->second;
  SphereFitParams params;
  params.radius_mm = file.radius_mm;
  std::vector<Eigen::Vector3d> in_cam, in_robot;
  for (const Station& st : file.stations) {
    const SphereFit fit =
        find_sphere(read_depth_mm(st.depth, read_cam.depth_scale), read_cam.intrinsics, params);
    ASSERT_TRUE(fit.ok) << st.depth;
    in_cam.push_back(fit.centre_mm);
    in_robot.push_back(st.sphere_in_robot);
  }
  const HandEyeResult he = solve_hand_eye(in_cam, in_robot);
  ASSERT_TRUE(he.ok) << he.error;
  EXPECT_LT(rotation_angle_deg(he.robot_from_camera.linear(), truth.linear()), 0.2);
  EXPECT_LT((he.robot_from_camera * Eigen::Vector3d(0, 0, 1000) - truth * Eigen::Vector3d(0, 0, 1000)).norm(),
            1.0);

  // Mistakes name the key.
  auto error_of = [&](const std::string& text) -> std::string {
    test::write_text(dir.file("bad.toml"), text);
    try {
      read_stations(dir.file("bad.toml"));
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of("camera = \"c.json\"\n").find("sphere_radius_mm"), std::string::npos);
  EXPECT_NE(error_of("sphere_radius_mm = 25\ncamera = \"c.json\"\n[[station]]\ndepth = \"a.png\"\n")
                .find("station[1].tcp_mm"),
            std::string::npos);
  EXPECT_NE(error_of("sphere_radius_mm = 25\ncamera = \"c.json\"\n[[station]]\ndepth = \"a.png\"\n"
                     "flange_xyz_mm = [1, 2, 3]\nflange_rxyz_deg = [0, 0, 0]\n")
                .find("sphere_in_flange_mm"),
            std::string::npos);
  EXPECT_NE(error_of("sphere_radius_mm = 25\ncamera = \"c.json\"\n[[station]]\ndepth = \"a.png\"\n"
                     "tcp_mm = [1, 2, 3]\n")
                .find("at least 4"),
            std::string::npos);
}

TEST(CalibrateHandEye, RejectsTooFewOrCollinearStations) {
  std::vector<Eigen::Vector3d> cam = {{0, 0, 800}, {100, 0, 800}, {200, 0, 800}, {300, 0, 800}};
  EXPECT_FALSE(solve_hand_eye(cam, cam).ok);
  EXPECT_NE(solve_hand_eye(cam, cam).error.find("one line"), std::string::npos);
  cam.pop_back();
  EXPECT_NE(solve_hand_eye(cam, cam).error.find("at least 4"), std::string::npos);
}

}  // namespace
}  // namespace pipeloc
