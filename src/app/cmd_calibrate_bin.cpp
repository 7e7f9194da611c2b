// pipeloc calibrate-bin: the bin frame (world_to_cam) and the bin interior (region of interest)
// from one depth frame of the bin, printed as TOML to paste into the config.
#include <spdlog/spdlog.h>

#include <cmath>
#include <iostream>
#include <memory>

#include "app/commands.hpp"
#include "calib/bin_frame.hpp"
#include "io/bop.hpp"
#include "io/png.hpp"

namespace pipeloc::app {

void add_calibrate_bin(CLI::App& app) {
  struct Options {
    std::string depth, camera;
    int im_id = -1;
    double margin_mm = 5;
    bool floor_only = false;
  };
  auto opt = std::make_shared<Options>();
  auto* cmd = app.add_subcommand("calibrate-bin",
                                 "Fit the bin's floor and walls in one depth frame; print world_to_cam and "
                                 "the region of interest as TOML");
  cmd->add_option("--depth", opt->depth, "16-bit depth PNG of the bin (empty, or with pipes)")->required();
  cmd->add_option("--camera", opt->camera, "scene_camera.json (BOP) with this image's intrinsics")
      ->required();
  cmd->add_option("--im-id", opt->im_id, "image id in the camera file (default: its first entry)");
  cmd->add_option("--margin-mm", opt->margin_mm, "region of interest this far inside the walls (mm)")
      ->check(CLI::Range(0.0, 200.0));
  cmd->add_flag("--floor-only", opt->floor_only,
                "the floor's frame alone, walls not looked for (a camera that sees part of the bin); no "
                "region of interest");
  cmd->callback([opt] {
    const auto cameras = read_scene_camera(opt->camera);
    if (cameras.empty()) throw IoError("'" + opt->camera + "': holds no camera");
    const auto it = opt->im_id < 0 ? cameras.begin() : cameras.find(opt->im_id);
    if (it == cameras.end())
      throw IoError("'" + opt->camera + "': no entry for image " + std::to_string(opt->im_id));
    CameraInfo cam = it->second;
    const Image<float> depth = read_depth_for_camera(opt->depth, opt->camera, it->first, &cam);
    const Intrinsics k = cam.intrinsics;
    BinCalibParams params;
    params.roi_margin_mm = opt->margin_mm;
    params.floor_only = opt->floor_only;
    const BinCalib calib = calibrate_bin(depth, k, params);
    if (!calib.ok) {
      spdlog::error("calibrate-bin: '{}': {}", opt->depth, calib.error);
      exit_status() = 2;
      return;
    }
    std::cout << bin_calib_toml(calib);
    // For a replayed dataset the same frame goes into scene_camera.json.
    const Pose& w = calib.world_to_cam;
    std::cout.precision(7);
    std::cout << "# scene_camera.json (replay): \"cam_R_w2c\": [";
    for (int i = 0; i < 9; ++i) std::cout << (i ? ", " : "") << w.linear()(i / 3, i % 3);
    std::cout << "], \"cam_t_w2c\": [" << w.translation().x() << ", " << w.translation().y() << ", "
              << w.translation().z() << "]\n";
    if (it->second.world_to_cam) {  // the file's own bin frame (simulated data): how far from it
      const Pose& given = *it->second.world_to_cam;
      const double normal_deg =
          std::acos(std::clamp(given.linear().col(2).dot(w.linear().col(2)), -1.0, 1.0)) * 180 / M_PI;
      const Eigen::Vector3d origin_in_given = given.inverse() * w.translation();
      const Eigen::Vector3d x_in_given = given.linear().transpose() * w.linear().col(0);
      spdlog::info(
          "the camera file's own world frame: floor normal {:.3f} deg apart; this origin at ({:.1f}, {:.1f}, "
          "{:.1f}) mm in it, this X turned {:.2f} deg about its Z",
          normal_deg, origin_in_given.x(), origin_in_given.y(), origin_in_given.z(),
          std::atan2(x_in_given.y(), x_in_given.x()) * 180 / M_PI);
    }
  });
}

}  // namespace pipeloc::app
