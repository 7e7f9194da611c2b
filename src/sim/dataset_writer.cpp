#include "sim/dataset_writer.hpp"

#include <cstdio>
#include <filesystem>

#include "io/png.hpp"
#include "model/stl.hpp"
#include "render/overlay.hpp"

namespace pipeloc {

Json model_info_json(const PipeModel& model, const std::string& name) {
  Eigen::Vector3f lo = model.mesh.vertices[0], hi = lo;
  for (const auto& v : model.mesh.vertices) lo = lo.cwiseMin(v), hi = hi.cwiseMax(v);
  Json symmetries = Json::array();
  for (const auto& s : model.symmetries) {
    const Eigen::Matrix4d m = s.matrix();
    Json row = Json::array();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) row.push_back(m(r, c));
    symmetries.push_back(row);
  }
  return {{"name", name},
          {"tube_diameter", model.tube_diameter_mm},
          {"diameter", model.extent_mm},
          {"min_x", lo.x()},
          {"min_y", lo.y()},
          {"min_z", lo.z()},
          {"size_x", hi.x() - lo.x()},
          {"size_y", hi.y() - lo.y()},
          {"size_z", hi.z() - lo.z()},
          {"symmetries_discrete", symmetries}};
}

void write_simulated_dataset(const PipeModel& model, const SimulateRequest& req) {
  namespace fs = std::filesystem;
  const std::string scene = scene_dir(req.out_dir, req.scene_id);
  std::error_code ec;
  fs::create_directories(scene + "/depth", ec);
  fs::create_directories(req.out_dir + "/models", ec);
  if (ec) throw IoError("cannot create '" + req.out_dir + "': " + ec.message());

  write_stl(model_path(req.out_dir, req.obj_id), model.mesh);
  Json models_info = {
      {std::to_string(req.obj_id), model_info_json(model, fs::path(model.source).stem().string())}};
  write_json(req.out_dir + "/models/models_info.json", models_info);

  std::mt19937 rng(req.seed);
  Json cameras = Json::object(), gts = Json::object(), infos = Json::object(), targets = Json::array();
  for (int im = 0; im < req.images; ++im) {
    const SimulatedScene s = simulate_scene(model, req.scene, rng);
    write_depth_png(depth_path(req.out_dir, req.scene_id, im),
                    to_raw_depth(s.depth_mm, s.camera.depth_scale));
    if (req.previews) {
      char name[32];
      std::snprintf(name, sizeof name, "/preview_%06d.png", im);
      write_rgb_png(scene + name, shade_depth(s.depth_mm));
    }
    const std::string key = std::to_string(im);
    cameras[key] = camera_to_json(s.camera);
    gts[key] = Json::array();
    infos[key] = Json::array();
    for (std::size_t i = 0; i < s.model_to_world.size(); ++i) {
      gts[key].push_back(pose_to_gt_json(req.obj_id, s.model_to_cam(i)));
      infos[key].push_back(gt_info_to_json(s.info[i]));
    }
    targets.push_back({{"scene_id", req.scene_id},
                       {"im_id", im},
                       {"obj_id", req.obj_id},
                       {"inst_count", int(s.model_to_world.size())}});
  }
  write_json(scene + "/scene_camera.json", cameras);
  write_json(scene + "/scene_gt.json", gts);
  write_json(scene + "/scene_gt_info.json", infos);
  write_json(req.out_dir + "/test_targets_bop19.json", targets, -1);
}

}  // namespace pipeloc
