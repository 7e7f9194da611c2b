// pipeloc calibrate-hand-eye: robot_from_camera from a calibration sphere held by the gripper at
// several stations, each a depth frame and the sphere's position read off the robot's pendant.
#include <spdlog/spdlog.h>
#include <toml++/toml.h>

#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "app/commands.hpp"
#include "calib/hand_eye.hpp"
#include "calib/sphere_fit.hpp"
#include "config/config_file.hpp"
#include "io/bop.hpp"
#include "io/png.hpp"
#include "plc/robot_pose.hpp"

namespace pipeloc::app {
namespace {

struct Station {
  std::string depth;
  Eigen::Vector3d sphere_in_robot;
};

struct StationFile {
  double radius_mm = 0;
  std::string camera;
  std::vector<Station> stations;
};

[[noreturn]] void bad(const std::string& file, const std::string& key, const std::string& what) {
  throw ConfigError("stations '" + file + "': " + key + ": " + what);
}

std::vector<double> numbers(const std::string& file, const toml::table& t, const std::string& where,
                            const char* key, std::size_t count) {
  const toml::array* a = t[key].as_array();
  const std::string expected = "expected an array of " + std::to_string(count) + " numbers";
  if (!a || a->size() != count) bad(file, where + key, expected);
  std::vector<double> out;
  for (const toml::node& e : *a) {
    const auto v = e.value<double>();
    if (!v || !e.is_number() || !std::isfinite(*v)) bad(file, where + key, expected);
    out.push_back(*v);
  }
  return out;
}

// The file's format: see docs/calibration.md.
StationFile read_stations(const std::string& file) {
  if (!std::filesystem::is_regular_file(file)) throw ConfigError("stations '" + file + "': no such file");
  toml::table root;
  try {
    root = toml::parse_file(file);
  } catch (const toml::parse_error& e) {
    throw ConfigError("stations '" + file + "': line " + std::to_string(e.source().begin.line) + ": " +
                      std::string(e.description()));
  }
  const std::filesystem::path dir = std::filesystem::path(file).parent_path();
  auto relative = [&](const std::string& p) {
    return std::filesystem::path(p).is_relative() ? (dir / p).lexically_normal().string() : p;
  };
  StationFile out;
  const auto radius = root["sphere_radius_mm"].value<double>();
  if (!radius || !(*radius > 1 && *radius < 500))
    bad(file, "sphere_radius_mm", "expected a number in (1, 500) mm");
  out.radius_mm = *radius;
  const auto camera = root["camera"].value<std::string>();
  if (!camera) bad(file, "camera", "expected the path of a scene_camera.json with the sensor's intrinsics");
  out.camera = relative(*camera);
  EulerConvention euler = EulerConvention::zyx;
  if (root.contains("euler")) {
    const auto e = root["euler"].value<std::string>();
    if (!e || (*e != "ZYX" && *e != "XYZ"))
      bad(file, "euler", "expected \"ZYX\" or \"XYZ\" (as [plc] euler)");
    euler = parse_euler_convention(*e);
  }
  std::optional<Eigen::Vector3d> offset;
  if (root.contains("sphere_in_flange_mm")) {
    const auto o = numbers(file, root, "", "sphere_in_flange_mm", 3);
    offset = Eigen::Vector3d(o[0], o[1], o[2]);
  }
  for (const auto& [key, node] : root) {
    const std::string k(key.str());
    if (k != "sphere_radius_mm" && k != "camera" && k != "euler" && k != "sphere_in_flange_mm" &&
        k != "station")
      bad(file, k, "unknown key");
  }
  const toml::array* list = root["station"].as_array();
  if (!list || list->empty()) bad(file, "station", "expected [[station]] tables (at least 4)");
  for (std::size_t i = 0; i < list->size(); ++i) {
    const std::string where = "station[" + std::to_string(i + 1) + "].";
    const toml::table* t = (*list)[i].as_table();
    if (!t) bad(file, where, "expected a table");
    Station s;
    const auto depth = (*t)["depth"].value<std::string>();
    if (!depth) bad(file, where + "depth", "expected the path of the station's 16-bit depth PNG");
    s.depth = relative(*depth);
    const bool tcp = t->contains("tcp_mm"), xyz = t->contains("flange_xyz_mm"),
               m = t->contains("flange_matrix");
    if (int(tcp) + int(xyz) + int(m) != 1)
      bad(file, where + "tcp_mm",
          "give exactly one of tcp_mm, flange_xyz_mm + flange_rxyz_deg, flange_matrix");
    if (tcp) {
      const auto v = numbers(file, *t, where, "tcp_mm", 3);
      s.sphere_in_robot = {v[0], v[1], v[2]};
    } else {
      if (!offset) bad(file, "sphere_in_flange_mm", "needed when stations give flange poses");
      Pose flange = Pose::Identity();
      if (m) {
        flange = pose_from_matrix_rowmajor(numbers(file, *t, where, "flange_matrix", 16).data());
      } else {
        const auto p = numbers(file, *t, where, "flange_xyz_mm", 3);
        const auto r = numbers(file, *t, where, "flange_rxyz_deg", 3);
        flange.linear() = rotation_from_euler_deg({r[0], r[1], r[2]}, euler);
        flange.translation() = Eigen::Vector3d(p[0], p[1], p[2]);
      }
      s.sphere_in_robot = flange * *offset;
    }
    for (const auto& [key, node] : *t) {
      const std::string k(key.str());
      if (k != "depth" && k != "tcp_mm" && k != "flange_xyz_mm" && k != "flange_rxyz_deg" &&
          k != "flange_matrix")
        bad(file, where + k, "unknown key");
    }
    out.stations.push_back(s);
  }
  if (out.stations.size() < 4)
    bad(file, "station", "expected at least 4 stations, got " + std::to_string(out.stations.size()));
  return out;
}

std::string matrix_toml(const Pose& p) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  const Eigen::Matrix4d m = p.matrix();
  s << "[";
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) {
      s.precision(j == 3 ? 2 : 7);
      s << m(i, j) << ", ";
    }
    s << " ";
  }
  s << "0, 0, 0, 1]";
  return s.str();
}

}  // namespace

void add_calibrate_hand_eye(CLI::App& app) {
  struct Options {
    std::string stations;
    double outlier_factor = 3;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand(
      "calibrate-hand-eye",
      "Solve robot_from_camera from a sphere seen at 4 or more robot stations; print TOML");
  cmd->add_option("--stations", opt->stations, "TOML file listing the stations (docs/calibration.md)")
      ->required();
  cmd->add_option("--outlier-factor", opt->outlier_factor,
                  "flag stations whose residual exceeds this x the median")
      ->check(CLI::Range(1.5, 100.0));
  cmd->callback([opt] {
    const StationFile file = read_stations(opt->stations);
    const auto cameras = read_scene_camera(file.camera);
    if (cameras.empty()) throw IoError("'" + file.camera + "': holds no camera");
    const CameraInfo& cam = cameras.begin()->second;
    SphereFitParams params;
    params.radius_mm = file.radius_mm;
    std::vector<Eigen::Vector3d> in_camera, in_robot;
    std::vector<SphereFit> fits;
    for (std::size_t i = 0; i < file.stations.size(); ++i) {
      const Station& s = file.stations[i];
      const Image<float> depth = read_depth_mm(s.depth, cam.depth_scale);
      Intrinsics k = cam.intrinsics;
      k.width = depth.width, k.height = depth.height;
      const SphereFit fit = find_sphere(depth, k, params);
      if (!fit.ok) {
        spdlog::error(
            "calibrate-hand-eye: station {} '{}': no sphere of radius {} mm found ({} px on the best "
            "cap, {} expected)",
            i + 1, s.depth, file.radius_mm, fit.inliers, fit.expected_px);
        exit_status() = 2;
        return;
      }
      fits.push_back(fit);
      in_camera.push_back(fit.centre_mm);
      in_robot.push_back(s.sphere_in_robot);
    }
    const HandEyeResult he = solve_hand_eye(in_camera, in_robot, opt->outlier_factor);
    if (!he.ok) {
      spdlog::error("calibrate-hand-eye: '{}': {}", opt->stations, he.error);
      exit_status() = 2;
      return;
    }
    std::printf("# pipeloc calibrate-hand-eye: %zu stations, %d used, residual %.2f mm RMS\n",
                file.stations.size(), he.used, he.rms_mm);
    std::printf("# station  sphere in camera (mm)            px on cap  fit rms  residual\n");
    for (std::size_t i = 0; i < fits.size(); ++i)
      std::printf("# %7zu  %8.1f %8.1f %8.1f  %9d  %5.2f mm  %5.2f mm%s\n", i + 1, fits[i].centre_mm.x(),
                  fits[i].centre_mm.y(), fits[i].centre_mm.z(), fits[i].inliers, fits[i].rms_mm,
                  he.residual_mm[i],
                  he.outlier[i] ? "  OUTLIER: check this station's pendant reading and frame" : "");
    std::printf("[plc]\nrobot_from_camera = %s\n", matrix_toml(he.robot_from_camera).c_str());
    for (std::size_t i = 0; i < fits.size(); ++i)
      if (he.outlier[i])
        spdlog::warn("station {} '{}' is an outlier: residual {:.2f} mm", i + 1, file.stations[i].depth,
                     he.residual_mm[i]);
  });
}

}  // namespace pipeloc::app
