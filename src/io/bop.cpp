#include "io/bop.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace pipeloc {
namespace {

std::string zero_pad(int value) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "%06d", value);
  return buf;
}

template <std::size_t N>
std::array<double, N> fixed_array(const Json& obj, const std::string& key, const std::string& path,
                                  const std::string& where) {
  const auto values = json_field<std::vector<double>>(obj, key, path, where, "an array of numbers");
  if (values.size() != N)
    throw IoError("'" + path + "': " + where + "." + key + ": expected " + std::to_string(N) +
                  " numbers, got " + std::to_string(values.size()));
  std::array<double, N> out{};
  for (std::size_t i = 0; i < N; ++i) {
    if (!std::isfinite(values[i]))
      throw IoError("'" + path + "': " + where + "." + key + ": non-finite value");
    out[i] = values[i];
  }
  return out;
}

int im_id_of(const std::string& key, const std::string& path) {
  try {
    std::size_t used = 0;
    const int id = std::stoi(key, &used);
    if (used == key.size() && id >= 0) return id;
  } catch (const std::exception&) {
  }
  throw IoError("'" + path + "': key '" + key + "' is not an image id");
}

void require_array(const Json& list, const std::string& path, const std::string& key) {
  if (!list.is_array()) throw IoError("'" + path + "': \"" + key + "\": expected an array");
}

// Why 9 row-major values are not a rotation ("" when they are): rows orthonormal and determinant
// +1, each to 1e-3 (a matrix typed with 4 decimals passes; a typo, a scale or a transpose
// mistake for a mirror do not).
std::string rotation_problem(const std::array<double, 9>& r) {
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) {
      const double dot = r[3 * i] * r[3 * j] + r[3 * i + 1] * r[3 * j + 1] + r[3 * i + 2] * r[3 * j + 2];
      if (std::abs(dot - (i == j ? 1.0 : 0.0)) > 1e-3) {
        char s[96];
        std::snprintf(s, sizeof s, "rows not orthonormal (row %d . row %d = %.6g, expected %d)", i + 1, j + 1,
                      dot, i == j ? 1 : 0);
        return s;
      }
    }
  const double det = r[0] * (r[4] * r[8] - r[5] * r[7]) - r[1] * (r[3] * r[8] - r[5] * r[6]) +
                     r[2] * (r[3] * r[7] - r[4] * r[6]);
  if (det < 0) return "determinant -1 (a reflection)";
  return "";
}

Json require_object(const std::string& path) {
  Json root = read_json(path);
  if (!root.is_object()) throw IoError("'" + path + "': expected a JSON object keyed by image id");
  return root;
}

}  // namespace

std::string scene_dir(const std::string& dataset, int scene_id) {
  return dataset + "/test/" + zero_pad(scene_id);
}
std::string depth_path(const std::string& dataset, int scene_id, int im_id) {
  return scene_dir(dataset, scene_id) + "/depth/" + zero_pad(im_id) + ".png";
}
std::string model_path(const std::string& dataset, int obj_id) {
  return dataset + "/models/obj_" + zero_pad(obj_id) + ".stl";
}

std::vector<Target> read_targets(const std::string& path) {
  const Json root = read_json(path);
  if (!root.is_array()) throw IoError("'" + path + "': expected an array of targets");
  std::vector<Target> out;
  for (std::size_t i = 0; i < root.size(); ++i) {
    const std::string where = "[" + std::to_string(i) + "]";
    Target t;
    t.scene_id = json_field<int>(root[i], "scene_id", path, where, "an integer");
    t.im_id = json_field<int>(root[i], "im_id", path, where, "an integer");
    t.obj_id = json_field<int>(root[i], "obj_id", path, where, "an integer");
    t.inst_count = root[i].contains("inst_count")
                       ? json_field<int>(root[i], "inst_count", path, where, "an integer")
                       : 0;
    out.push_back(t);
  }
  return out;
}

std::map<int, CameraInfo> read_scene_camera(const std::string& path) {
  const Json root = require_object(path);
  std::map<int, CameraInfo> out;
  for (const auto& [key, value] : root.items()) {
    const int id = im_id_of(key, path);
    const std::string where = "\"" + key + "\"";
    CameraInfo cam;
    const auto k = fixed_array<9>(value, "cam_K", path, where);
    cam.intrinsics.fx = k[0];
    cam.intrinsics.cx = k[2];
    cam.intrinsics.fy = k[4];
    cam.intrinsics.cy = k[5];
    if (!(k[0] > 0 && k[4] > 0))
      throw IoError("'" + path + "': " + where + ".cam_K: focal lengths must be > 0");
    if (value.contains("width") != value.contains("height"))
      throw IoError("'" + path + "': " + where + ": width and height come together");
    if (value.contains("width")) {
      cam.intrinsics.width = json_field<int>(value, "width", path, where, "an integer");
      cam.intrinsics.height = json_field<int>(value, "height", path, where, "an integer");
      if (!(cam.intrinsics.width > 0 && cam.intrinsics.height > 0 && cam.intrinsics.width <= 100000 &&
            cam.intrinsics.height <= 100000))
        throw IoError("'" + path + "': " + where + ".width/height: expected sizes in [1, 100000] px");
      cam.size_given = true;
    }
    cam.depth_scale = json_field<double>(value, "depth_scale", path, where, "a number");
    if (!(cam.depth_scale > 0))
      throw IoError("'" + path + "': " + where + ".depth_scale: expected a number > 0");
    const bool has_r = value.contains("cam_R_w2c"), has_t = value.contains("cam_t_w2c");
    if (has_r != has_t) throw IoError("'" + path + "': " + where + ": cam_R_w2c and cam_t_w2c come together");
    if (has_r) {
      const auto r = fixed_array<9>(value, "cam_R_w2c", path, where);
      if (const std::string why = rotation_problem(r); !why.empty())
        throw IoError("'" + path + "': image " + key + ": cam_R_w2c: expected a rotation matrix: " + why);
      cam.world_to_cam = pose_from_rt(r, fixed_array<3>(value, "cam_t_w2c", path, where));
    }
    out[id] = cam;
  }
  return out;
}

std::map<int, std::vector<GtPose>> read_scene_gt(const std::string& path) {
  const Json root = require_object(path);
  std::map<int, std::vector<GtPose>> out;
  for (const auto& [key, list] : root.items()) {
    const int id = im_id_of(key, path);
    require_array(list, path, key);
    auto& poses = out[id];
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string where = "\"" + key + "\"[" + std::to_string(i) + "]";
      GtPose gt;
      gt.obj_id = json_field<int>(list[i], "obj_id", path, where, "an integer");
      gt.model_to_cam = pose_from_rt(fixed_array<9>(list[i], "cam_R_m2c", path, where),
                                     fixed_array<3>(list[i], "cam_t_m2c", path, where));
      poses.push_back(gt);
    }
  }
  return out;
}

std::map<int, std::vector<GtInfo>> read_scene_gt_info(const std::string& path) {
  const Json root = require_object(path);
  std::map<int, std::vector<GtInfo>> out;
  for (const auto& [key, list] : root.items()) {
    const int id = im_id_of(key, path);
    require_array(list, path, key);
    auto& infos = out[id];
    for (std::size_t i = 0; i < list.size(); ++i) {
      const std::string where = "\"" + key + "\"[" + std::to_string(i) + "]";
      GtInfo g;
      g.px_count_all = json_field<int>(list[i], "px_count_all", path, where, "an integer");
      g.px_count_visib = json_field<int>(list[i], "px_count_visib", path, where, "an integer");
      g.px_count_valid = json_field<int>(list[i], "px_count_valid", path, where, "an integer");
      g.visib_fract = json_field<double>(list[i], "visib_fract", path, where, "a number");
      g.occ_by_pipes = json_field<double>(list[i], "occ_by_pipes", path, where, "a number");
      g.top = json_field<bool>(list[i], "top", path, where, "true or false");
      infos.push_back(g);
    }
  }
  return out;
}

std::map<int, ModelInfo> read_models_info(const std::string& path) {
  const Json root = require_object(path);
  std::map<int, ModelInfo> out;
  for (const auto& [key, value] : root.items()) {
    const int id = im_id_of(key, path);
    const std::string where = "\"" + key + "\"";
    ModelInfo info;
    if (value.contains("name")) info.name = json_field<std::string>(value, "name", path, where, "a string");
    if (value.contains("tube_diameter"))
      info.tube_diameter_mm = json_field<double>(value, "tube_diameter", path, where, "a number");
    info.diameter_mm = json_field<double>(value, "diameter", path, where, "a number");
    if (value.contains("symmetries_discrete")) {
      const auto& list = value.at("symmetries_discrete");
      require_array(list, path, key + ".symmetries_discrete");
      for (std::size_t i = 0; i < list.size(); ++i) {
        const std::string w = where + ".symmetries_discrete[" + std::to_string(i) + "]";
        if (!list[i].is_array() || list[i].size() != 16 ||
            !std::all_of(list[i].begin(), list[i].end(), [](const Json& x) { return x.is_number(); }))
          throw IoError("'" + path + "': " + w + ": expected 16 numbers (4x4)");
        const auto m = list[i].get<std::vector<double>>();
        if (m.size() != 16) throw IoError("'" + path + "': " + w + ": expected 16 numbers (4x4)");
        info.symmetries.push_back(
            pose_from_rt({m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]}, {m[3], m[7], m[11]}));
      }
    }
    out[id] = info;
  }
  return out;
}

Image<float> read_depth_mm(const std::string& png_path, double depth_scale) {
  const Image<std::uint16_t> raw = read_depth_png(png_path);
  Image<float> depth(raw.width, raw.height);
  for (std::size_t i = 0; i < raw.pixels.size(); ++i) depth.pixels[i] = float(raw.pixels[i] * depth_scale);
  return depth;
}

Image<float> read_depth_for_camera(const std::string& png_path, const std::string& camera_path, int im_id,
                                   CameraInfo* camera) {
  Image<float> depth = read_depth_mm(png_path, camera->depth_scale);
  Intrinsics& k = camera->intrinsics;
  const auto size = [](int w, int h) { return std::to_string(w) + "x" + std::to_string(h); };
  if (camera->size_given && (depth.width != k.width || depth.height != k.height))
    throw IoError("depth '" + png_path + "' is " + size(depth.width, depth.height) + " px but its camera ('" +
                  camera_path + "', image " + std::to_string(im_id) + ") is for " + size(k.width, k.height) +
                  " px images: intrinsics of another image or resolution");
  if (!(k.cx >= 0 && k.cx <= depth.width && k.cy >= 0 && k.cy <= depth.height))
    throw IoError("depth '" + png_path + "' is " + size(depth.width, depth.height) + " px but its camera ('" +
                  camera_path + "', image " + std::to_string(im_id) + ") has its principal point at (" +
                  std::to_string(k.cx) + ", " + std::to_string(k.cy) +
                  "), outside the image: intrinsics of another resolution");
  k.width = depth.width;
  k.height = depth.height;
  return depth;
}

TargetFrame read_target_frame(const std::string& dataset, const Target& t,
                              std::map<int, std::map<int, CameraInfo>>* cameras) {
  if (!cameras->count(t.scene_id))
    (*cameras)[t.scene_id] = read_scene_camera(scene_dir(dataset, t.scene_id) + "/scene_camera.json");
  const auto& scene = (*cameras)[t.scene_id];
  const auto cam = scene.find(t.im_id);
  if (cam == scene.end())
    throw IoError("scene " + std::to_string(t.scene_id) + ": no camera for image " + std::to_string(t.im_id));
  TargetFrame frame{cam->second, {}};
  frame.depth_mm =
      read_depth_for_camera(depth_path(dataset, t.scene_id, t.im_id),
                            scene_dir(dataset, t.scene_id) + "/scene_camera.json", t.im_id, &frame.camera);
  return frame;
}

Json camera_to_json(const CameraInfo& cam) {
  const auto& k = cam.intrinsics;
  Json j = {{"cam_K", {k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0}},
            {"depth_scale", cam.depth_scale},
            {"width", k.width},
            {"height", k.height}};
  if (cam.world_to_cam) {
    j["cam_R_w2c"] = rotation_rowmajor(*cam.world_to_cam);
    j["cam_t_w2c"] = translation_mm(*cam.world_to_cam);
  }
  return j;
}

Json pose_to_gt_json(int obj_id, const Pose& model_to_cam) {
  return {{"obj_id", obj_id},
          {"cam_R_m2c", rotation_rowmajor(model_to_cam)},
          {"cam_t_m2c", translation_mm(model_to_cam)}};
}

Json gt_info_to_json(const GtInfo& g) {
  return {{"px_count_all", g.px_count_all},     {"px_count_visib", g.px_count_visib},
          {"px_count_valid", g.px_count_valid}, {"visib_fract", g.visib_fract},
          {"occ_by_pipes", g.occ_by_pipes},     {"top", g.top}};
}

}  // namespace pipeloc
