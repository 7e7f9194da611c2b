// The BOP dataset layout of DESIGN.md: models/, test/SSSSSS/{depth/IIIIII.png, scene_camera.json,
// scene_gt.json, scene_gt_info.json}, test_targets_bop19.json.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/image.hpp"
#include "io/json_file.hpp"

namespace pipeloc {

struct Target {
  int scene_id = 0, im_id = 0, obj_id = 0, inst_count = 0;
};

struct GtPose {
  int obj_id = 0;
  Pose model_to_cam = Pose::Identity();
};

struct GtInfo {
  int px_count_all = 0, px_count_visib = 0, px_count_valid = 0;
  double visib_fract = 0, occ_by_pipes = 0;
  bool top = false;
};

struct ModelInfo {
  std::string name;
  double tube_diameter_mm = 0, diameter_mm = 0;
  std::vector<Pose> symmetries;  // discrete, proper, other than identity
};

std::string scene_dir(const std::string& dataset, int scene_id);
std::string depth_path(const std::string& dataset, int scene_id, int im_id);
std::string model_path(const std::string& dataset, int obj_id);

std::vector<Target> read_targets(const std::string& path);
// im_id -> camera of one scene_camera.json; cam_R_w2c/cam_t_w2c optional (both or neither).
std::map<int, CameraInfo> read_scene_camera(const std::string& path);
std::map<int, std::vector<GtPose>> read_scene_gt(const std::string& path);
std::map<int, std::vector<GtInfo>> read_scene_gt_info(const std::string& path);
std::map<int, ModelInfo> read_models_info(const std::string& path);

// Depth in mm (float) from a 16-bit PNG and its depth_scale; 0 = no reading.
Image<float> read_depth_mm(const std::string& png_path, double depth_scale);

// The depth image of one camera entry (image im_id of camera_path), checked against it: the
// size the entry gives (width/height, when it does), the principal point inside the image. The
// camera gets the image's size. An IoError names both files, the image and the sizes.
Image<float> read_depth_for_camera(const std::string& png_path, const std::string& camera_path, int im_id,
                                   CameraInfo* camera);

// One target's depth image and camera (intrinsics sized to the image). Each scene's camera file
// is read once into `cameras`; a missing camera entry is an IoError naming scene and image.
struct TargetFrame {
  CameraInfo camera;
  Image<float> depth_mm;
};
TargetFrame read_target_frame(const std::string& dataset, const Target& target,
                              std::map<int, std::map<int, CameraInfo>>* cameras);

Json camera_to_json(const CameraInfo& cam);
Json pose_to_gt_json(int obj_id, const Pose& model_to_cam);
Json gt_info_to_json(const GtInfo& info);

}  // namespace pipeloc
