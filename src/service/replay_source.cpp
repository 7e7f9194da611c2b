#include "service/replay_source.hpp"

#include <algorithm>
#include <filesystem>

#include "io/bop.hpp"
#include "io/png.hpp"

namespace pipeloc {
namespace fs = std::filesystem;

ReplaySource::ReplaySource(const ReplaySourceConfig& cfg) : cfg_(cfg) {
  const fs::path root(cfg.path);
  if (!fs::is_directory(root)) throw SourceError("source.replay.path '" + cfg.path + "': no such folder");
  try {
    if (fs::is_directory(root / "test")) {  // BOP: scenes in order, images in order
      std::vector<fs::path> scenes;
      for (const auto& e : fs::directory_iterator(root / "test"))
        if (e.is_directory()) scenes.push_back(e.path());
      std::sort(scenes.begin(), scenes.end());
      for (const fs::path& scene : scenes) {
        const int scene_id = std::stoi(scene.filename().string());
        for (const auto& [im_id, camera] : read_scene_camera((scene / "scene_camera.json").string())) {
          if (frames_.size() >= std::size_t(cfg.max_frames)) break;
          add(depth_path(cfg.path, scene_id, im_id), (scene / "scene_camera.json").string(), im_id, camera,
              scene_id, im_id);
        }
      }
    } else {  // a folder of PNGs and one camera
      if (cfg.camera.empty())
        throw SourceError("source.replay.camera: needed for a folder of PNGs (a scene_camera.json)");
      const auto cameras = read_scene_camera(cfg.camera);
      if (cameras.empty())
        throw SourceError("source.replay.camera '" + cfg.camera + "': no camera in the file");
      std::vector<fs::path> pngs;
      for (const auto& e : fs::directory_iterator(root))
        if (e.is_regular_file() && e.path().extension() == ".png") pngs.push_back(e.path());
      std::sort(pngs.begin(), pngs.end());
      for (std::size_t i = 0; i < pngs.size() && frames_.size() < std::size_t(cfg.max_frames); ++i)
        add(pngs[i].string(), cfg.camera, cameras.begin()->first, cameras.begin()->second, 0, int(i));
    }
  } catch (const IoError& e) {
    throw SourceError(std::string("source.replay: ") + e.what());
  } catch (const std::invalid_argument&) {
    throw SourceError("source.replay.path '" + cfg.path + "': scene folders under test/ must be numbers");
  }
  if (frames_.empty()) throw SourceError("source.replay.path '" + cfg.path + "': no depth PNGs found");
}

void ReplaySource::add(const std::string& png, const std::string& camera_file, int camera_id,
                       const CameraInfo& camera, int scene_id, int im_id) {
  Stored s;
  s.camera = camera;
  s.depth_mm = read_depth_for_camera(png, camera_file, camera_id, &s.camera);
  s.scene_id = scene_id;
  s.im_id = im_id;
  if (frames_.empty())
    intrinsics_ = s.camera.intrinsics;
  else if (s.depth_mm.width != intrinsics_.width || s.depth_mm.height != intrinsics_.height)
    throw SourceError("source.replay: '" + png + "' is " + std::to_string(s.depth_mm.width) + "x" +
                      std::to_string(s.depth_mm.height) + ", the first frame " +
                      std::to_string(intrinsics_.width) + "x" + std::to_string(intrinsics_.height) +
                      ": one sensor, one size");
  frames_.push_back(std::move(s));
}

GrabStatus ReplaySource::grab(Clock::time_point, Clock::time_point, Frame* out) {
  const Stored& s = frames_[next_];
  next_ = (next_ + 1) % frames_.size();
  if (out->depth_mm.pixels.size() != s.depth_mm.pixels.size()) return GrabStatus::frame_invalid;
  std::copy(s.depth_mm.pixels.begin(), s.depth_mm.pixels.end(), out->depth_mm.pixels.begin());
  out->camera = s.camera;
  out->captured = Clock::now();
  out->sequence = ++sequence_;
  out->scene_id = s.scene_id;
  out->im_id = s.im_id;
  return GrabStatus::ok;
}

std::string ReplaySource::describe() const {
  return "replay: " + std::to_string(frames_.size()) + " frames from " + cfg_.path + ", " +
         std::to_string(intrinsics_.width) + "x" + std::to_string(intrinsics_.height) + ", looping";
}

}  // namespace pipeloc
