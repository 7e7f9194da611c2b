// The station file of calibrate-hand-eye (TOML; docs/calibration.md): the sphere's radius, the
// camera's intrinsics, and per station a depth frame and where the sphere's centre was in the
// robot frame: read off the pendant with the tool-centre point set to the sphere's centre
// (tcp_mm), or the flange pose (flange_xyz_mm + flange_rxyz_deg in `euler`, or flange_matrix)
// with the sphere's offset in the flange frame (sphere_in_flange_mm).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace pipeloc {

struct Station {
  std::string depth;                // path of the 16-bit depth PNG
  Eigen::Vector3d sphere_in_robot;  // mm
};

struct StationFile {
  double radius_mm = 0;
  std::string camera;  // scene_camera.json
  std::vector<Station> stations;
};

// Paths relative to the file. Throws ConfigError naming the file, the key and what was expected.
StationFile read_stations(const std::string& path);

}  // namespace pipeloc
