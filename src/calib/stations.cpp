#include "calib/stations.hpp"

#include <toml++/toml.h>

#include <cmath>
#include <filesystem>
#include <optional>

#include "config/config_file.hpp"
#include "plc/robot_pose.hpp"

namespace pipeloc {
namespace {

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

}  // namespace

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

}  // namespace pipeloc
